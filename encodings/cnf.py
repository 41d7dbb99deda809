"""The model as CNF for python-sat: clauses as they are, cardinality groups through pysat's
encodings, solved incrementally with assumptions (``done[k]`` for the makespan). An objective is
minimized by a descent: each assignment found, the next call asks for a lower cost (a totalizer
over the objective's variables, or one literal of a chain), until a call is refuted (the last
assignment is optimal) or time runs out.

Solving runs in conflict budgets and reads the run's budget between them; the solvers that can be
interrupted (all but CaDiCaL) solve in a thread of their own and are interrupted when the budget
expires (its time spent, or Ctrl-C), by the thread that watches it, since one budget can take seconds on a large
model (under an address-space limit that leaves less than ``THREAD_ROOM``, the budgets alone)."""
from __future__ import annotations

from pysat.card import CardEnc, EncType, ITotalizer
from pysat.solvers import Solver

from bille.instances.interrupts import held_back
from bille.instances.limits import address_room
from bille.instances.run import Budget

from . import SAT, UNKNOWN, UNSAT
from .interface import SAT_SOLVERS as SOLVERS
from .interface import THREAD_ROOM, Backend, Objective, Outcome, interruptible
from .model import Model, OutOfTime

BUDGET = 2_000  # conflicts per call between clock checks
CHUNK = 20_000  # clauses loaded between two looks at the budget


class SatBackend(Backend):
    """Solve a :class:`~.model.Model` with a SAT solver of python-sat (:data:`SOLVERS`; default
    CaDiCaL 1.9.5), a :class:`~.interface.Backend`."""

    def __init__(self, model: Model, cuts=None, solver: str = "cadical195", budget: Budget | None = None) -> None:
        super().__init__(model, cuts)
        self.top = model.num_vars
        self.interruptible = not solver.startswith("cadical")
        self.num_clauses = 0
        with held_back():  # the encoders would turn a Ctrl-C into an error of their own
            self.solver = Solver(name=solver)
            try:
                for k in range(0, len(model.clauses), CHUNK):
                    _stop_if_spent(budget)
                    self.add_clauses(model.clauses[k:k + CHUNK])
                groups = [(g, True) for g in model.exactly_one] + [(g, False) for g in model.at_most_one]
                for group, exactly in groups:  # one group's encoding can take a tenth of a second
                    _stop_if_spent(budget)
                    self._card(group, exactly=exactly)
            except OutOfTime:
                self.solver.delete()
                raise
        self._totalizers: dict[tuple, ITotalizer] = {}
        self._stopped = False

    def _card(self, lits: list[int], exactly: bool) -> None:
        if len(lits) <= 6:  # pairwise is smallest here
            clauses = [[-a, -b] for k, a in enumerate(lits) for b in lits[k + 1:]]
        else:
            enc = CardEnc.atmost(lits=lits, bound=1, top_id=self.top, encoding=EncType.seqcounter)
            self.top = max(self.top, enc.nv)
            clauses = enc.clauses
        if exactly:
            clauses = clauses + [list(lits)]
        self.solver.append_formula(clauses)
        self.num_clauses += len(clauses)

    def add_clauses(self, clauses) -> None:
        self.solver.append_formula(clauses)
        self.num_clauses += len(clauses)

    def size(self) -> dict:
        return {"variables": self.top, "clauses": self.num_clauses}

    def stop(self) -> None:
        self._stopped = True

    def close(self) -> None:
        self.solver.delete()

    def solve(self, assumptions=(), budget=None, objective=None, hint=None) -> Outcome:
        """:meth:`.Backend.solve`; an objective by the descent of the module docstring, from
        ``hint`` if given (it must be an assignment of this model under ``assumptions``)."""
        if objective is None:
            return super().solve(assumptions, budget)
        best = None if hint is None else Outcome(SAT, list(hint))
        limit, cuts = objective.at_most, 0
        while True:
            if best is not None:
                cost = objective.cost(best.value)
                if cost == 0:
                    return Outcome(SAT, best.values, cuts)
                limit = cost - 1
            bound = [] if limit is None else self._bound(objective, limit)
            step = super().solve([*assumptions, *bound], budget)
            cuts += step.cuts
            if step.status != SAT:
                status = SAT if step.status == UNSAT and best is not None else step.status
                return Outcome(status, None if best is None else best.values, cuts)
            best = step

    def _bound(self, objective: Objective, cost: int) -> list[int]:
        """Assumption literals meaning "cost at most ``cost``". Off a chain, one literal of a
        totalizer over the objective's literals, built on first use and counting up to ``cost + 1``
        only (its size grows with that count): later bounds of one objective must be lower."""
        if objective.chain:
            return objective.chain_bound(cost)
        lits = tuple(-v for v in objective.lits) if objective.maximize else tuple(objective.lits)
        totalizer = self._totalizers.get(lits)
        if totalizer is None:
            with held_back():
                totalizer = ITotalizer(lits=list(lits), ubound=cost + 1, top_id=self.top)
                self._totalizers[lits] = totalizer
                self.top = totalizer.top_id
                self.add_clauses(totalizer.cnf.clauses)
        return [-totalizer.rhs[cost]]

    def _solve(self, assumptions, budget, objective, hint) -> Outcome:
        start = budget.now()
        self.stats["solves"] += 1
        if self._stopped or budget.expired():
            return Outcome(UNKNOWN)
        try:
            if not self.interruptible or address_room() < THREAD_ROOM:
                return self._budgets(assumptions, budget, False)
            halt = []  # set when the solve is to end, whatever the clock says

            def interrupt() -> None:
                halt.append(True)
                self.solver.interrupt()

            return interruptible(lambda: self._budgets(assumptions, budget, True, halt), interrupt, budget)
        finally:
            if self.interruptible:
                self.solver.clear_interrupt()  # an interrupt that came after the last budget
            self.stats["solve_s"] += budget.now() - start

    def _budgets(self, assumptions, budget, expect_interrupt: bool, halt=()) -> Outcome:
        """Solve in conflict budgets until an answer, the budget's end, or a halt."""
        while True:
            self.solver.conf_budget(BUDGET)
            before = self.solver.accum_stats().get("conflicts", 0)
            with held_back():  # one conflict budget: python-sat's own Ctrl-C handler stays out
                result = self.solver.solve_limited(assumptions=assumptions, expect_interrupt=expect_interrupt)
            self.stats["conflicts"] += self.solver.accum_stats().get("conflicts", 0) - before
            if result is True:
                return Outcome(SAT, self.solver.get_model())
            if result is False:
                return Outcome(UNSAT)
            if halt or self._stopped or budget.expired():
                return Outcome(UNKNOWN)


def _stop_if_spent(budget: Budget | None) -> None:
    if budget is not None and budget.expired():
        raise OutOfTime


__all__ = ["BUDGET", "SOLVERS", "SatBackend", "THREAD_ROOM"]
