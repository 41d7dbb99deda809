"""The paper's planner comparison (Results, "Planner comparison": Fig. CompMaps and Table I).

Five crowded maps with 2 to 6 robots (bundled ``compare-2`` ... ``compare-6``), movesets S5 and
S7, joint A* and M* with epsilon in {1, 2, 3}, Temporal A* with epsilon in {1, 2, 3} and H in
{2, 5, 8}, LaCAM* (first schedule, and after 1 s): the sweep file ``planners.yaml`` shipped with
bille, run by the sweep engine (:mod:`bille.tools.sweep`): every run gets the same time limit,
runs in its own process, and its schedule is validated. Results go to a CSV file, tables like Table I (time steps, tiles traveled, planning
time; "gave up" or "out of time" when unsolved) and a log-scale plot of planning time like the figure.

Also: Temporal A* with many robots on a large structure (mean replanning time per step).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import random
import time
from pathlib import Path

import numpy as np

from bille.instances.counters import Counters

from ..tables import text_table

MAPS = [f"compare-{m}" for m in range(2, 7)]
MOVESETS = ("S5", "S7")
FIELDS = ["map", "robots", "moveset", "method", "epsilon", "horizon", "improve", "status", "solved", "makespan",
          "tiles_traveled", "sum_of_costs", "time_s"]
SWEEP_FILE = Path(__file__).resolve().parent.parent / "sweep" / "files" / "planners.yaml"


def run_grid(time_limit: float, jobs: int, maps=MAPS, movesets=MOVESETS, progress=True, folder=None) -> list[dict]:
    """The comparison as the sweep file ``planners.yaml`` (shipped with bille) runs it: every run
    in its own process through the sweep engine, here restricted to ``maps`` and ``movesets``, its
    results in ``folder`` (measured afresh: earlier results there are replaced)."""
    import tempfile

    from ..sweep.commands import run_spec
    from ..sweep.spec import load_spec

    spec = load_spec(SWEEP_FILE)
    runs = [r for r in spec.runs if r.instance.split()[0] in maps and r.instance.split()[1] in movesets]
    spec = dataclasses.replace(spec, runs=runs, time_limit=time_limit)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(folder or tmp) / "planners-sweep"
        (out / "runs.jsonl").unlink(missing_ok=True)
        _, rows = run_spec(spec, out, jobs=jobs, quiet=not progress)
    order = {r.key: k for k, r in enumerate(runs)}
    return [_planner_row(r) for r in sorted(rows, key=lambda r: order.get(r["key"], len(order)))]


def _planner_row(row: dict) -> dict:
    """A sweep row as a row of the comparison's table."""
    options, stats = json.loads(row["options"]), json.loads(row["stats"] or "{}")
    eps = options.get("epsilon")
    name, moveset = row["instance"].split()
    return dict(map=name, moveset=moveset, method=row["method"], robots=row["robots"],
                epsilon=None if eps is None else (int(eps) if float(eps).is_integer() else eps),
                horizon=options.get("horizon"), improve=options.get("improve"), status=row["status"],
                solved=row["makespan"] is not None, makespan=row["makespan"], tiles_traveled=row["tiles_traveled"],
                sum_of_costs=Counters.of(stats).sum_of_costs, time_s=row["time_s"])


def label(row: dict) -> str:
    if row["method"] == "lacam":
        return "LaCAM*(first)" if not row.get("improve") else f"LaCAM*({row['improve']:g} s)"
    name = {"astar": "A*", "mstar": "M*", "temporal-astar": "Temp A*"}[row["method"]]
    eps = f"eps={row['epsilon']}"
    return f"{name}({eps})" if row["horizon"] is None else f"{name}({eps},H={row['horizon']})"


def write_csv(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def _unsolved(row: dict | None) -> str:
    if row is None:
        return "N/A"
    return {"unsolved": "gave up", "timeout": "out of time"}.get(row["status"], row["status"])


def tables(rows: list[dict], time_limit: float) -> list[str]:
    """Per moveset, like Table I: time steps, tiles traveled and planning time per configuration
    and number of robots ("gave up" when a planner stopped without a schedule before the time
    limit, "out of time" when the limit ended it), then planning time as a ratio to M*(eps=1) on the
    same map, the baseline of the same run."""
    out = []
    robots = sorted({r["robots"] for r in rows})
    columns = ["planner"] + [f"m={m}" for m in robots]
    right = set(columns[1:])
    metrics = [("time steps", "makespan", str), ("tiles traveled", "tiles_traveled", str),
               ("planning time [s]", "time_s", lambda t: f"{t:.3f}")]
    for ms in sorted({r["moveset"] for r in rows}):
        sub = [r for r in rows if r["moveset"] == ms]
        labels = list(dict.fromkeys(label(r) for r in sub))
        cell = {(label(r), r["robots"]): r for r in sub}
        for title, field, fmt in metrics:
            out.append(f"{title} ({ms}, time limit {time_limit:g} s)")
            out += text_table(columns, [[lbl] + [fmt(r[field]) if r and r["solved"] else _unsolved(r)
                                                 for r in (cell.get((lbl, m)) for m in robots)] for lbl in labels],
                              right=right)
            out.append("")
        out.append(f"planning time / M*(eps=1) on the same map ({ms}; below 1 is faster)")
        table = []
        for lbl in labels:
            ratios = []
            for m in robots:
                r, b = cell.get((lbl, m)), cell.get(("M*(eps=1)", m))
                ok = r and r["solved"] and b and b["solved"] and b["time_s"] > 0
                ratios.append(f"{r['time_s'] / b['time_s']:.3g}" if ok else "-")
            table.append([lbl] + ratios)
        out += text_table(columns, table, right=right)
        out.append("")
    return out


def plot(rows: list[dict], time_limit: float, path: Path) -> None:
    """Planning time per map (log scale), one panel per moveset; runs out of time as X on the
    time-limit line (dashed), as in the paper's figure; runs that gave up before it (status
    ``unsolved``: a deadlock, no plan) as hollow markers at the time they stopped."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    movesets = sorted({r["moveset"] for r in rows})
    labels = list(dict.fromkeys(label(r) for r in rows))
    family = {"astar": ("Blues", "s"), "mstar": ("Greens", "^"), "temporal-astar": ("Reds", "o"),
              "lacam": ("Purples", "D")}
    style = {}
    for method, (cmap, marker) in family.items():
        mine = [lbl for lbl in labels if any(label(r) == lbl and r["method"] == method for r in rows)]
        for k, lbl in enumerate(mine):
            style[lbl] = (plt.get_cmap(cmap)(0.45 + 0.5 * k / max(1, len(mine) - 1)), marker)
    fig, axes = plt.subplots(len(movesets), 1, figsize=(11, 3.4 * len(movesets)), squeeze=False)
    for ax, ms in zip(axes[:, 0], movesets):
        for k, lbl in enumerate(labels):
            color, marker = style[lbl]
            offset = (k - len(labels) / 2) * 0.035
            for r in (r for r in rows if r["moveset"] == ms and label(r) == lbl):
                x = r["robots"] + offset
                if r["solved"]:
                    ax.plot(x, max(r["time_s"], 1e-4), marker, color=color, markersize=5)
                elif r["status"] == "timeout":  # out of time: on the time-limit line
                    ax.plot(x, time_limit, "x", color=color, markersize=6, markeredgewidth=1.5)
                else:  # gave up (deadlock, no plan) before the limit: hollow, at the time it stopped
                    ax.plot(x, max(r["time_s"], 1e-4), marker, color=color, markersize=6, markerfacecolor="none")
        ax.axhline(time_limit, linestyle="--", color="gray", linewidth=1)
        ax.set_yscale("log")
        ax.set_ylabel("planning time [s]")
        ax.set_title(f"moveset {ms}  (x: out of time at {time_limit:g} s; hollow: gave up)", fontsize=10)
        ax.set_xticks(sorted({r["robots"] for r in rows}))
        ax.set_xlabel("robots (map compare-m)")
    handles = [plt.Line2D([], [], linestyle="", marker=style[lbl][1], color=style[lbl][0], label=lbl) for lbl in labels]
    fig.legend(handles=handles, loc="center right", fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0, 0.8, 1))
    fig.savefig(path, dpi=130)
    plt.close(fig)


# ---- many robots -----------------------------------------------------------------------------


def crowd_instance(size: int, robots: int, seed: int):
    """A ``size`` square of tiles with ~8% holes, ``robots`` S7 robots and random goal cells."""
    from bille.instances.walking import UNREACHABLE, walk_for
    from bille.instances import Grid, Instance, check_instance, load_moveset

    from .core import holey_square, north_facing

    rnd = random.Random(seed)
    n = size * size
    tiles = holey_square(size, rnd)
    grid = Grid.from_masks(size, size, np.zeros(n, bool), tiles)
    ms = load_moveset("S7")
    placed = north_facing(tiles, size, robots, rnd)
    probe = Instance("crowd", ms, grid, tuple(placed))
    walk = walk_for(probe.world.graphs[0], tiles)
    goals, taken = [], set()
    for r, pose in zip(placed, probe.start_state.poses):
        while True:
            cell = rnd.choice(np.flatnonzero(tiles).tolist())
            if cell not in taken and walk.distances(cell)[pose] < UNREACHABLE:
                goals.append(grid.xy(cell))
                taken.add(cell)
                break
    return check_instance(Instance(f"crowd-{size}-{robots}", ms, grid, tuple(placed), robot_goals=tuple(goals)))


def bench_crowd(size: int = 64, robots: int = 50, horizon: int = 5, seed: int = 0) -> list[str]:
    from bille.heuristics import spacetime
    from bille.heuristics.joint import JointProblem
    from bille.solvers import solve, validate

    inst = crowd_instance(size, robots, seed)
    result = solve(inst, "temporal-astar", horizon=horizon)
    ok = result.schedule is not None and validate(inst, result.schedule).valid
    # baseline: every robot's window planned alone (no reservations), once, from the start
    problem = JointProblem.of(inst)
    t0 = time.perf_counter()
    for i, p in enumerate(problem.start):
        spacetime.window(problem.walks[i], problem.dist_lists[i], problem.home_lists[i], p, horizon,
                         [set() for _ in range(horizon + 1)], set())
    alone_ms = 1000 * (time.perf_counter() - t0)
    counts = result.counters
    mean = counts.plan_ms_mean
    return [
        f"Temporal A* with {robots} robots on a {size}x{size} structure (S7, H={horizon}, seed {seed}):",
        f"  status {result.status}{'' if ok else ' (no valid schedule)'}, {counts.steps} steps, "
        f"{counts.priority_shifts} priority shifts, total {result.time_s:.2f} s",
        f"  replanning per step: mean {mean:.1f} ms, max {counts.plan_ms_max:.1f} ms   [target mean < 100 ms]",
        f"  baseline, every robot's window alone without reservations: {alone_ms:.1f} ms "
        f"-> coordination costs {mean / alone_ms:.2f}x",
    ]


def default_jobs() -> int:
    return max(1, os.cpu_count() or 1)
