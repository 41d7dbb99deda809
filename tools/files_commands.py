"""Commands on files: ``check`` a schedule, ``show`` an instance, ``list`` the bundled ones."""
from __future__ import annotations

import click

from bille.instances import InstanceError, check_instance, load_instance
from bille.instances.bundled import SCHEDULE_SUFFIX, bundled_names, bundled_path
from bille.solvers import validate

from .common import (EXIT_NO, EXIT_OK, instance_arg, label_of, print_json, record_traces, robots, schedule_arg, trace_of,
                     writable)
from .render import describe, draw


@click.command()
@click.argument("instance")
@click.argument("schedule")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Also write a rerun recording; a violation is marked at its step.")
def check(instance: str, schedule: str, as_json: bool, rrd: str | None) -> int:
    """Check SCHEDULE against the rules for INSTANCE (exit 0 valid, 1 invalid, 2 bad input)."""
    writable(rrd)
    inst = instance_arg(instance)
    sched = schedule_arg(schedule)
    report = validate(inst, sched)
    if rrd:
        record_traces([trace_of(inst, sched, label_of(schedule))], rrd, quiet=as_json)
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


@click.command("list")
def list_() -> int:
    """List the bundled instances, each with the name of its bundled schedule (a known valid one,
    usable wherever a schedule file is: bille check corridor-2 corridor-2.schedule)."""
    for name in bundled_names():
        inst = load_instance(bundled_path(name))
        kind = "reconfiguration" if inst.is_reconfiguration else "path planning"
        click.echo(f"{name:<16} {inst.width}x{inst.height}, {robots(inst.num_robots)}, moveset {inst.moveset.name}, "
                   f"{kind}; schedule {name}{SCHEDULE_SUFFIX}")
    return EXIT_OK
