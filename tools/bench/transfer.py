"""``bille bench load-transfer``: the paper's load-transfer experiment (Results, "Load transfer").

Each map runs twice with the reconfiguration loop and Temporal A* (epsilon 1, ``H`` 10 by
default): without load transfer (the baseline of the same run) and with it (``d_tr`` 5), as the
sweep file ``load-transfer.yaml`` shipped with bille, through the sweep engine. The
table gives the percentage decrease in time steps (makespan) and tiles traveled, as in the
paper's bar plot, which is drawn to a PNG. With ``--random N`` it also runs random
reconfiguration instances (10 to 50 tiles moved, 2 to 10 robots): success rate and mean makespan
with and without load transfer, and, with ``--exact-limit``, the gap to CP-SAT's optimum on the
instances CP-SAT proves within that time.
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from bille.instances import BilleError, Instance
from bille.instances.counters import Counters
from bille.solvers import solve

from ..common import solved
from ..tables import text_table

FIELDS = ("map", "robots", "tasks", "status_off", "steps_off", "traveled_off", "time_off", "status_on", "steps_on",
          "traveled_on", "time_on", "relays", "swaps", "steps_decrease", "traveled_decrease")
SIZES = ((10, 2), (20, 4), (30, 6), (50, 10))  # (tiles moved, robots) of the random instances


def _run(inst: Instance, transfer: bool, horizon: int, d_tr: int, time_limit: float,
         motion: str = "temporal-astar"):
    if motion == "lacam":
        return solved(solve(inst, "lacam", load_transfer=transfer, d_tr=d_tr, time_limit=time_limit))
    return solved(solve(inst, "temporal-astar", epsilon=1.0, horizon=horizon, load_transfer=transfer, d_tr=d_tr,
                        time_limit=time_limit))


def decrease(before: int | None, after: int | None) -> float | None:
    """Percentage decrease from ``before`` to ``after`` (None when either is missing).

    >>> decrease(80, 60)
    25.0
    """
    if before is None or after is None or before == 0:
        return None
    return round(100.0 * (before - after) / before, 1)


SWEEP_FILE = Path(__file__).resolve().parent.parent / "sweep" / "files" / "load-transfer.yaml"


def run_maps(instances: list[Instance], horizon: int, d_tr: int, time_limit: float, jobs: int = 1,
             files: list[str] | None = None) -> list[dict]:
    """The maps as the sweep file ``load-transfer.yaml`` (shipped with bille) runs them, through
    the sweep engine, with ``horizon``, ``d_tr`` and ``time_limit`` in place of the file's (the
    maps ``files``: names or paths, one per instance)."""
    import tempfile

    import yaml

    from ..sweep.commands import run_spec
    from ..sweep.spec import parse_spec

    data = yaml.safe_load(SWEEP_FILE.read_text(encoding="utf-8"))
    data["instances"] = [str(Path(f).resolve()) if Path(f).exists() else f
                         for f in (files or [inst.name for inst in instances])]
    data["methods"]["temporal-astar"].update(horizon=horizon, d_tr=d_tr)
    data["time_limit"] = time_limit
    spec = parse_spec(data, SWEEP_FILE)
    with tempfile.TemporaryDirectory() as tmp:
        _, found = run_spec(spec, Path(tmp) / "load-transfer", jobs=jobs, quiet=True)
    by = {(r["instance_hash"], json.loads(r["options"])["load_transfer"]): r for r in found}
    rows = []
    for run in spec.runs[::2]:
        off, on = by[run.instance_hash, False], by[run.instance_hash, True]
        counts = Counters.of(json.loads(on["stats"] or "{}"))
        inst = instances[len(rows)]
        row = {"map": inst.name, "robots": on["robots"], "tasks": counts.jobs,
               "relays": counts.relays or 0, "swaps": counts.swaps or 0}
        for tag, res in (("off", off), ("on", on)):
            failure = json.loads(res["stats"] or "{}").get("failure")
            row[f"status_{tag}"] = res["status"] if res["schedule"] else (failure or res["error"] or res["status"])
            row[f"steps_{tag}"] = res["makespan"]
            row[f"traveled_{tag}"] = res["tiles_traveled"]
            row[f"time_{tag}"] = None if res["time_s"] is None else round(res["time_s"], 3)
        row["steps_decrease"] = decrease(row["steps_off"], row["steps_on"])
        row["traveled_decrease"] = decrease(row["traveled_off"], row["traveled_on"])
        rows.append(row)
    return rows


def _cell(v) -> str:
    return "N/A" if v is None else str(v)


def table(rows: list[dict]) -> list[str]:
    columns = ["map", "robots", "tasks", "steps off", "on", "dec%", "traveled off", "on ", "dec% ", "relays",
               "swaps", "plan s off/on"]
    out = ["load transfer: Temporal A* without (baseline) and with load transfer; decrease in percent"]
    out += text_table(columns, [[r["map"], r["robots"], _cell(r["tasks"]), _cell(r["steps_off"]), _cell(r["steps_on"]),
                                 _cell(r["steps_decrease"]), _cell(r["traveled_off"]), _cell(r["traveled_on"]),
                                 _cell(r["traveled_decrease"]), r["relays"], r["swaps"],
                                 f"{r['time_off']}/{r['time_on']}"] for r in rows],
                      right=set(columns) - {"map", "plan s off/on"})
    for r in rows:
        for tag in ("off", "on"):
            if r[f"steps_{tag}"] is None:
                out.append(f"  {r['map']} with load transfer {tag}: no schedule ({r[f'status_{tag}']})")
    both = [r for r in rows if r["steps_decrease"] is not None]
    if both:
        out.append(f"mean decrease over the {len(both)} maps solved both ways: time steps "
                   f"{np.mean([r['steps_decrease'] for r in both]):.1f} %, tiles traveled "
                   f"{np.mean([r['traveled_decrease'] for r in both]):.1f} %")
    return out


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)


def plot(rows: list[dict], path: Path) -> None:
    """Bars of the percentage decrease in time steps and tiles traveled per map (the paper's
    plot); a map solved only one way is marked with its status."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(max(6, 0.9 * len(rows) + 2), 3.6))
    for k, (key, name, color) in enumerate((("steps_decrease", "time steps", "#3b75af"),
                                           ("traveled_decrease", "tiles traveled", "#ef8636"))):
        vals = [r[key] if r[key] is not None else 0.0 for r in rows]
        ax.bar(x + (k - 0.5) * 0.38, vals, 0.38, label=name, color=color)
    for i, r in enumerate(rows):
        if r["steps_decrease"] is None:
            ax.text(i, 0, "off: N/A" if r["steps_off"] is None else "on: N/A", ha="center", va="bottom",
                    fontsize=7, rotation=90)
    ax.axhline(0, color="black", linewidth=0.8)
    ax.set_xticks(x, [r["map"] for r in rows])
    ax.set_ylabel("decrease with load transfer [%]")
    ax.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    try:
        fig.savefig(path, dpi=130)
    except OSError as exc:
        raise BilleError(f"{path}: cannot write the plot ({exc.strerror})") from None
    finally:
        plt.close(fig)


def random_report(runs: int, horizon: int, d_tr: int, time_limit: float, exact_limit: float,
                  motion: str = "temporal-astar"):
    """Success rate and mean makespan with and without load transfer on random instances, and
    the gap to the optimum where CP-SAT proves one within ``exact_limit`` seconds: yields the
    lines of a table, one per size as soon as it is measured."""
    from dataclasses import replace

    from bille.heuristics.loop.sequence import NoSequence, sequence_of
    from bille.instances import Task
    from bille.instances.generators.random import random_reconfiguration

    method = f"Temporal A*, H {horizon}" if motion == "temporal-astar" else "lacam (LaCAM* motion layer)"
    yield f"random reconfiguration instances ({runs} per size; S7; {method}, d_tr {d_tr})"
    yield ("(a derived sequence; where the derivation gives up, the generator's own moves as tasks, "
           "counted under 'tasks')")
    yield (f"{'moved':>5} {'robots':>6} | {'solved off':>10} {'on':>4} | {'mean steps off':>14} {'on':>6} | "
           f"{'optimal':>7} {'gap% off':>8} {'on':>6} | {'tasks':>5}")
    for moved, robots in SIZES:
        tiles = 6 * moved  # a structure dense enough for bipeds to turn: 60 tiles on 14x14 for 10 moved
        side = max(14, int(np.ceil(np.sqrt(3.3 * tiles))))
        steps = {False: [], True: []}  # the makespans of the schedules found, without and with
        gaps = {False: [], True: []}
        optimal = given = 0
        for seed in range(runs):
            inst = random_reconfiguration(side, side, tiles, robots, moved, seed=seed)
            try:  # derived once, and given to both runs as the instance's tasks
                w = inst.width
                jobs = sequence_of(inst)
                inst = replace(inst, tasks=tuple(Task((j.pick % w, j.pick // w), (j.place % w, j.place // w))
                                                 for j in jobs))
            except NoSequence:  # the same instance with the moves that made its goal
                inst = random_reconfiguration(side, side, tiles, robots, moved, seed=seed, tasks=True)
                given += 1
            results = {}
            for transfer in (False, True):
                results[transfer] = res = _run(inst, transfer, horizon, d_tr, time_limit, motion)
                if res.metrics is not None:
                    steps[transfer].append(res.metrics.makespan)
            if exact_limit > 0:
                exact = solved(solve(inst, "cpsat", time_limit=exact_limit))
                if exact.status == "optimal":
                    optimal += 1
                    for transfer, res in results.items():
                        if res.metrics is not None:
                            gaps[transfer].append(100.0 * (res.metrics.makespan - exact.metrics.makespan)
                                                  / max(1, exact.metrics.makespan))

        def mean(v):
            return f"{np.mean(v):.1f}" if v else "N/A"

        yield (f"{moved:>5} {robots:>6} | {len(steps[False]):>7}/{runs:<2} {len(steps[True]):>2}/{runs:<2}| "
               f"{mean(steps[False]):>14} {mean(steps[True]):>6} | {optimal:>7} {mean(gaps[False]):>8} "
               f"{mean(gaps[True]):>6} | {given:>5}")
