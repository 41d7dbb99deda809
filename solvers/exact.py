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
``infeasible`` (a static proof, or the complete planner exhausted the reachable states:
``stats.reason``), ``unsolved`` (no schedule up to the horizon cap), ``timeout`` (time ran out
with no schedule; the lower bound says how far the search got).
"""
from __future__ import annotations

import time
from contextlib import contextmanager
from typing import Callable

import numpy as np

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.backend import SAT_SOLVERS, Objective, open_backend
from bille.encodings.model import CONNECTIVITY, Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance, OptionError
from bille.instances.result import Result
from bille.instances.rules import goal_violation
from bille.instances.schedule import Schedule

from .bounds import Bounds, lower_bound
from .incumbent import EXHAUSTED, to_cap
from .lanes import Lanes
from .satsearch import SatSearch


# the restrictions of the model (encodings.model.Options): what their optimum is optimal for, and
# what their schedules are called
RESTRICTIONS = {
    "single_carry": ("makespan among the schedules that carry every tile once (single_carry)",
                     "single-carry schedule"),
    "keep_structure": ("makespan among the schedules that pick and place only where the start and the goal differ "
                       "(keep_structure)", "schedule that keeps the structure"),
}


def default_cap(lower: int) -> int:
    """The default horizon cap: generous for the small instances exact solvers are for."""
    return max(2 * lower, lower + 24)


def plan_cpsat(instance: Instance, *, time_limit: float | None = None, threads: int = 1, seed: int = 0,
               presolve: bool = False,
               max_makespan: int | None = None, connectivity: str = "eager", minimize_travel: bool = True,
               prune: bool = True, prune_tiles: bool = True, single_carry: bool = False, keep_structure: bool = False,
               first_horizon: int | None = None, incumbent: Schedule | None = None, travel_time: float | None = None,
               bounds: Bounds | None = None, progress: Callable | None = None) -> Result:
    """Optimal makespan with OR-Tools CP-SAT.

    Parameters
    ----------
    time_limit : seconds for the whole search.
    threads : CP-SAT workers (1 with a fixed seed is repeatable).
    presolve : CP-SAT's presolve for the makespan search; off by default: on these large
        Boolean models it costs more than it saves (``bille bench exact`` measures it). The
        minimization of tiles traveled always presolves: an objective profits from it (compare-6:
        1.8 s with it, 120 s without).
    max_makespan : horizon cap (default: the incumbent's makespan, or ``max(2 LB, LB + 24)``
        where there is no incumbent).
    connectivity : ``eager`` (reachability layers; measured faster, see ``bille bench exact``)
        or ``lazy`` (cuts on demand).
    minimize_travel : then minimize tiles traveled at the optimal makespan.
    travel_time : seconds for that minimization (default: half the time the makespan search took,
        at least 1 s; within ``time_limit``); ``stats.tiles_traveled_optimal`` says whether it
        was proved. ``stats.makespan_s`` is the time to the proved optimal makespan.
    prune : reachability and candidate-cell pruning (switch off to measure them).
    prune_tiles : the reachability in time with the tiles (:mod:`bille.encodings.reach`), part of
        ``prune``; off alone, the encoding as it was before it (``bille bench exact`` compares).
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
    return _Search("cpsat", instance, time_limit, max_makespan, connectivity, minimize_travel, (prune, prune_tiles),
                   _restriction(single_carry, keep_structure), threads=threads, seed=seed, presolve=presolve,
                   travel_time=travel_time, first_horizon=first_horizon, incumbent=incumbent, bounds=bounds,
                   progress=progress).run()


def plan_sat(instance: Instance, *, time_limit: float | None = None, max_makespan: int | None = None,
             connectivity: str = "eager", minimize_travel: bool = True, prune: bool = True, prune_tiles: bool = True,
             single_carry: bool = False, keep_structure: bool = False, solver: str = "glucose42", chunk: int = 1,
             incumbent: Schedule | None = None, travel_time: float | None = None, bounds: Bounds | None = None,
             progress: Callable | None = None) -> Result:
    """Optimal makespan with a SAT solver of python-sat, incremental with assumptions.

    Parameters are those of :func:`plan_cpsat`, and: ``solver`` (a python-sat solver name,
    default ``glucose42``), ``chunk`` (how many horizons one model covers before it is rebuilt
    larger, default 1).

    The defaults were chosen by measurement (seconds to the proved optimal makespan on 2 cores;
    docs/exact.md has the table): a model built for one horizon is pruned to what that horizon
    allows, and that outweighs keeping learned clauses across horizons in a larger model;
    Glucose 4.2 beats CaDiCaL 1.9.5 on these models (``bille bench exact --only sat-solver``).
    reconfig-30: 18 s against 51 s for CaDiCaL with 8 horizons per model; lt-4: 4.8 s against
    24 s; compare-5: 0.4 s against 2.7 s.
    """
    if solver not in SAT_SOLVERS:
        raise OptionError(f"sat: unknown solver {solver!r} (expected one of: {', '.join(SAT_SOLVERS)})")
    return _Search("sat", instance, time_limit, max_makespan, connectivity, minimize_travel, (prune, prune_tiles),
                   _restriction(single_carry, keep_structure), solver=solver, chunk=chunk, incumbent=incumbent,
                   travel_time=travel_time, bounds=bounds, progress=progress).run()


class _Search(Lanes, SatSearch):
    def __init__(self, method, instance, time_limit, max_makespan, connectivity, minimize_travel, prune,
                 restriction, **kw):
        if time_limit is not None and time_limit <= 0:
            raise OptionError(f"{method}: the time limit must be positive, got {time_limit}")
        if connectivity not in CONNECTIVITY:
            raise OptionError(f"{method}: connectivity must be one of {', '.join(CONNECTIVITY)}, got {connectivity!r}")
        if kw.get("threads", 1) < 1 or kw.get("chunk", 1) < 1:
            raise OptionError(f"{method}: threads and chunk must be at least 1")
        self.progress = kw.pop("progress", None)
        self.method, self.instance, self.kw = method, instance, kw
        self.start = time.perf_counter()
        self.deadline = None if time_limit is None else self.start + time_limit
        prune, prune_tiles = prune
        self.options = Options(prune_reach=prune, prune_cells=prune, prune_tiles=prune and prune_tiles,
                               connectivity=connectivity,
                               single_carry=restriction == "single_carry",
                               keep_structure=restriction == "keep_structure")
        self.minimize_travel = minimize_travel
        self.incumbent: np.ndarray | None = None
        self.fallback: np.ndarray | None = None
        self.bounds = kw.pop("bounds", None) or lower_bound(instance)
        self.cap = default_cap(self.bounds.lower) if max_makespan is None else max_makespan
        self.cap_given = max_makespan is not None
        if self.cap < self.bounds.lower:
            raise OptionError(f"{method}: the horizon cap {self.cap} is below the makespan lower bound "
                              f"{self.bounds.lower} ({_parts(self.bounds.parts)})")
        self.stats = {"lower_bound": self.bounds.lower, "bound_parts": self.bounds.parts, "horizon_cap": self.cap,
                      "connectivity": connectivity, "pruning": prune, "cuts": 0, "horizons": []}
        self.restricted = restriction
        if restriction is not None:
            self.stats[restriction] = True
            self.stats["objective"] = RESTRICTIONS[restriction][0]

    @contextmanager
    def travel_time(self):
        """The minimization of tiles traveled runs until its own, earlier deadline (see
        ``travel_time`` in :func:`plan_cpsat`)."""
        full = self.deadline
        budget = self.kw.get("travel_time")
        if budget is None:
            budget = max(1.0, 0.5 * (time.perf_counter() - self.start))
        end = time.perf_counter() + budget
        self.deadline = end if full is None else min(full, end)
        try:
            yield
        finally:
            self.deadline = full

    def left(self) -> float | None:
        return None if self.deadline is None else self.deadline - time.perf_counter()

    def timeout(self, lower: int) -> Result:
        """Time is up at horizon ``lower``: the incumbent if there is one (also one above the
        horizon cap), else no schedule."""
        best = self.incumbent if self.incumbent is not None else self.fallback
        if best is not None:
            return self.result("feasible", best, lower=lower)
        return self.result("timeout", lower=lower)

    def _find_incumbent(self) -> bool:
        """A first schedule (:func:`.incumbent.to_cap`); its makespan caps the search. True if
        the complete planner proved instead that no schedule exists. A restricted search
        (``single_carry``, ``keep_structure``) takes none: a schedule outside the restriction would
        cap its horizons, and be returned as if it were the restriction's optimum."""
        given = self.kw.pop("incumbent", None)
        if self.restricted:
            if given is not None:
                raise OptionError(f"{self.method}: an incumbent cannot be combined with {self.restricted} (a "
                                  f"schedule outside the restriction would cap its search)")
            return False
        found, exhausted = to_cap(self.instance, given, self.deadline, self.method)
        if found is None:
            return exhausted
        self.stats["incumbent"] = {"method": found.method, "makespan": found.makespan}
        self.fallback = found.ids  # returned if the search ends without a schedule of its own
        if found.makespan <= self.cap or not self.cap_given:
            # a schedule is there to be shortened: the default cap, which bounds a search that
            # may have none, gives way to it (a 3x3 map with two robots and its optimum 36 once
            # ended at the default cap 27, 'feasible' with 79 steps, in 11 s of its 60)
            self.incumbent, self.cap = found.ids, found.makespan
            self.stats["horizon_cap"] = found.makespan
        return False

    def _report(self, last: dict | None = None) -> None:
        if self.progress is not None:
            last = self.stats["horizons"][-1] if last is None else last
            self.progress({"horizon": last["T"], "answer": last["answer"], "time_s": last["time_s"],
                           "elapsed": time.perf_counter() - self.start})

    def result(self, status, ids=None, lower=None) -> Result:
        """The result; a restricted search's proofs (:data:`RESTRICTIONS`) hold for the schedules of
        the restriction only, so they go to ``stats.restricted_lower_bound`` and the instance
        keeps its static bound (``optimal`` then means optimal for ``stats.objective``)."""
        if self.restricted and lower is not None:
            self.stats["restricted_lower_bound"] = lower
            lower = self.bounds.lower
        schedule = None if ids is None else Schedule.from_ids(self.instance, ids, meta={"method": self.method})
        return Result(self.method, status, schedule, lower_bound=lower, stats=self.stats,
                      time_s=time.perf_counter() - self.start)

    def run(self) -> Result:
        inst = self.instance
        if self.bounds.impossible:
            self.stats["reason"] = "; ".join(self.bounds.impossible)
            return self.result("infeasible")
        if goal_violation(inst.world, inst.start_state, inst.goal_tiles, inst.goal_cells, 0) is None:
            self.stats["tiles_traveled_optimal"] = True
            return self.result("optimal", np.zeros((inst.num_robots, 0), dtype=np.int64), lower=0)
        if self._find_incumbent():  # the complete planner's proof: no reachable state is a goal
            self.stats["reason"] = EXHAUSTED
            return self.result("infeasible")
        return self._cpsat() if self.method == "cpsat" else self._sat()

    def open(self, model, threads: int | None = None):
        """A back end for ``model`` with this search's solver and settings."""
        kw = self.kw
        return open_backend(kw.get("solver", "cpsat"), model, self.instance, connectivity=self.options.connectivity,
                            threads=threads or kw.get("threads", 1), seed=kw.get("seed", 0),
                            presolve=kw.get("presolve", False), deadline=self.deadline)

    def solved(self, backend, assumptions=(), **objective):
        """``backend.solve`` until this search's deadline, its cuts counted in ``stats``."""
        outcome = backend.solve(assumptions, self.deadline, **objective)
        self.stats["cuts"] += outcome.cuts
        return outcome

    # ---- CP-SAT: one model per horizon --------------------------------------------------------

    def _cpsat(self) -> Result:
        """Horizons upward from the lower bound; from ``first_horizon`` if given, downward while
        satisfiable (a schedule of ``T`` steps also fits ``T + 1``: infeasible at ``T - 1``
        proves the ones below too)."""
        first = self.kw.get("first_horizon")
        if first is None and self.kw["threads"] >= 2:
            return self._cpsat_lanes()
        lower = max(1, self.bounds.lower)
        T = lower if first is None else min(max(lower, first), self.cap)
        found, proved_below = None, lower  # the smallest satisfiable horizon; no schedule below this
        while T <= self.cap:
            if found is None and self.incumbent is not None and proved_below >= self.incumbent.shape[1]:
                return self._proved_incumbent(proved_below)
            try:
                model = build(self.instance, T, self.options, deadline=self.deadline)
                backend = self.open(model)
            except OutOfTime:
                return self.timeout(proved_below)
            self.stats["horizons"].append({"T": T, **backend.size()})
            began = time.perf_counter()
            outcome = self.solved(backend)
            status = outcome.status
            self.stats["horizons"][-1].update(answer=status, time_s=round(time.perf_counter() - began, 3))
            self._report()
            if status == UNKNOWN:
                return self.timeout(proved_below)
            if status == UNSAT:
                proved_below = T + 1
                if found is not None:
                    break
                T += 1
                continue
            found = (model, backend, outcome)
            self.incumbent = decode(model, self.instance, outcome.value)
            if T <= proved_below:
                break
            T -= 1
        if found is None:
            return self._infeasible()
        model, backend, outcome = found
        self.stats["makespan_s"] = round(time.perf_counter() - self.start, 3)
        ids = self.travel(backend, model, model.T, self.incumbent, outcome.values)
        self.stats["solver"] = backend.stats
        return self.result("optimal", ids, lower=model.T)

    def _proved_incumbent(self, k: int) -> Result:
        """Every horizon below ``k``, the incumbent's makespan, is infeasible: the incumbent is
        optimal. Tiles traveled are then minimized at ``k`` as after any other proof."""
        ids = self.incumbent
        self.stats["tiles_traveled_optimal"] = False
        self.stats["makespan_s"] = round(time.perf_counter() - self.start, 3)
        if self.minimize_travel:
            with self.travel_time():
                try:
                    model = build(self.instance, k, self.options, min_done=None if self.method == "cpsat" else k,
                                  deadline=self.deadline)
                    backend = self.open(model)
                except OutOfTime:
                    return self.result("optimal", ids, lower=k)
                try:
                    ids = self.travel(backend, model, k, ids)
                finally:
                    backend.close()
        return self.result("optimal", ids, lower=k)

    def travel(self, backend, model, k: int, ids, hint=None):
        """``ids``, a schedule of the proved optimal makespan ``k``, or one of as many steps with
        fewer tiles traveled: the motions up to step ``k`` minimized (``done[k]`` assumed where the
        model has it) from ``hint`` (the schedule's assignment, if known), within the minimization's
        time (``travel_time``). ``stats.tiles_traveled_optimal`` says whether the minimum was proved."""
        self.stats["tiles_traveled_optimal"] = False
        if not self.minimize_travel:
            return ids
        steps = {v: t for (_, t), group in model.y.items() for v, _, _ in group}
        motion = [v for v in model.motion if steps[v] <= k]  # done[k] excludes the later ones
        backend.tune(presolve=True)  # CP-SAT: an objective profits from presolve
        with self.travel_time():
            outcome = self.solved(backend, [model.done[k]] if k in model.done else [], objective=Objective(motion),
                                  hint=hint)
        if outcome.values is None:
            return ids  # no better schedule in time: keep this one
        self.stats["tiles_traveled_optimal"] = outcome.status == SAT
        return decode(model, self.instance, outcome.value)[:, :k]

    def _infeasible(self) -> Result:
        """No schedule within the horizon cap: not a proof that none exists (a longer one may),
        so ``unsolved``, with the cap + 1 as the lower bound; ``feasible`` with that bound if an
        incumbent above the cap exists."""
        if self.fallback is not None:
            return self.result("feasible", self.fallback, lower=self.cap + 1)
        which = RESTRICTIONS[self.restricted][1] if self.restricted else "schedule"
        self.stats["failure"] = f"no {which} with a makespan up to the horizon cap {self.cap}"
        return self.result("unsolved", lower=self.cap + 1)


def _restriction(single_carry: bool, keep_structure: bool) -> str | None:
    return "single_carry" if single_carry else "keep_structure" if keep_structure else None


def _parts(parts: dict) -> str:
    return ", ".join(f"{k} {v}" for k, v in parts.items() if v is not None)
