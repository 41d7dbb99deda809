"""The method registry: method name -> ``plan(instance, **options) -> Result``.

An explicit table, in the order shown to users, of where each planning function lives
(``"module:function"``): a method's module, and the libraries it needs (OR-Tools, python-sat),
are imported when the method is first looked up, not when the command line starts. The paper's planners walk on a fixed structure;
on an instance that moves tiles, ``temporal-astar`` and ``mstar`` are the motion layer of the
reconfiguration loop (:mod:`bille.heuristics.reconfigure`). Which function serves an instance is
decided here, not by the planners.
"""
from __future__ import annotations

import importlib
from collections.abc import MutableMapping
from typing import Callable, Iterator

from bille.instances import Instance, OptionError
from bille.instances.result import Result
from bille.instances.run import Run


def plan_temporal_astar(instance: Instance, *, epsilon: float = 1.0, horizon: int = 5,
                        run: Run | None = None, max_steps: int | None = None,
                        max_shifts: int | None = None, shift_priorities: bool = True,
                        priorities: list[int] | None = None, load_transfer: bool = False,
                        d_tr: int = 5, active: list[int] | None = None) -> Result:
    """Temporal A* (:func:`bille.heuristics.temporal_astar.plan`); on an instance that moves tiles,
    the reconfiguration loop with Temporal A* as its motion layer (``load_transfer``, ``d_tr``:
    equations (1)-(3) of the paper; ``active``: the robots that take jobs)."""
    from bille.heuristics import reconfigure, temporal_astar

    if instance.is_reconfiguration:
        if not shift_priorities:
            raise OptionError("temporal-astar: shift_priorities=false is for path planning only")
        return reconfigure.plan(instance, motion="temporal-astar", load_transfer=load_transfer, d_tr=d_tr,
                                epsilon=epsilon, horizon=horizon, run=run, max_steps=max_steps,
                                max_shifts=max_shifts, priorities=priorities, active=active)
    _loop_only("temporal-astar", active=active)
    return temporal_astar.plan(instance, epsilon=epsilon, horizon=horizon, run=run,
                               max_steps=max_steps, max_shifts=max_shifts, shift_priorities=shift_priorities,
                               priorities=priorities)


def plan_mstar(instance: Instance, *, epsilon: float = 1.0, od: bool = True, run: Run | None = None,
               max_expansions: int = 5_000_000, load_transfer: bool = False, d_tr: int = 5,
               max_steps: int | None = None, active: list[int] | None = None) -> Result:
    """M* (:func:`bille.heuristics.mstar.plan`); on an instance that moves tiles, the
    reconfiguration loop with M* as its motion layer (``load_transfer``, ``d_tr``, ``max_steps``,
    ``active`` as for the loop)."""
    from bille.heuristics import mstar, reconfigure

    if instance.is_reconfiguration:
        return reconfigure.plan(instance, motion="mstar", load_transfer=load_transfer, d_tr=d_tr, epsilon=epsilon,
                                run=run, max_steps=max_steps, active=active)
    _loop_only("mstar", active=active)
    return mstar.plan(instance, epsilon=epsilon, od=od, run=run, max_expansions=max_expansions)


# of the time limit, at most, for the loop before the complete search takes over: the loop
# either finishes in a second or two or not at all (measured on a random 10x8 instance with four
# robots and ten moved tiles, `bille gen random --robots 4 --moved 10 --seed 2`: its motion layer
# finds no joint plan in 60 s, where the whole-state search finds a schedule in 17 s)
LOOP_SHARE = 0.5


def plan_lacam(instance: Instance, *, objective: str = "makespan", run: Run | None = None,
               improve: float = 1.0, max_nodes: int = 2_000_000, seed: int = 0, load_transfer: bool = False,
               d_tr: int = 5, max_steps: int | None = None, active: list[int] | None = None) -> Result:
    """LaCAM* (:func:`bille.heuristics.lacam.plan`). On an instance that moves tiles, the
    reconfiguration loop with LaCAM* as its motion layer (``load_transfer``, ``d_tr``,
    ``max_steps``, ``active`` as for the loop), and where the loop gives up, or runs out of its
    share of the time limit (:data:`LOOP_SHARE`), LaCAM* over whole states (every robot taking
    jobs; :mod:`bille.heuristics.lacam_states`) with the time left: complete, so the method
    finds a schedule whenever one exists (time and memory permitting) and proves ``infeasible``
    when its space is exhausted. ``objective`` is for path planning; ``improve``, ``max_nodes``
    and ``seed`` for the searches over configurations."""
    from bille.heuristics import lacam, lacam_states, reconfigure

    if not instance.is_reconfiguration:
        _loop_only("lacam", active=active)
        return lacam.plan(instance, objective=objective, run=run, improve=improve,
                          max_nodes=max_nodes, seed=seed)
    if instance.collisions == "classic":
        raise OptionError(f"lacam: instance '{instance.name}' moves tiles under classic collisions; "
                          "the reconfiguration loop plans under the Bill-E rule only")
    if objective != "makespan":
        raise OptionError(f"lacam: objective '{objective}' is for path planning; a reconfiguration is "
                          "planned for its makespan")
    run = run or Run.limited()
    loop = reconfigure.plan(instance, motion="lacam", load_transfer=load_transfer, d_tr=d_tr,
                            run=run.part(run.budget.share(LOOP_SHARE)), max_steps=max_steps, active=active,
                            method="lacam")
    if loop.status not in ("unsolved", "timeout") or run.budget.expired():
        return loop
    whole = lacam_states.plan(instance, run=run, improve=improve, max_nodes=max_nodes, seed=seed)
    whole.stats["loop"] = {"status": loop.status, "failure": loop.stats.get("failure"),
                           "steps": loop.stats.get("steps", 0)}
    return whole


def _loop_only(method: str, **options) -> None:
    """Options of the reconfiguration loop given for path planning: one clear error."""
    for name, value in options.items():
        if value is not None:
            raise OptionError(f"{method}: {name} is for instances that move tiles (the reconfiguration loop)")


ABOUT = {  # method -> (what it plans for, what it proves); `bille methods` and `-O help` print them
    "auto": ("the method the instance calls for, named in its output: the brute force on tiny state spaces, "
             "cbs on classic MAPF, anytime otherwise", "what the method it ran proves"),
    "astar": ("least sum of costs (then makespan) over walking-only schedules, on a fixed structure",
              "optimal with epsilon 1"),
    "cbs": ("least sum of costs (or makespan) on a fixed structure, classic or Bill-E collisions; see docs/cbs.md",
            "optimal with w 1 (over every schedule where no free cell touches a tile); a lower bound on the "
            "sum of costs otherwise"),
    "mstar": ("as astar, by subdimensional expansion; on a reconfiguration, the loop's motion layer",
              "optimal with epsilon 1 on a fixed structure; nothing on a reconfiguration"),
    "temporal-astar": ("the paper's prioritized planner in a window of H steps; on a reconfiguration, the loop's "
                       "motion layer", "nothing (feasible schedules)"),
    "lacam": ("LaCAM*: complete and anytime; on a reconfiguration, the loop then a search over whole states",
              "optimal walking makespan when its search space is exhausted; infeasible when the whole-state "
              "search is"),
    "cpsat": ("least makespan, by the time-expanded model on CP-SAT; then tiles traveled",
              "optimal makespan; a lower bound when it stops early"),
    "sat": ("least makespan, by the time-expanded model on a SAT solver (python-sat)",
            "optimal makespan; a lower bound when it stops early"),
    "anytime": ("a schedule at once, then shorter ones, while a lower bound rises", "the makespan's lower bound; "
                "optimal when the two meet (the certified gap otherwise)"),
    "bfs": ("least makespan by breadth-first search over joint states (tiny instances)", "optimal makespan"),
}

# the seconds a method gets from solve() without a time limit given (None: no limit)
DEFAULT_TIME_LIMIT = {"auto": 60.0, "cbs": 60.0, "anytime": 60.0}

CLASSIC = ("auto", "astar", "cbs", "lacam", "bfs")  # the methods that plan under classic collisions (docs/rules.md)

class Registry(MutableMapping):
    """Method name -> planning function, each imported from ``"module:function"`` when it is
    first looked up. Iterating gives the names without importing anything; a function may also
    be set directly (tests replace a method this way)."""

    def __init__(self, where: dict[str, str]) -> None:
        self._where: dict[str, str | Callable[..., Result]] = dict(where)

    def __getitem__(self, name: str) -> Callable[..., Result]:
        plan = self._where[name]
        if isinstance(plan, str):
            module, _, function = plan.partition(":")
            plan = self._where[name] = getattr(importlib.import_module(module), function)
        return plan

    def __setitem__(self, name: str, plan: Callable[..., Result]) -> None:
        self._where[name] = plan

    def __delitem__(self, name: str) -> None:
        del self._where[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._where)

    def __contains__(self, name) -> bool:  # the mapping's own test would import the method
        return name in self._where

    def __len__(self) -> int:
        return len(self._where)


METHODS = Registry({
    "auto": "bille.solvers.auto:plan",
    "astar": "bille.heuristics.astar:plan",
    "cbs": "bille.heuristics.cbs:plan",
    "mstar": f"{__name__}:plan_mstar",
    "temporal-astar": f"{__name__}:plan_temporal_astar",
    "lacam": f"{__name__}:plan_lacam",
    "cpsat": "bille.solvers.exact:plan_cpsat",
    "sat": "bille.solvers.exact:plan_sat",
    "anytime": "bille.solvers.anytime:plan",
    "bfs": "bille.solvers.bfs:plan",
})
