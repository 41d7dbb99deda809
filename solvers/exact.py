"""Optimal makespan by the time-expanded encodings (``cpsat`` and ``sat``).

Makespan search: from the lower bound upward, horizon ``T = LB, LB + 1, ...`` until the model is
satisfiable; optimality is proved by infeasibility at ``T - 1`` (or ``T`` equal to the bound).
CP-SAT may instead start from a guess (``first_horizon``) and go down while satisfiable.
CP-SAT builds the model for each ``T`` (pruning is tightest for the exact horizon); SAT builds it
once for a range of horizons and searches by assumptions (``done[k]``: every robot waits after
step ``k``), incrementally, rebuilding only when the range is exhausted. With lazy connectivity
each solution is checked step by step and a disconnected one adds cuts for every step before the
solver goes on. Then, at the optimal makespan, tiles traveled are minimized (``minimize_travel``).

Incumbent: a schedule given with ``incumbent``, else the best the heuristics find in a twentieth
of the time limit (at most 1 s), else the complete planner's in a tenth (:mod:`.incumbent`),
validated; its makespan caps the horizons (also above the default cap, which bounds a search
with no schedule to go by), and it is returned (``feasible``) when time runs out.

Statuses: ``optimal`` (``stats.tiles_traveled_optimal`` says whether the second objective was
proved too), ``feasible`` (time ran out; the incumbent, with the lower bound reached),
``interrupted`` (a second Ctrl-C, or a ``progress`` callback that raised ``KeyboardInterrupt``:
the best schedule so far, if any, with the lower bound reached; a first Ctrl-C cancels the run's
budget and ends it as time running out does, and ``solve()`` calls it ``interrupted``),
``infeasible`` (a static proof, or the complete planner exhausted the reachable states:
``stats.reason``), ``unsolved`` (no schedule up to the horizon cap), ``timeout`` (time ran out
with no schedule; the lower bound says how far the search got).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from bille.encodings.backend import SAT_SOLVERS
from bille.encodings.model import CONNECTIVITY, Options
from bille.instances import Instance, OptionError
from bille.instances.result import Result
from bille.instances.run import Run
from bille.instances.rules import goal_violation
from bille.instances.schedule import Schedule

from .bounds import Bounds, lower_bound
from .horizons import sequential
from .incumbent import EXHAUSTED, to_cap
from .lanes import parallel
from .search import RESTRICTIONS, Job, Search


def default_cap(lower: int) -> int:
    """The default horizon cap: generous for the small instances exact solvers are for."""
    return max(2 * lower, lower + 24)


def plan_cpsat(instance: Instance, *, run: Run | None = None, threads: int = 1, seed: int = 0,
               presolve: bool = False,
               max_makespan: int | None = None, connectivity: str = "eager", minimize_travel: bool = True,
               prune: bool = True, prune_tiles: bool = True, single_carry: bool = False, keep_structure: bool = False,
               first_horizon: int | None = None, incumbent: Schedule | None = None, travel_time: float | None = None,
               bounds: Bounds | None = None, progress: Callable | None = None) -> Result:
    """Optimal makespan with OR-Tools CP-SAT.

    Parameters
    ----------
    run : the run context (its budget covers the whole search; default: no limit).
    threads : CP-SAT workers (1 with a fixed seed is repeatable).
    presolve : CP-SAT's presolve for the makespan search; off by default: on these large
        Boolean models it costs more than it saves (``bille bench exact`` measures it). The
        minimization of tiles traveled always presolves: an objective profits from it.
    max_makespan : horizon cap (default: the incumbent's makespan, or ``max(2 LB, LB + 24)``
        where there is no incumbent).
    connectivity : ``eager`` (reachability layers; measured faster, see ``bille bench exact``)
        or ``lazy`` (cuts on demand).
    minimize_travel : then minimize tiles traveled at the optimal makespan.
    travel_time : seconds for that minimization (default: half the time the makespan search took,
        at least 1 s; within the run's budget); ``stats.tiles_traveled_optimal`` says whether it
        was proved. ``stats.makespan_s`` is the time to the proved optimal makespan.
    prune : reachability and candidate-cell pruning (switch off to measure them).
    prune_tiles : the reachability in time with the tiles (:mod:`bille.encodings.reach`), part of
        ``prune``; switch it off alone to measure it (``bille bench exact`` compares).
    single_carry : only schedules that carry every tile once, from a start-only cell straight to
        a goal-only cell (no hand-over): the best such makespan (see ``encodings.model.Options``).
        Its proofs hold for those schedules only: ``optimal`` is optimal for ``stats.objective``,
        their bound is ``stats.restricted_lower_bound``, and ``lower_bound`` stays the instance's
        static bound (a hand-over may be shorter: Theorem 2's gadget, 24 against 28).
    keep_structure : only schedules that pick and place where the start and the goal differ (no
        stepping stone, no tile of the structure moved aside): the best such makespan, with the
        proofs of ``single_carry`` about those schedules only (bridge-3: 19, where moving the
        structure gives 15). ``single_carry`` is the stricter of the two.
    first_horizon : a guess of the optimal makespan: the search starts there, going down while
        schedules are found and up while none is, instead of up from the lower bound (each
        horizon below the optimum costs a proof of infeasibility; one at ``T - 1`` is enough).
    incumbent : a schedule to start from (``bille solve --incumbent FILE``); must be valid.
    bounds : the static lower bound, if already computed (``solve()`` passes it).
    progress : called with ``{"horizon", "answer", "time_s", "elapsed"}`` as each horizon is
        decided (the command line's live line).
    """
    if first_horizon is not None and first_horizon < 1:
        raise OptionError(f"cpsat: first_horizon must be at least 1, got {first_horizon}")
    job = Job("cpsat", "cpsat", _options(prune, prune_tiles, connectivity, single_carry, keep_structure),
              threads=threads, seed=seed, presolve=presolve, first_horizon=first_horizon,
              minimize_travel=minimize_travel, travel_time=travel_time,
              restriction=_restriction(single_carry, keep_structure))
    return makespan_search(job, instance, run, max_makespan, incumbent, bounds, progress)


def plan_sat(instance: Instance, *, run: Run | None = None, max_makespan: int | None = None,
             connectivity: str = "eager", minimize_travel: bool = True, prune: bool = True, prune_tiles: bool = True,
             single_carry: bool = False, keep_structure: bool = False, solver: str = "glucose42", chunk: int = 1,
             incumbent: Schedule | None = None, travel_time: float | None = None, bounds: Bounds | None = None,
             progress: Callable | None = None) -> Result:
    """Optimal makespan with a SAT solver of python-sat, incremental with assumptions.

    Parameters are those of :func:`plan_cpsat`, and: ``solver`` (a python-sat solver name,
    default ``glucose42``), ``chunk`` (how many horizons one model covers before it is rebuilt
    larger, default 1).

    The defaults are the fastest measured to a proved optimum (``bille bench exact --only
    sat-solver``; docs/exact.md): a model built for one horizon is pruned to what that horizon
    allows, which outweighs keeping learned clauses across horizons in a larger model.
    """
    if solver not in SAT_SOLVERS:
        raise OptionError(f"sat: unknown solver {solver!r} (expected one of: {', '.join(SAT_SOLVERS)})")
    job = Job("sat", solver, _options(prune, prune_tiles, connectivity, single_carry, keep_structure),
              incremental=True, chunk=chunk, minimize_travel=minimize_travel, travel_time=travel_time,
              restriction=_restriction(single_carry, keep_structure))
    return makespan_search(job, instance, run, max_makespan, incumbent, bounds, progress)


def makespan_search(job: Job, instance: Instance, run: Run | None, max_makespan: int | None,
        incumbent: Schedule | None, bounds: Bounds | None, progress: Callable | None) -> Result:
    """The makespan search ``job`` on ``instance`` (module docstring): the static and trivial
    answers, the incumbent, then the search over horizons (:func:`.lanes.parallel` with two or
    more threads and no ``first_horizon``, else :func:`.horizons.sequential`)."""
    method = job.method
    if job.options.connectivity not in CONNECTIVITY:
        raise OptionError(f"{method}: connectivity must be one of {', '.join(CONNECTIVITY)}, "
                          f"got {job.options.connectivity!r}")
    if job.threads < 1 or job.chunk < 1:
        raise OptionError(f"{method}: threads and chunk must be at least 1")
    budget = (run or Run.limited()).budget.child()  # started now: the search's own time
    bounds = bounds or lower_bound(instance)
    cap = default_cap(bounds.lower) if max_makespan is None else max_makespan
    if cap < bounds.lower:
        raise OptionError(f"{method}: the horizon cap {cap} is below the makespan lower bound "
                          f"{bounds.lower} ({_parts(bounds.parts)})")
    search = Search(job, instance, budget, bounds, cap, progress)
    if bounds.impossible:
        search.stats["reason"] = "; ".join(bounds.impossible)
        return search.result("infeasible")
    if goal_violation(instance.world, instance.start_state, instance.goal_tiles, instance.goal_cells, 0) is None:
        search.stats["tiles_traveled_optimal"] = True
        return search.result("optimal", np.zeros((instance.num_robots, 0), dtype=np.int64), lower=0)
    try:
        if _find_incumbent(search, incumbent, max_makespan is not None):
            search.stats["reason"] = EXHAUSTED  # the complete planner's proof: no reachable state is a goal
            return search.result("infeasible")
        return parallel(search) if job.threads >= 2 and job.first_horizon is None else sequential(search)
    except KeyboardInterrupt:  # Ctrl-C: the best schedule and the bound proved so far
        return search.interrupted()


def _find_incumbent(search: Search, given: Schedule | None, cap_given: bool) -> bool:
    """A first schedule (:func:`.incumbent.to_cap`); its makespan caps the search. True if the
    complete planner proved instead that no schedule exists. A restricted search
    (``single_carry``, ``keep_structure``) takes none: a schedule outside the restriction would cap
    its horizons, and be returned as if it were the restriction's optimum."""
    job = search.job
    if job.restriction:
        if given is not None:
            raise OptionError(f"{job.method}: an incumbent cannot be combined with {job.restriction} (a "
                              f"schedule outside the restriction would cap its search)")
        return False
    found, exhausted = to_cap(search.instance, given, search.budget, job.method)
    if found is None:
        return exhausted
    search.stats["incumbent"] = {"method": found.method, "makespan": found.makespan}
    search.fallback = found.ids  # returned if the search ends without a schedule of its own
    if found.makespan <= search.cap or not cap_given:
        # a schedule is there to be shortened: the default cap, which bounds a search that may
        # have none, gives way to it (a cap given stays)
        search.incumbent, search.cap = found.ids, found.makespan
        search.stats["horizon_cap"] = found.makespan
    return False


def _options(prune: bool, prune_tiles: bool, connectivity: str, single_carry: bool, keep_structure: bool) -> Options:
    return Options(prune_reach=prune, prune_cells=prune, prune_tiles=prune and prune_tiles, connectivity=connectivity,
                   single_carry=single_carry, keep_structure=keep_structure and not single_carry)


def _restriction(single_carry: bool, keep_structure: bool) -> str | None:
    return "single_carry" if single_carry else "keep_structure" if keep_structure else None


def _parts(parts: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in parts.items() if v is not None)


__all__ = ["RESTRICTIONS", "default_cap", "makespan_search", "plan_cpsat", "plan_sat"]
