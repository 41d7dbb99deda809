"""Commands on files: ``check`` a schedule, ``show`` an instance, ``list`` the bundled ones."""
from __future__ import annotations

import click
import numpy as np

from bille.instances import InstanceError, check_instance, load_instance
from bille.instances.bundled import SCHEDULE_SUFFIX, bundled_names, bundled_path
from bille.solvers import validate

from .common import (EXIT_NO, EXIT_OK, instance_arg, label_of, print_json, record_traces, robots, schedule_for, trace_of,
                     writable)
from .render import describe, draw


@click.command()
@click.argument("instance")
@click.argument("schedule")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Also write a rerun recording; a violation is marked at its step.")
@click.option("--poses", "poses_path", type=click.Path(dir_okay=False), metavar="OUT.csv|OUT.json",
              help="Also write every robot's feet, heading, load, action and the cells it picks or places, "
                   "per step (up to a violation).")
def check(instance: str, schedule: str, as_json: bool, rrd: str | None, poses_path: str | None) -> int:
    """Check SCHEDULE against the rules for INSTANCE (exit 0 valid, 1 invalid, 2 bad input)."""
    if poses_path and not poses_path.endswith((".csv", ".json")):
        raise click.BadParameter(f"{poses_path}: expected a .csv or .json file name", param_hint="--poses")
    writable(rrd, poses_path)
    inst = instance_arg(instance)
    sched = schedule_for(schedule, inst)
    report = validate(inst, sched)
    if rrd:
        record_traces([trace_of(inst, sched, label_of(schedule))], rrd, quiet=as_json)
    if poses_path:
        write_poses(trace_of(inst, sched, label_of(schedule)), poses_path)
    if as_json:
        print_json(report.to_json())
    elif report.valid:
        m = report.metrics
        click.echo(f"valid: makespan {m.makespan}, tiles traveled {m.tiles_traveled}, "
                   f"waits {m.waits}, picks {m.picks}, places {m.places}")
    else:
        v = report.violation
        robot = "" if v.robot is None else f", robot {v.robot}"
        click.echo(f"invalid: step {v.step}{robot}, rule {v.rule}: {v.message}")
    return EXIT_OK if report.valid else EXIT_NO


@click.command()
@click.argument("instance")
def show(instance: str) -> int:
    """Draw INSTANCE (robots as letters: front foot upper case, back foot lower case, '*' a
    carried tile) with its sizes, movesets and validity (exit 1 if invalid)."""
    inst = instance_arg(instance, check=False)
    try:
        check_instance(inst)
        validity, code = "valid", EXIT_OK
    except InstanceError as exc:
        validity, code = f"INVALID: {exc}", EXIT_NO
    start_tiles, goal_tiles = int(inst.start.tiles.sum()), int(inst.goal_grid.tiles.sum())
    moved = int((inst.start.tiles != inst.goal_grid.tiles).sum())
    kind = "reconfiguration" if inst.is_reconfiguration else "path planning"
    click.echo(f"{inst.name}: {inst.width}x{inst.height} grid, moveset {inst.moveset.name}, "
               f"{robots(inst.num_robots)}, {kind}")
    click.echo(f"tiles: {start_tiles} at start, {goal_tiles} in the goal, {moved} cells differ; "
               f"tasks: {len(inst.tasks) if inst.tasks is not None else 'none'}")
    click.echo(f"instance: {validity}")
    for line in draw(inst) + ["robots:"] + describe(inst):
        click.echo(line)
    return code


POSE_FIELDS = ["step", "robot", "front_x", "front_y", "back_x", "back_y", "heading", "carrying", "action", "picked",
               "placed"]


def pose_rows(tr) -> list[dict]:
    """Per frame and robot: feet, heading (N, E, S, W; none for a point robot), load, the action
    that led there, and the cell it picked or placed in that step."""
    from bille.instances.grid import HEADING_NAMES, HEADING_VECTORS

    heading_of = dict(zip(HEADING_VECTORS, HEADING_NAMES))
    inst, rows = tr.instance, []
    for t in range(tr.steps + 1):
        for i in range(inst.num_robots):
            (fx, fy), (bx, by) = tr.front[t, i].tolist(), tr.back[t, i].tolist()
            action = tr.actions[t][i] if t else None
            picked = placed = None
            if t and tr.carrying[t, i] != tr.carrying[t - 1, i]:
                mine = {(int(x), int(y)) for x, y in tr.swept[t][i]}
                cell = next(([c % inst.width, c // inst.width] for c in
                             np.flatnonzero(tr.tiles[t] != tr.tiles[t - 1]).tolist()
                             if (c % inst.width, c // inst.width) in mine), None)
                picked, placed = (cell, None) if tr.carrying[t, i] else (None, cell)
            rows.append(dict(step=t, robot=i, front_x=fx, front_y=fy, back_x=bx, back_y=by,
                             heading=heading_of.get((fx - bx, fy - by)), carrying=bool(tr.carrying[t, i]),
                             action=action, picked=picked, placed=placed))
    return rows


def write_poses(tr, path: str) -> None:
    import csv
    import io
    import json

    from bille.instances import BilleError
    from bille.instances.files import write_atomic

    rows = pose_rows(tr)
    if path.endswith(".json"):
        text = json.dumps({"instance": tr.instance.name, "fields": POSE_FIELDS, "rows": rows}, indent=None)
    else:
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=POSE_FIELDS)
        writer.writeheader()
        for r in rows:
            writer.writerow({k: ("" if v is None else " ".join(map(str, v)) if isinstance(v, list) else v)
                             for k, v in r.items()})
        text = buf.getvalue()
    write_atomic(path, text, BilleError)


@click.command("list")
@click.option("--maps", is_flag=True, help="List the MovingAI maps shipped for bille gen movingai instead.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (instances, maps).")
def list_(maps: bool, as_json: bool) -> int:
    """List the bundled instances, each with the name of its bundled schedule (a known valid one,
    usable wherever a schedule file is: bille check corridor-2 corridor-2.schedule); with --maps,
    the MovingAI maps shipped (bille gen movingai NAME -k AGENTS)."""
    from .bench.maps import shipped_maps

    folder = shipped_maps()
    if as_json:
        instances = []
        for name in bundled_names():
            inst = load_instance(bundled_path(name))
            instances.append({"name": name, "width": inst.width, "height": inst.height, "robots": inst.num_robots,
                              "moveset": inst.moveset.name, "reconfiguration": bool(inst.is_reconfiguration),
                              "schedule": f"{name}{SCHEDULE_SUFFIX}"})
        print_json({"instances": instances, "maps": sorted(p.stem for p in folder.glob("*.map"))})
        return EXIT_OK
    if maps:
        for path in sorted(folder.glob("*.map")):
            scens = sorted(p.name for p in folder.glob(f"{path.stem}-*.scen"))
            click.echo(f"{path.stem:<24} scenarios: {', '.join(scens) or 'none'}")
        return EXIT_OK
    for name in bundled_names():
        inst = load_instance(bundled_path(name))
        kind = "reconfiguration" if inst.is_reconfiguration else "path planning"
        click.echo(f"{name:<16} {inst.width}x{inst.height}, {robots(inst.num_robots)}, moveset {inst.moveset.name}, "
                   f"{kind}; schedule {name}{SCHEDULE_SUFFIX}")
    click.echo("MovingAI maps for bille gen movingai: bille list --maps")
    return EXIT_OK
