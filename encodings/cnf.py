"""The model as CNF for python-sat: clauses as they are, cardinality groups through pysat's
encodings, solved incrementally with assumptions (``done[k]`` for the makespan, a totalizer for
tiles traveled). Solving runs in conflict budgets and checks the clock between them; the solvers
that can be interrupted (all but CaDiCaL) are also interrupted at the deadline by a timer, since
one budget can take seconds on a large model (under an address-space limit that leaves less than
``THREAD_ROOM``, the budgets alone)."""
from __future__ import annotations

import threading
import time

from pysat.card import CardEnc, EncType, ITotalizer
from pysat.solvers import Solver

from bille.instances.limits import address_room

from . import SAT, UNKNOWN, UNSAT
from .model import Model

BUDGET = 2_000  # conflicts per call between clock checks
# address space a timer thread needs (its stack, and the malloc arena glibc gives a new thread):
# with less room under an address-space limit, starting one can fail, or hang in
# ``Thread.start`` when the new thread dies before it says it has started
THREAD_ROOM = 1 << 30
# python-sat's incremental solvers that take assumptions and conflict budgets
SOLVERS = ("cadical195", "cadical153", "cadical103", "glucose42", "glucose4", "glucose3", "gluecard4",
           "gluecard3", "maplechrono", "maplecm", "maplesat", "mergesat3", "minicard", "minisat22")


class SatBackend:
    """Solve a :class:`~.model.Model` with a SAT solver of python-sat (default CaDiCaL 1.9.5)."""

    def __init__(self, model: Model, solver: str = "cadical195") -> None:
        self.model = model
        self.top = model.num_vars
        self.solver = Solver(name=solver)
        self.interruptible = not solver.startswith("cadical")
        self.solver.append_formula(model.clauses)
        self.num_clauses = len(model.clauses)
        for group in model.exactly_one:
            self._card(group, exactly=True)
        for group in model.at_most_one:
            self._card(group, exactly=False)
        self.values: list[int] | None = None
        self.totalizer: ITotalizer | None = None
        self.stats = {"conflicts": 0, "solves": 0, "solve_s": 0.0}

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

    def at_most(self, lits: list[int], bound: int) -> int:
        """An assumption literal meaning "at most ``bound`` of ``lits`` are true".

        A totalizer over ``lits`` is built on first use, counting up to ``bound + 1`` only (its
        size grows with that count), so later calls must ask for smaller bounds."""
        if self.totalizer is None:
            self.totalizer = ITotalizer(lits=lits, ubound=bound + 1, top_id=self.top)
            self.top = self.totalizer.top_id
            self.add_clauses(self.totalizer.cnf.clauses)
        return -self.totalizer.rhs[bound]

    def solve(self, assumptions: list[int], deadline: float | None) -> str:
        start = time.perf_counter()
        self.stats["solves"] += 1
        if deadline is not None and start > deadline:
            return UNKNOWN
        timer = None
        if deadline is not None and self.interruptible and address_room() >= THREAD_ROOM:
            timer = threading.Timer(deadline - start, self.solver.interrupt)
            timer.start()
        try:
            while True:
                self.solver.conf_budget(BUDGET)
                before = self.solver.accum_stats().get("conflicts", 0)
                result = self.solver.solve_limited(assumptions=assumptions, expect_interrupt=timer is not None)
                self.stats["conflicts"] += self.solver.accum_stats().get("conflicts", 0) - before
                if result is True:
                    self.values = self.solver.get_model()
                    return SAT
                if result is False:
                    self.values = None
                    return UNSAT
                if deadline is not None and time.perf_counter() > deadline:
                    return UNKNOWN
        finally:
            if timer is not None:
                timer.cancel()
                timer.join()
                self.solver.clear_interrupt()
            self.stats["solve_s"] += time.perf_counter() - start

    def value(self, v: int) -> bool:
        return self.values[v - 1] > 0

    def delete(self) -> None:
        self.solver.delete()
