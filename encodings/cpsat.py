"""The model in OR-Tools CP-SAT, written straight into the model proto: variable ``v`` of the
model is CP-SAT variable ``v - 1``, its negation the CP-SAT literal ``-v``; clauses become
``bool_or``, cardinality groups ``exactly_one`` / ``at_most_one``. Assumptions and an
objective's bound are constraints of one call (unit ``bool_or``, a linear constraint), added to
a copy of the model; an objective is CP-SAT's own."""
from __future__ import annotations

from ortools.sat.python import cp_model

from bille.instances.run import Budget

from . import SAT, UNKNOWN, UNSAT
from .interface import Backend, Objective, Outcome, interruptible
from .model import Model, OutOfTime


def _lits(clause) -> list[int]:
    return [l - 1 if l > 0 else l for l in clause]


class CpSatBackend(Backend):
    """Solve a :class:`~.model.Model` with CP-SAT (:class:`~.interface.Backend`)."""

    def __init__(self, model: Model, cuts=None, threads: int = 1, seed: int = 0, presolve: bool = False,
                 budget: Budget | None = None) -> None:
        super().__init__(model, cuts)
        self.threads, self.seed, self.presolve = threads, seed, presolve
        self.cp = cp_model.CpModel()
        proto = self.cp.proto
        for _ in range(model.num_vars):
            proto.variables.add().domain.extend((0, 1))
        self._add(model.clauses, budget)
        for group in model.exactly_one:
            proto.constraints.add().exactly_one.literals.extend(_lits(group))
        for group in model.at_most_one:
            proto.constraints.add().at_most_one.literals.extend(_lits(group))
        self._solver: cp_model.CpSolver | None = None
        self._stopped = False

    def add_clauses(self, clauses) -> None:
        self._add(clauses, None)

    def _add(self, clauses, budget: Budget | None) -> None:
        constraints = self.cp.proto.constraints
        for k, c in enumerate(clauses):
            constraints.add().bool_or.literals.extend(_lits(c))
            if budget is not None and k % 20_000 == 0 and budget.expired():
                raise OutOfTime

    def size(self) -> dict:
        return self.model.size()

    def tune(self, threads: int | None = None, presolve: bool | None = None) -> None:
        if threads is not None:
            self.threads = threads
        if presolve is not None:
            self.presolve = presolve

    def _solve(self, assumptions, budget, objective, hint) -> Outcome:
        proto = self.cp.proto
        proto.clear_objective()
        proto.clear_solution_hint()
        if objective is not None:
            proto.objective.vars.extend([v - 1 for v in objective.lits])
            proto.objective.coeffs.extend([-1 if objective.maximize else 1] * len(objective.lits))
        if hint is not None:
            proto.solution_hint.vars.extend(list(range(len(hint))))
            proto.solution_hint.values.extend([int(x) for x in hint])
        cp = self.cp
        if assumptions or (objective is not None and objective.at_most is not None):
            cp = cp_model.CpModel()  # the call's own constraints go to a copy
            cp.proto.copy_from(proto)
            for lit in assumptions:
                cp.proto.constraints.add().bool_or.literals.append(_lits([lit])[0])
            if objective is not None and objective.at_most is not None:
                _bound(cp.proto, objective)
        return self._run(cp, budget, objective)

    def _run(self, cp: cp_model.CpModel, budget: Budget, objective: Objective | None) -> Outcome:
        solver = cp_model.CpSolver()
        self._solver = solver
        if self._stopped:
            return Outcome(UNKNOWN)
        solver.parameters.num_workers = self.threads
        solver.parameters.random_seed = self.seed
        solver.parameters.cp_model_presolve = self.presolve
        # Ctrl-C is Python's to hear (:func:`~.interface.interruptible`): CP-SAT's own handler would
        # end the search as if time had run out, and leave no handler behind it in Python
        solver.parameters.catch_sigint_signal = False
        seconds = budget.seconds()
        if seconds is not None:
            solver.parameters.max_time_in_seconds = max(0.01, seconds)
        start = budget.now()
        status = interruptible(lambda: solver.solve(cp), solver.stop_search, budget)
        self.stats["solves"] += 1
        self.stats["conflicts"] += int(solver.num_conflicts)
        self.stats["solve_s"] += budget.now() - start
        if status in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            proven = status == cp_model.OPTIMAL or objective is None
            return Outcome(SAT if proven else UNKNOWN, list(solver.response_proto.solution))
        return Outcome(UNSAT if status == cp_model.INFEASIBLE else UNKNOWN)

    def stop(self) -> None:
        self._stopped = True
        if self._solver is not None:
            self._solver.stop_search()


def _bound(proto, objective: Objective) -> None:
    """The objective's ``at_most`` as a constraint."""
    if objective.chain:
        for lit in _lits(objective.chain_bound(objective.at_most)):
            proto.constraints.add().bool_or.literals.append(lit)
        return
    n = len(objective.lits)
    linear = proto.constraints.add().linear
    linear.vars.extend([v - 1 for v in objective.lits])
    linear.coeffs.extend([1] * n)
    linear.domain.extend((n - objective.at_most, n) if objective.maximize else (0, objective.at_most))
