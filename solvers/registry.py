"""The method registry: one record per method (:class:`Method`), in the order shown to users.

A record says where the method's planning function ``plan(instance, options, run) -> Result``
and its options class (:class:`~bille.instances.options.MethodOptions`) live (``"module:name"``:
a method's module, and the libraries it needs (OR-Tools, python-sat), are imported when the method
is first used, not when the command line starts), what it plans for and proves, whether it plans
under classic collisions, whether it searches from the static bound (``solve()`` then computes it
first and hands it over), and its default time limit. ``bille methods``, ``-O help``, ``solve()``
and the parametrized tests read the records.

The registry names entry points only: what a method does on which instance is its own package's
decision (the paper's planners walk on a fixed structure; on an instance that moves tiles,
``mstar`` and ``lacam`` run the reconfiguration loop, :mod:`bille.heuristics.loop.reconfigure`,
with the planner as its motion layer, :func:`bille.heuristics.mstar.method` and
:func:`bille.heuristics.lacam.method.method`; ``temporal-astar`` always runs the loop: path
planning is the loop with no jobs).
"""
from __future__ import annotations

import dataclasses
import importlib
from collections.abc import MutableMapping
from dataclasses import dataclass
from typing import Callable, Iterator

from bille.instances import Instance
from bille.instances.result import Result
from bille.instances.run import Run


@dataclass(frozen=True)
class Method:
    """One method: where its planning function and options class live (``"module:name"``),
    what it plans for and what it proves (``bille methods``), whether it plans under classic
    collisions, whether it searches from the static bound (``solve()`` computes it first and
    hands it over as ``bounds``), the seconds it gets without a time limit given (None: no
    limit), and whether it needs one (its parts take shares of it). Calling a record runs the
    method: ``record(instance, options, run)``."""

    name: str
    plan_at: str
    options_at: str
    plans: str
    proves: str
    classic: bool = False
    bound: bool = False
    time_limit: float | None = None
    limit_required: bool = False
    function: Callable[..., Result] | None = None  # set where a test replaces the method

    def plan(self) -> Callable[..., Result]:
        return self.function or _load(self.plan_at)

    def options(self) -> type:
        return _load(self.options_at)

    def __call__(self, instance: Instance, options=None, run: Run | None = None, **internal) -> Result:
        return self.plan()(instance, options, run, **internal)


def _load(where: str):
    module, _, name = where.partition(":")
    return getattr(importlib.import_module(module), name)


class Registry(MutableMapping):
    """Method name -> :class:`Method`. Looking a record up imports nothing; a planning function
    set in place of a record (tests replace a method this way) keeps the record's other fields."""

    def __init__(self, records: list[Method]) -> None:
        self._records = {r.name: r for r in records}

    def __getitem__(self, name: str) -> Method:
        return self._records[name]

    def __setitem__(self, name: str, value: Method | Callable[..., Result]) -> None:
        self._records[name] = value if isinstance(value, Method) else dataclasses.replace(self._records[name],
                                                                                         function=value)

    def __delitem__(self, name: str) -> None:
        del self._records[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._records)

    def __len__(self) -> int:
        return len(self._records)


_H = "bille.heuristics"
METHODS = Registry([
    Method("auto", "bille.solvers.auto:plan", "bille.solvers.auto:AutoOptions",
           "the method the instance calls for, named in its output: the brute force on tiny state spaces, "
           "cbs on classic MAPF, anytime otherwise", "what the method it ran proves",
           classic=True, bound=True, time_limit=60.0, limit_required=True),
    Method("astar", f"{_H}.astar:plan", f"{_H}.astar:Options",
           "least sum of costs (then makespan) over walking-only schedules, on a fixed structure",
           "optimal with epsilon 1", classic=True),
    Method("cbs", f"{_H}.cbs:plan", f"{_H}.cbs.method:Options",
           "least sum of costs (or makespan) on a fixed structure, classic or Bill-E collisions; see docs/cbs.md",
           "optimal with w 1 (over every schedule where no free cell touches a tile); a lower bound on the "
           "sum of costs otherwise", classic=True, time_limit=60.0),
    Method("mstar", f"{_H}.mstar:method", f"{_H}.mstar:Options",
           "as astar, by subdimensional expansion; on a reconfiguration, the loop's motion layer",
           "optimal with epsilon 1 on a fixed structure; nothing on a reconfiguration"),
    Method("temporal-astar", f"{_H}.temporal_astar:plan", f"{_H}.temporal_astar:Options",
           "the paper's prioritized planner in a window of H steps; on a reconfiguration, the loop's motion layer",
           "nothing (feasible schedules)"),
    Method("lacam", f"{_H}.lacam.method:method", f"{_H}.lacam:Options",
           "LaCAM*: complete and anytime; on a reconfiguration, the loop then a search over whole states",
           "optimal walking makespan when its search space is exhausted; infeasible when the whole-state "
           "search is", classic=True),
    Method("cpsat", "bille.solvers.exact:plan_cpsat", "bille.solvers.exact:CpsatOptions",
           "least makespan, by the time-expanded model on CP-SAT; then tiles traveled",
           "optimal makespan; a lower bound when it stops early", bound=True),
    Method("sat", "bille.solvers.exact:plan_sat", "bille.solvers.exact:SatOptions",
           "least makespan, by the time-expanded model on a SAT solver (python-sat)",
           "optimal makespan; a lower bound when it stops early", bound=True),
    Method("anytime", "bille.solvers.anytime:plan", "bille.solvers.anytime:AnytimeOptions",
           "a schedule at once, then shorter ones, while a lower bound rises",
           "the makespan's lower bound; optimal when the two meet (the certified gap otherwise)",
           bound=True, time_limit=60.0, limit_required=True),
    Method("bfs", "bille.solvers.bfs:plan", "bille.solvers.bfs:Options",
           "least makespan by a compiled breadth-first search over joint states, over every schedule or a class "
           "(cells=keep|no-scaffold|all, add_cells); see docs/exact.md",
           "optimal makespan of the class searched; a bound of the class when it stops early",
           classic=True, time_limit=60.0),
])

CLASSIC = tuple(name for name, record in METHODS.items() if record.classic)  # docs/rules.md
