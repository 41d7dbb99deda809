"""The interface of the solvers of a :class:`~.model.Model` (CP-SAT, :mod:`.cpsat`; the SAT
solvers of python-sat, :mod:`.cnf`), each a :class:`Backend` opened by
:func:`~.backend.open_backend`.

Each :meth:`Backend.solve` call takes assumptions (literals that hold for this call only), a
budget (:class:`~bille.instances.run.Budget`) and an optional :class:`Objective`, and answers an :class:`Outcome`: a status, the
assignment if one was found, and the connectivity cuts the call added. Clauses may be added
between calls; what a solver learned stays with it.

Every assignment a back end returns keeps the tiles connected at every step: where the model
leaves connectivity to cuts (``lazy``, ``cuts``), a solution that breaks it adds the cuts the
back end was opened with and the solver goes on, in :meth:`Backend.solve`, the one place that
loop is written. A model with the eager encoding is checked all the same (it never needs a cut).

A solver's call runs in a thread of its own (:func:`interruptible`) while the caller watches the
budget: when it expires (its time spent, or the run cancelled by Ctrl-C) the solver is stopped
through its own interface and the call answers ``unknown``. CaDiCaL holds Python's lock while it
solves and cannot be interrupted; it runs in conflict budgets, and the budget is read between
two of them.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass, field, replace
from typing import Callable, Sequence

from bille.instances.interrupts import quiet_thread
from bille.instances.limits import address_room
from bille.instances.run import Budget

from .model import Model

# python-sat's incremental solvers that take assumptions and conflict budgets
SAT_SOLVERS = ("cadical195", "cadical153", "cadical103", "glucose42", "glucose4", "glucose3", "gluecard4",
               "gluecard3", "maplechrono", "maplecm", "maplesat", "mergesat3", "minicard", "minisat22")
SOLVERS = ("cpsat",) + SAT_SOLVERS  # every name open_backend takes
# address space a new thread needs (its stack, and the malloc arena glibc gives it): with less
# room under an address-space limit, starting one can fail, or hang in ``Thread.start`` when the
# new thread dies before it says it has started
THREAD_ROOM = 1 << 30
WATCH_S = 0.05  # seconds between two looks at the budget while a solver runs: how late a Ctrl-C is heard


@dataclass(frozen=True)
class Objective:
    """Minimize how many of the variables ``lits`` are true (``maximize``: maximize it).

    The *cost* is what is minimized: the number of true variables, or with ``maximize`` of false
    ones. ``at_most``: only assignments of at most that cost count. ``chain``: the variables are
    ordered so that a true one makes every later one true (``done[1..L]``); a bound on the cost is
    then one of them, and a SAT back end needs no counter."""

    lits: Sequence[int]
    maximize: bool = False
    chain: bool = False
    at_most: int | None = None

    def cost(self, value: Callable[[int], bool]) -> int:
        if self.chain:  # the first true variable says how many are, whatever the later ones say
            true = len(self.lits) - next((k for k, v in enumerate(self.lits) if value(v)), len(self.lits))
        else:
            true = sum(1 for v in self.lits if value(v))
        return len(self.lits) - true if self.maximize else true

    def chain_bound(self, cost: int) -> list[int]:
        """The literals that say "cost at most ``cost``" of a chain."""
        if self.maximize:  # a true one among the first cost + 1
            return [self.lits[cost]]
        return [-v for v in self.lits[:len(self.lits) - cost]]  # none true before the last ``cost``


@dataclass(frozen=True)
class Outcome:
    """A back end's answer. ``status``: ``sat`` (an assignment; with an objective, proved
    optimal), ``unsat`` (none exists), ``unknown`` (time ran out or the search was stopped; with
    an objective, ``values`` may still hold the best assignment found). ``cuts``: connectivity
    cuts added on the way."""

    status: str
    values: list[int] | None = field(default=None, repr=False)
    cuts: int = 0

    def value(self, v: int) -> bool:
        """Whether variable ``v`` (a negative literal: its negation) is true."""
        return self.values[v - 1] > 0 if v > 0 else not self.values[-v - 1] > 0


class Backend:
    """A solver loaded with a model. Subclasses give :meth:`_solve` (one call of the solver),
    :meth:`add_clauses`, :meth:`stop` and :meth:`size`; ``stats`` adds up ``conflicts``,
    ``solves`` and ``solve_s`` over the calls."""

    def __init__(self, model: Model, cuts: Callable | None = None) -> None:
        self.model, self._cuts = model, cuts
        self.stats = {"conflicts": 0, "solves": 0, "solve_s": 0.0}

    def solve(self, assumptions: Sequence[int] = (), budget: Budget | None = None,
              objective: Objective | None = None, hint: list[int] | None = None) -> Outcome:
        """Solve under ``assumptions`` until ``budget`` expires (None: no limit), optimizing ``objective`` if given; ``hint``: an assignment of this model to
        start from (an earlier outcome's ``values``). Adds connectivity cuts until the
        assignment keeps the tiles connected (module docstring)."""
        cuts, budget = 0, budget or Budget()
        while True:
            outcome = self._solve(list(assumptions), budget, objective, hint)
            if outcome.values is None or self._cuts is None:
                break
            found = self._cuts(outcome.value)
            if not found:
                break
            self.add_clauses(found)
            cuts += len(found)
        return replace(outcome, cuts=outcome.cuts + cuts)

    def _solve(self, assumptions: list[int], budget: Budget, objective: Objective | None,
               hint: list[int] | None) -> Outcome:
        raise NotImplementedError

    def add_clauses(self, clauses) -> None:
        raise NotImplementedError

    def stop(self) -> None:
        """End a solve running in another thread (it answers ``unknown``), and every later one."""
        raise NotImplementedError

    def size(self) -> dict:
        """The size of what the solver holds (variables, clauses, ...)."""
        raise NotImplementedError

    def tune(self, threads: int | None = None, presolve: bool | None = None) -> None:
        """Worker threads and presolve for the next calls, where the solver has them (CP-SAT)."""

    def close(self) -> None:
        """Free the solver."""

    def __enter__(self) -> Backend:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def interruptible(work: Callable[[], Outcome], interrupt: Callable[[], None], budget: Budget) -> Outcome:
    """``work()``, a solver's call, run in a thread of its own while this one watches ``budget``
    (Python runs signal handlers in the main thread only, and only between bytecodes, never inside
    a solver's C++ call). ``interrupt`` ends the work early when the budget expires (its time
    spent or the run cancelled; the work answers as it does when interrupted), and on a
    ``KeyboardInterrupt`` (the work is waited for and the interrupt goes on). With too little
    address space for a thread (:data:`THREAD_ROOM`), the work runs in this thread."""
    if address_room() < THREAD_ROOM:
        return work()
    box: dict = {}
    done = threading.Event()

    def run() -> None:
        quiet_thread()  # a Ctrl-C goes to the waiting thread, never to a solver's own handler here
        try:
            box["outcome"] = work()
        except BaseException as error:  # handed to the waiting thread
            box["error"] = error
        finally:
            done.set()

    thread = threading.Thread(target=run, name="solver", daemon=True)
    thread.start()
    try:
        while not done.wait(min(WATCH_S, budget.left())):
            if budget.expired():
                interrupt()
                while not done.wait(WATCH_S):  # again until it ends: a stop may land before the solve began
                    interrupt()
    except BaseException:
        interrupt()
        thread.join()
        raise
    thread.join()
    if "error" in box:
        raise box["error"]
    return box["outcome"]


__all__ = ["Backend", "Objective", "Outcome", "SAT_SOLVERS", "SOLVERS", "THREAD_ROOM", "interruptible"]
