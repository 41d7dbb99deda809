"""``bille bench joint``: the compiled joint search on the paper's maps, class by class.

For each map and class: the class's optimum (or the bound reached), the states stored, the
seconds. The baseline, measured in the same run: the pure-Python search (``engine=python``) and
the compiled one each store the same number of states of the class ``all`` from the start; the
ratio of their times is the compiled search's speed-up.
"""
from __future__ import annotations

import json
import time

import click

from bille.instances import load_instance
from bille.instances.bundled import bundled_path

from ..common import EXIT_OK
from .args import names

BASELINE_STATES = 20_000


def _solve(inst, **options):
    from bille.solvers import solve

    return solve(inst, "bfs", **options)


def _row(name: str, cells: str, add: list | None, time_limit: float) -> dict:
    inst = load_instance(bundled_path(name))
    options = {"cells": cells, **({"add_cells": add} if add else {})}
    began = time.perf_counter()
    got = _solve(inst, time_limit=time_limit, **options)
    seconds = time.perf_counter() - began
    decided = got.status == "optimal"
    value = got.metrics.makespan if decided else got.stats.get("class", {}).get("lower_bound")
    return {"map": inst.name, "class": got.stats["class"]["cells"] + ("+" + str(len(add)) if add else ""),
            "answer": f"optimal {value}" if decided else f">= {value} ({got.failure})",
            "states": got.counters.states, "s": round(seconds, 2)}


def _speed(name: str) -> tuple[float, float]:
    """Seconds of the Python and of the compiled search for the same number of states."""
    inst = load_instance(bundled_path(name))
    out = []
    for engine in ("python", "compiled"):
        began = time.perf_counter()
        forward = {"direction": "forward"} if engine == "compiled" else {}  # the same states, from the start
        _solve(inst, time_limit=None, engine=engine, max_states=BASELINE_STATES, **forward)
        out.append(time.perf_counter() - began)
    return out[0], out[1]


def report(maps, cells: str, add: list | None, time_limit: float, echo) -> None:
    echo(f"the compiled joint search, cells={cells}{f', add_cells={add}' if add else ''}, "
         f"{time_limit:g} s per map")
    echo(f"{'map':<10} {'class':<13} {'answer':<34} {'states':>11} {'s':>8}")
    _solve(load_instance(bundled_path("bridge-2")), cells="keep", time_limit=None)  # compiled code loaded
    for name in maps:
        r = _row(name, cells, add, time_limit)
        echo(f"{r['map']:<10} {r['class']:<13} {r['answer']:<34} {r['states']:>11,} {r['s']:>8.2f}")
    python, compiled = _speed(maps[0])
    echo(f"baseline on {maps[0]}: {BASELINE_STATES:,} states of the class all: Python {python:.2f} s, "
         f"compiled {compiled:.3f} s, ratio {python / compiled:.0f}x")


@click.command("joint")
@click.option("--maps", default="lt-1,lt-2,lt-3,lt-4,lt-5,lt-7,lt-8,bridge-2", show_default=True,
              help="Comma-separated bundled maps.")
@click.option("--cells", type=click.Choice(["keep", "no-scaffold", "all"]), default="keep", show_default=True,
              help="The class of schedules searched.")
@click.option("--add-cells", metavar="JSON", help="Cells added to the class, e.g. [[8,2],[8,5]].")
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=60.0, show_default=True, help="Seconds per map.")
def bench_joint(maps: str, cells: str, add_cells: str | None, time_limit: float) -> int:
    """The compiled joint search on the paper's maps within a class of schedules: each class's
    optimum, states and seconds, and the speed-up over the Python search in the same run."""
    add = None
    if add_cells:
        try:
            add = json.loads(add_cells)
        except json.JSONDecodeError:
            raise click.BadParameter(f"expected a JSON list of [x, y] pairs, got {add_cells!r}",
                                     param_hint="--add-cells") from None
    report(names(maps), cells, add, time_limit, echo=click.echo)
    return EXIT_OK
