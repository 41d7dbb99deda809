"""``bille bench joint``: the compiled joint search on the paper's maps, class by class.

For each map and class: the class's optimum (or the bound reached), the states stored, the
seconds. The baseline, measured in the same run: the pure-Python search (``engine=python``) and
the compiled one each store the same number of states of the class ``all`` from the start; the
ratio of their times is the compiled search's speed-up.
"""
from __future__ import annotations

import time

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.solvers import solve

BASELINE_STATES = 20_000


def _row(name: str, cells: str, add: list | None, time_limit: float) -> dict:
    inst = load_instance(bundled_path(name))
    options = {"cells": cells, **({"add_cells": add} if add else {})}
    began = time.perf_counter()
    got = solve(inst, "bfs", time_limit=time_limit, **options)
    seconds = time.perf_counter() - began
    decided = got.status == "optimal"
    value = got.metrics.makespan if decided else got.stats.get("class", {}).get("lower_bound")
    return {"map": inst.name, "class": got.stats["class"]["cells"] + ("+" + str(len(add)) if add else ""),
            "answer": f"optimal {value}" if decided else f">= {value} ({got.stats.get('failure')})",
            "states": got.stats.get("states"), "s": round(seconds, 2)}


def _speed(name: str) -> tuple[float, float]:
    """Seconds of the Python and of the compiled search for the same number of states."""
    inst = load_instance(bundled_path(name))
    out = []
    for engine in ("python", "compiled"):
        began = time.perf_counter()
        solve(inst, "bfs", time_limit=None, engine=engine, max_states=BASELINE_STATES)
        out.append(time.perf_counter() - began)
    return out[0], out[1]


def report(maps, cells: str, add: list | None, time_limit: float, echo) -> None:
    echo(f"the compiled joint search, cells={cells}{f', add_cells={add}' if add else ''}, "
         f"{time_limit:g} s per map")
    echo(f"{'map':<10} {'class':<13} {'answer':<34} {'states':>11} {'s':>8}")
    solve(load_instance(bundled_path("bridge-2")), "bfs", cells="keep", time_limit=None)  # compiled code loaded
    for name in maps:
        r = _row(name, cells, add, time_limit)
        echo(f"{r['map']:<10} {r['class']:<13} {r['answer']:<34} {r['states']:>11,} {r['s']:>8.2f}")
    python, compiled = _speed(maps[0])
    echo(f"baseline on {maps[0]}: {BASELINE_STATES:,} states of the class all: Python {python:.2f} s, "
         f"compiled {compiled:.3f} s, ratio {python / compiled:.0f}x")
