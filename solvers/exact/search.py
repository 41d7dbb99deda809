"""The state of one exact makespan search: its settings (:class:`Job`),
its budget, what it has proved and found (:class:`Search`), and the steps every search ends
with: the result, a timeout, the proof of an incumbent, the minimization of tiles traveled.
The searches themselves are :func:`.horizons.sequential` and :func:`.lanes.parallel`.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable

import numpy as np

from bille.encodings import SAT
from bille.encodings.backend import Backend, Objective, Outcome, open_backend
from bille.encodings.model import Model, Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance
from bille.instances.claim import EVERY, Claim
from bille.instances.failure import Failure, cap
from bille.instances.result import Result
from bille.instances.run import INTERRUPTED, Budget
from bille.instances.schedule import Schedule

# the restrictions of the model (encodings.model.Options): the schedules their optimum is optimal
# among, and what one of their schedules is called
RESTRICTIONS = {
    "single_carry": ("the schedules that carry every tile once", "single-carry schedule"),
    "keep_structure": ("the schedules that pick and place only where the start and the goal differ",
                       "schedule that keeps the structure"),
    "no_scaffold": ("the schedules that never set a tile down where neither the start nor the goal has one",
                    "schedule without scaffold"),
}


def restricted(restriction: str, lower: int | None) -> Claim:
    """The claim of a model under ``restriction`` whose horizons below ``lower`` are refuted; its
    class is the bounds module's of the same name (:mod:`bille.solvers.bounds.classes`)."""
    return Claim(among=RESTRICTIONS[restriction][0], spelled=restriction, bounds=restriction.replace("_", "-"),
                 lower=lower)


@dataclass(frozen=True)
class Job:
    """How one makespan search solves: the model's options, the back end and its settings.

    ``incremental``: one model covers ``chunk`` horizons, each decided under the assumption
    ``done[k]`` (the SAT search, which keeps what it learned within the range); otherwise one
    model per horizon, without ``done`` literals (CP-SAT, whose pruning is tightest at the exact
    horizon)."""

    method: str  # the method's name: cpsat or sat
    solver: str  # the back end: cpsat or a python-sat solver (:func:`~bille.encodings.backend.open_backend`)
    options: Options
    incremental: bool = False
    chunk: int = 1
    threads: int = 1
    seed: int = 0
    presolve: bool = False
    first_horizon: int | None = None
    minimize_travel: bool = True
    travel_time: float | None = None
    restriction: str | None = None  # a key of RESTRICTIONS

    def model(self, instance: Instance, T: int, first: int, budget: Budget) -> Model:
        """The model for horizons ``first`` to ``T`` (``T`` alone when not incremental)."""
        return build(instance, T, self.options, min_done=first if self.incremental else None, budget=budget)

    def open(self, model: Model, instance: Instance, budget: Budget, threads: int | None = None) -> Backend:
        return open_backend(self.solver, model, instance, connectivity=self.options.connectivity,
                            threads=threads or self.threads, seed=self.seed, presolve=self.presolve, budget=budget)


class Search:
    """What one makespan search knows: every horizon below ``proved_below`` is infeasible;
    ``incumbent`` (action ids) is the best schedule within the horizon cap ``cap``, ``fallback``
    one above it; ``stats`` the result's statistics; ``budget`` the search's (narrowed while tiles
    traveled are minimized, :meth:`travel_budget`)."""

    def __init__(self, job: Job, instance: Instance, budget: Budget, bounds, cap: int, progress: Callable | None,
                 start: int | None = None):
        self.job, self.instance, self.budget, self.bounds = job, instance, budget, bounds
        self.cap, self.progress = cap, progress
        # the first horizon: the static bound, or a restricted search's bound on its class
        self.proved_below = max(1, bounds.lower, start or 0)
        self.incumbent: np.ndarray | None = None
        self.fallback: np.ndarray | None = None
        self.stats = {"lower_bound": bounds.lower, "bound_parts": bounds.parts, "horizon_cap": cap,
                      "connectivity": job.options.connectivity, "pruning": job.options.prune_reach, "cuts": 0,
                      "horizons": []}
        self.claim = EVERY if job.restriction is None else restricted(job.restriction, self.proved_below)

    def solve(self, backend: Backend, assumptions=(), **objective) -> Outcome:
        """``backend.solve`` within the budget, its cuts counted in ``stats``."""
        outcome = backend.solve(assumptions, self.budget, **objective)
        self.stats["cuts"] += outcome.cuts
        return outcome

    def record(self, T: int, backend: Backend, answer: str, seconds: float, model_horizon: int | None = None) -> None:
        """Horizon ``T`` decided: a row of ``stats.horizons``, told to ``progress``."""
        row = {"T": T, **({} if model_horizon is None else {"model_horizon": model_horizon}), **backend.size(),
               "answer": answer, "time_s": round(seconds, 3)}
        self.stats["horizons"].append(row)
        self.report(row)

    def report(self, row: dict) -> None:
        if self.progress is not None:
            self.progress({"horizon": row["T"], "answer": row["answer"], "time_s": row["time_s"],
                           "elapsed": self.budget.elapsed()})

    def result(self, status: str, ids=None, lower: int | None = None, failure: Failure | None = None) -> Result:
        """The result; a restricted search's proofs (:data:`RESTRICTIONS`) hold for the schedules of
        the restriction only, so they go to its claim and the instance keeps its static bound
        (``optimal`` then means optimal among the restriction's schedules)."""
        if self.job.restriction and lower is not None:
            self.claim = restricted(self.job.restriction, lower)
            lower = self.bounds.lower
        method = self.job.method
        schedule = None if ids is None else Schedule.from_ids(self.instance, ids, meta={"method": method})
        return Result(method, status, schedule, lower_bound=lower, stats=self.stats, time_s=self.budget.elapsed(),
                      claim=self.claim, failure=failure)

    def timeout(self) -> Result:
        """Time is up: the incumbent if there is one (also one above the horizon cap), with the
        bound proved, else no schedule."""
        best = self.incumbent if self.incumbent is not None else self.fallback
        if best is not None:
            return self.result("feasible", best, lower=self.proved_below)
        return self.result("timeout", lower=self.proved_below, failure=self.budget.why())

    def interrupted(self) -> Result:
        """Stopped by the user: the best schedule so far (the incumbent, else one above the
        horizon cap), if any, with the bound proved."""
        best = self.incumbent if self.incumbent is not None else self.fallback
        return self.result("interrupted", best, lower=self.proved_below, failure=INTERRUPTED)

    def infeasible(self) -> Result:
        """No schedule within the horizon cap: not a proof that none exists (a longer one may),
        so ``unsolved``, with the cap + 1 as the lower bound; ``feasible`` with that bound if an
        incumbent above the cap exists."""
        if self.fallback is not None:
            return self.result("feasible", self.fallback, lower=self.cap + 1)
        which = RESTRICTIONS[self.job.restriction][1] if self.job.restriction else "schedule"
        return self.result("unsolved", lower=self.cap + 1,
                           failure=cap(f"no {which} with a makespan up to the horizon cap {self.cap}"))

    def optimal(self, T: int, model: Model, backend: Backend, outcome: Outcome) -> Result:
        """Horizon ``T`` is satisfiable and every one below it infeasible: the outcome's schedule
        is optimal; tiles traveled are then minimized."""
        self.stats["makespan_s"] = round(self.budget.elapsed(), 3)
        ids = decode(model, self.instance, outcome.value)[:, :T]
        with self.travel_budget():
            ids = self.travel(backend, model, T, ids, outcome.values)
        self.stats["solver"] = backend.stats
        return self.result("optimal", ids, lower=T)

    def proved_incumbent(self) -> Result:
        """Every horizon below the incumbent's makespan is infeasible: the incumbent is optimal.
        Tiles traveled are then minimized at its makespan as after any other proof."""
        k, ids = self.proved_below, self.incumbent
        self.stats["tiles_traveled_optimal"] = False
        self.stats["makespan_s"] = round(self.budget.elapsed(), 3)
        if self.job.minimize_travel:
            with self.travel_budget():
                try:
                    model = self.job.model(self.instance, k, k, self.budget)
                    backend = self.job.open(model, self.instance, self.budget)
                except OutOfTime:
                    backend = None
                if backend is not None:
                    try:
                        ids = self.travel(backend, model, k, ids)
                    finally:
                        backend.close()
        return self.result("optimal", ids, lower=k)

    def travel(self, backend: Backend, model: Model, k: int, ids, hint=None):
        """``ids``, a schedule of the proved optimal makespan ``k``, or one of as many steps with
        fewer tiles traveled: the motions up to step ``k`` minimized (``done[k]`` assumed where the
        model has it) from ``hint`` (the schedule's assignment, if known), within the search's
        budget (the callers narrow it, :meth:`travel_budget`). ``stats.tiles_traveled_optimal``
        says whether the minimum was proved."""
        self.stats["tiles_traveled_optimal"] = False
        if not self.job.minimize_travel:
            return ids
        steps = {v: t for (_, t), group in model.y.items() for v, _, _ in group}
        motion = [v for v in model.motion if steps[v] <= k]  # done[k] excludes the later ones
        backend.tune(presolve=True)  # CP-SAT: an objective profits from presolve
        outcome = self.solve(backend, [model.done[k]] if k in model.done else [], objective=Objective(motion),
                             hint=hint)
        if outcome.values is None:
            return ids  # no better schedule in time: keep this one
        self.stats["tiles_traveled_optimal"] = outcome.status == SAT
        return decode(model, self.instance, outcome.value)[:, :k]

    @contextmanager
    def travel_budget(self):
        """The minimization of tiles traveled runs on a child budget: ``job.travel_time`` seconds,
        by default half the time spent so far (at least 1 s)."""
        full = self.budget
        seconds = self.job.travel_time
        self.budget = full.child(max(1.0, 0.5 * full.elapsed()) if seconds is None else seconds)
        try:
            yield
        finally:
            self.budget = full
