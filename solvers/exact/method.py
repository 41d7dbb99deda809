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
of the time limit (at most 1 s), else the complete planner's in a tenth (:mod:`bille.solvers.incumbent`),
validated; its makespan caps the horizons (also above the default cap, which bounds a search
with no schedule to go by), and it is returned (``feasible``) when time runs out.

Statuses: ``optimal`` (``stats.tiles_traveled_optimal`` says whether the second objective was
proved too), ``feasible`` (time ran out; the incumbent, with the lower bound reached),
``interrupted`` (a second Ctrl-C, or a callback of the run's events that raised ``KeyboardInterrupt``:
the best schedule so far, if any, with the lower bound reached; a first Ctrl-C cancels the run's
budget and ends it as time running out does, and ``solve()`` calls it ``interrupted``),
``infeasible`` (a static proof, or the complete planner exhausted the reachable states:
``stats.reason``), ``unsolved`` (no schedule up to the horizon cap), ``timeout`` (time ran out
with no schedule; the lower bound says how far the search got).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.encodings.backend import SAT_SOLVERS
from bille.encodings.model import CONNECTIVITY, Options
from bille.instances import Instance, OptionError
from bille.instances.failure import Failure, no_schedule
from bille.instances.options import MethodOptions, option
from bille.instances.result import Result
from bille.instances.run import Budget, Run
from bille.instances.rules import goal_violation
from bille.instances.schedule import Schedule

from ..bounds import Bounds, lower_bound
from ..incumbent import EXHAUSTED, to_cap
from .horizons import sequential
from .lanes import parallel
from .search import RESTRICTIONS, Job, Search


def default_cap(lower: int) -> int:
    """The default horizon cap: generous for the small instances exact solvers are for."""
    return max(2 * lower, lower + 24)


@dataclass(frozen=True)
class ModelOptions(MethodOptions):
    """The options both exact methods share.

    ``max_makespan``: horizon cap (default: the incumbent's makespan, or ``max(2 LB, LB + 24)``
    where there is no incumbent). ``connectivity``: ``eager`` (reachability layers; measured
    faster, see ``bille bench exact``), ``lazy`` (cuts on demand) or ``cuts``.
    ``minimize_travel``: then minimize tiles traveled at the optimal makespan; ``travel_time``:
    seconds for that minimization (default: half the time the makespan search took, at least 1
    s; within the run's budget); ``stats.tiles_traveled_optimal`` says whether it was proved.
    ``stats.makespan_s`` is the time to the proved optimal makespan. ``prune``: reachability and
    candidate-cell pruning (switch off to measure them); ``prune_tiles``: the reachability in
    time with the tiles (:mod:`bille.encodings.reach`), part of ``prune``. ``single_carry``: only
    schedules that carry every tile once, from a start-only cell straight to a goal-only cell
    (no hand-over): the best such makespan (see ``encodings.model.Options``); its proofs hold for
    those schedules only: ``optimal`` is optimal among them, their bound is the result's
    claim's, and ``lower_bound`` stays the instance's static bound (a
    hand-over may be shorter: Theorem 2's gadget, 24 against 28). ``keep_structure``: only
    schedules that pick and place where the start and the goal differ (no stepping stone, no
    tile of the structure moved aside), with the proofs of ``single_carry`` about those
    schedules only (bridge-3: 19, where moving the structure gives 15); ``single_carry`` is the
    stricter of the two. ``no_scaffold``: only schedules that never set a tile down, even for a
    while, where neither the start nor the goal has one (the class ``no-scaffold``), with the same
    kind of proofs; both others imply it. ``incumbent``: a schedule to start from (``bille solve --incumbent
    FILE``); must be valid."""

    max_makespan: int | None = option(None, at_least=1,
                                      help="horizon cap (default: the incumbent's makespan, or max(2 LB, LB + 24))")
    connectivity: str = option("eager", choices=CONNECTIVITY,
                               help="how the structure is kept connected: eager (reachability layers), lazy or cuts")
    minimize_travel: bool = option(True, help="then minimize tiles traveled at the optimal makespan")
    prune: bool = option(True, help="reachability and candidate-cell pruning (switch off to measure it)")
    prune_tiles: bool = option(True, help="reachability in time with the tiles, part of prune")
    single_carry: bool = option(False,
                                help="only schedules that carry each tile once, start-only cell to goal-only cell (a "
                                     "class)")
    keep_structure: bool = option(False,
                                  help="only schedules that pick and place where start and goal differ (a class)")
    no_scaffold: bool = option(False,
                               help="only schedules that never set a tile where neither start nor goal has one (a "
                                    "class)")
    incumbent: Schedule | None = option(None,
                                        help="a valid schedule to start from (--incumbent FILE): caps the horizon")
    travel_time: float | None = option(None, at_least=0,
                                       help="seconds for minimizing tiles traveled (default: half the makespan "
                                            "search, at least 1)")

    def model(self) -> Options:
        return Options(prune_reach=self.prune, prune_cells=self.prune, prune_tiles=self.prune and self.prune_tiles,
                       connectivity=self.connectivity, single_carry=self.single_carry,
                       keep_structure=self.keep_structure and not self.single_carry,
                       no_scaffold=self.no_scaffold and not (self.single_carry or self.keep_structure))

    def restriction(self) -> str | None:
        """The narrowest restriction asked for (each implies the ones after it), or None."""
        return next((r for r in ("single_carry", "keep_structure", "no_scaffold") if getattr(self, r)), None)


@dataclass(frozen=True)
class CpsatOptions(ModelOptions):
    """CP-SAT's: ``threads`` (workers; 1 with a fixed seed is repeatable), ``seed``,
    ``presolve`` (for the makespan search; off by default: on these large Boolean models it
    costs more than it saves, ``bille bench exact`` measures it; the minimization of tiles
    traveled always presolves), ``first_horizon`` (a guess of the optimal makespan: the search
    starts there, going down while schedules are found and up while none is, instead of up from
    the lower bound; each horizon below the optimum costs a proof of infeasibility, one at
    ``T - 1`` is enough), and those of :class:`ModelOptions`."""

    METHOD = "cpsat"
    threads: int = option(1, at_least=1, help="CP-SAT workers (1 with a fixed seed is repeatable)")
    seed: int = option(0, at_least=0, help="CP-SAT's random seed")
    presolve: bool = option(False,
                            help="CP-SAT's presolve for the makespan search (off: it costs more than it saves here)")
    first_horizon: int | None = option(None, at_least=1,
                                       help="a guess of the optimum: search down from it while schedules are found, "
                                            "up while none is")


@dataclass(frozen=True)
class SatOptions(ModelOptions):
    """The SAT search's: ``solver`` (a python-sat solver name), ``chunk`` (how many horizons one
    model covers before it is rebuilt larger), and those of :class:`ModelOptions`. The defaults
    are the fastest measured to a proved optimum (``bille bench exact --only sat-solver``;
    docs/exact.md): a model built for one horizon is pruned to what that horizon allows, which
    outweighs keeping learned clauses across horizons in a larger model."""

    METHOD = "sat"
    solver: str = option("glucose42", choices=SAT_SOLVERS, help="the python-sat solver")
    chunk: int = option(1, at_least=1, help="horizons one model covers before it is rebuilt larger")


def plan_cpsat(instance: Instance, options: CpsatOptions | None = None, run: Run | None = None, *,
               bounds: Bounds | None = None) -> Result:
    """Optimal makespan with OR-Tools CP-SAT (:class:`CpsatOptions`), within the run's budget
    (no run: no limit); ``bounds``: the static lower bound, if already computed (``solve()``
    passes it). The run's progress hears of each horizon decided: ``{"horizon", "answer",
    "time_s", "elapsed"}`` (the command line's live line)."""
    o = options or CpsatOptions()
    job = Job("cpsat", "cpsat", o.model(), threads=o.threads, seed=o.seed, presolve=o.presolve,
              first_horizon=o.first_horizon, minimize_travel=o.minimize_travel, travel_time=o.travel_time,
              restriction=o.restriction())
    return makespan_search(job, instance, run, o.max_makespan, o.incumbent, bounds)


def plan_sat(instance: Instance, options: SatOptions | None = None, run: Run | None = None, *,
             bounds: Bounds | None = None) -> Result:
    """Optimal makespan with a SAT solver of python-sat, incremental with assumptions
    (:class:`SatOptions`; otherwise as :func:`plan_cpsat`)."""
    o = options or SatOptions()
    job = Job("sat", o.solver, o.model(), incremental=True, chunk=o.chunk, minimize_travel=o.minimize_travel,
              travel_time=o.travel_time, restriction=o.restriction())
    return makespan_search(job, instance, run, o.max_makespan, o.incumbent, bounds)


def makespan_search(job: Job, instance: Instance, run: Run | None, max_makespan: int | None,
                    incumbent: Schedule | None, bounds: Bounds | None) -> Result:
    """The makespan search ``job`` on ``instance`` (module docstring): the static and trivial
    answers, the incumbent, then the search over horizons (:func:`.lanes.parallel` with two or
    more threads and no ``first_horizon``, else :func:`.horizons.sequential`)."""
    method = job.method
    run = run or Run()
    budget = run.budget.child()  # started now: the search's own time
    bounds = bounds or lower_bound(instance)
    within = _class_bound(job, instance, bounds, budget)
    start = bounds.lower if within is None or within.empty else max(bounds.lower, within.lower)
    cap = default_cap(start) if max_makespan is None else max_makespan
    if cap < bounds.lower:
        raise OptionError(f"{method}: the horizon cap {cap} is below the makespan lower bound "
                          f"{bounds.lower} ({_parts(bounds.parts)})")
    search = Search(job, instance, budget, bounds, cap, run.events.progress, start=start)
    if bounds.impossible:
        search.stats["reason"] = "; ".join(bounds.impossible)
        return search.result("infeasible")
    if within is not None and within.empty:  # a proof for the restriction only: not "infeasible"
        return search.result("unsolved", failure=no_schedule(f"no {RESTRICTIONS[job.restriction][1]} exists: "
                                                             f"{'; '.join(within.why)}"))
    if cap < start:  # the class's bound is already above the cap
        which = RESTRICTIONS[job.restriction][1]
        return search.result("unsolved", lower=start, failure=Failure(
            "cap", f"no {which} with a makespan up to the horizon cap {cap}: its class needs {start}"))
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


def _class_bound(job: Job, instance: Instance, bounds: Bounds, budget: Budget):
    """For a restricted search, the bound of its class of schedules (:mod:`bille.solvers.bounds.classes`:
    ``no_scaffold``, ``keep_structure`` and ``single_carry`` are the classes of those names),
    where its horizons start: every horizon below it has no schedule of the class. None for an
    unrestricted search or where the static bound proves the instance infeasible. The class
    bounds ``solve()`` computed with the static bound are used, else computed here."""
    from bille.solvers.bounds.classes import RESTRICTIONS, applies, class_bounds

    if job.restriction is None or bounds.impossible or not applies(instance):
        return None
    classes = bounds.classes or class_bounds(instance, budget=budget, unconditional=bounds.lower)
    return classes[RESTRICTIONS[job.restriction]]


def _find_incumbent(search: Search, given: Schedule | None, cap_given: bool) -> bool:
    """A first schedule (:func:`bille.solvers.incumbent.to_cap`); its makespan caps the search. True if the
    complete planner proved instead that no schedule exists. A restricted search
    (``single_carry``, ``keep_structure``, ``no_scaffold``) takes none: a schedule outside the restriction would cap
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


def _parts(parts: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in parts.items() if v is not None)


__all__ = ["CpsatOptions", "ModelOptions", "RESTRICTIONS", "SatOptions", "default_cap", "makespan_search", "plan_cpsat",
           "plan_sat"]
