"""The model in OR-Tools CP-SAT, written straight into the model proto: variable ``v`` of the
model is CP-SAT variable ``v - 1``, its negation the CP-SAT literal ``-v``; clauses become
``bool_or``, cardinality groups ``exactly_one`` / ``at_most_one``."""
from __future__ import annotations

import time

from ortools.sat.python import cp_model

from . import SAT, UNKNOWN, UNSAT
from .model import Model, OutOfTime


def _lits(clause) -> list[int]:
    return [l - 1 if l > 0 else l for l in clause]


class CpSatBackend:
    """Solve a :class:`~.model.Model` with CP-SAT; clauses (lazy cuts) can be added between solves."""

    def __init__(self, model: Model, threads: int = 1, seed: int = 0, deadline: float | None = None,
                 presolve: bool = True) -> None:
        self.model, self.threads, self.seed, self.presolve = model, threads, seed, presolve
        self.cp = cp_model.CpModel()
        proto = self.cp.proto
        for _ in range(model.num_vars):
            proto.variables.add().domain.extend((0, 1))
        self.add_clauses(model.clauses, deadline)
        for group in model.exactly_one:
            proto.constraints.add().exactly_one.literals.extend(_lits(group))
        for group in model.at_most_one:
            proto.constraints.add().at_most_one.literals.extend(_lits(group))
        self.values: list[int] | None = None
        self.stats = {"conflicts": 0, "solves": 0, "solve_s": 0.0}
        self._solver: cp_model.CpSolver | None = None
        self._stopped = False

    def add_clauses(self, clauses, deadline: float | None = None) -> None:
        constraints = self.cp.proto.constraints
        for k, c in enumerate(clauses):
            constraints.add().bool_or.literals.extend(_lits(c))
            if deadline is not None and k % 20_000 == 0 and time.perf_counter() > deadline:
                raise OutOfTime

    def solve(self, time_limit: float | None, minimize: list[int] | None = None,
              hint: list[int] | None = None, presolve: bool | None = None, maximize: bool = False) -> str:
        """``sat`` (proved optimal when minimizing), ``unsat`` or ``unknown``; a solution found
        without proof of its optimum also returns ``unknown``, with :attr:`values` set.
        ``minimize`` lists the variables whose count is minimized (``maximize``: maximized).
        ``presolve`` overrides the backend's setting for this call."""
        proto = self.cp.proto
        if minimize is not None:
            proto.clear_objective()
            proto.objective.vars.extend([v - 1 for v in minimize])
            proto.objective.coeffs.extend([-1 if maximize else 1] * len(minimize))
        if hint is not None:
            proto.clear_solution_hint()
            proto.solution_hint.vars.extend(list(range(len(hint))))
            proto.solution_hint.values.extend([int(x) for x in hint])
        solver = cp_model.CpSolver()
        self._solver = solver
        if self._stopped:
            return UNKNOWN
        solver.parameters.num_workers = self.threads
        solver.parameters.random_seed = self.seed
        solver.parameters.cp_model_presolve = self.presolve if presolve is None else presolve
        if time_limit is not None:
            solver.parameters.max_time_in_seconds = max(0.01, time_limit)
        start = time.perf_counter()
        status = solver.solve(self.cp)
        self.stats["solves"] += 1
        self.stats["conflicts"] += int(solver.num_conflicts)
        self.stats["solve_s"] += time.perf_counter() - start
        if status in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            self.values = list(solver.response_proto.solution)
            proven = status == cp_model.OPTIMAL or minimize is None
            return SAT if proven else UNKNOWN
        self.values = None
        return UNSAT if status == cp_model.INFEASIBLE else UNKNOWN

    def stop(self) -> None:
        """Stop a solve running in another thread (it returns ``unknown``), and any later one."""
        self._stopped = True
        if self._solver is not None:
            self._solver.stop_search()

    def value(self, v: int) -> bool:
        return self.values[v - 1] > 0
