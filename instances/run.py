"""The run context: the one thing that carries time, cancellation and news through a solve.

A :class:`Budget` is the time a run (or a part of it) may take, read from one clock, and a cancel
flag shared by every budget made from it: :meth:`Budget.expired` is true once the time is spent
*or* the run is cancelled, so a search that polls its budget stops for both alike and returns
what it holds. A part gets a :meth:`~Budget.child` (a budget of its own, never past its
parent's end) or a :meth:`~Budget.share` (a fraction of what is left). :class:`Events` carries
what a run tells while it runs: a schedule found, a bound proved, progress. :class:`Run` holds
the two; ``solve()`` builds it, every method takes it, and the methods' parts take the budget.

Ctrl-C cancels the run (:func:`bille.instances.interrupts.cancelling`); nothing unwinds through
a solver. The clock is injectable: tests drive a budget with a fake one.

>>> now = [0.0]
>>> budget = Budget(3, clock=lambda: now[0])  # ends at 3
>>> part = budget.child(10)  # never past its parent's end
>>> now[0] = 2.5; budget.left(), part.expired()
(0.5, False)
>>> now[0] = 3.0; part.expired()
True
>>> budget = Budget(clock=lambda: now[0]); budget.left()
inf
>>> budget.share(0.5).cancel(); budget.expired(), budget.left()
(True, 0.0)
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

from .failure import Failure


class _Flag:
    """The cancel flag of one run, shared by its budgets."""

    __slots__ = ("set",)

    def __init__(self) -> None:
        self.set = False


# why a budget stopped a search (:meth:`Budget.why`): the failures a method gives for it
TIME_LIMIT, INTERRUPTED = Failure("time-limit", "time limit"), Failure("interrupted", "interrupted")


class Budget:
    """Seconds a run may take from now (None: no limit), and whether it was cancelled.

    Parameters
    ----------
    seconds : the limit, from the moment the budget is made; None for none.
    clock : a function giving the time in seconds (``time.perf_counter`` unless a test drives it).
    """

    __slots__ = ("clock", "start", "end", "_flag")

    def __init__(self, seconds: float | None = None, *, clock: Callable[[], float] = time.perf_counter,
                 _parent: Budget | None = None) -> None:
        self.clock = clock
        self.start = clock()
        self.end = None if seconds is None else self.start + seconds
        if _parent is not None and _parent.end is not None:
            self.end = _parent.end if self.end is None else min(self.end, _parent.end)
        self._flag = _Flag() if _parent is None else _parent._flag

    def now(self) -> float:
        """The clock's time."""
        return self.clock()

    def elapsed(self) -> float:
        """Seconds since the budget was made."""
        return self.clock() - self.start

    def left(self) -> float:
        """Seconds left: ``inf`` without a limit, 0 once spent or cancelled."""
        if self._flag.set:
            return 0.0
        return math.inf if self.end is None else max(0.0, self.end - self.clock())

    def seconds(self) -> float | None:
        """Seconds left, or None without a limit (for a solver's own time-limit parameter)."""
        left = self.left()
        return None if math.isinf(left) else left

    def expired(self) -> bool:
        """Whether the time is spent or the run cancelled: where a search stops."""
        return self._flag.set or (self.end is not None and self.clock() >= self.end)

    def why(self) -> Failure:
        """Why a search that stopped at its budget stopped: :data:`INTERRUPTED` (cancelled, Ctrl-C)
        or :data:`TIME_LIMIT`; the failure a method gives (``Result.failure``)."""
        return INTERRUPTED if self._flag.set else TIME_LIMIT

    def child(self, seconds: float | None = None) -> Budget:
        """A budget for a part: ``seconds`` from now (None: what is left), never past this one's
        end, cancelled with it."""
        return Budget(seconds, clock=self.clock, _parent=self)

    def share(self, fraction: float) -> Budget:
        """A child budget of ``fraction`` of the time left (no limit stays no limit)."""
        return self.child(None if self.end is None else fraction * self.left())

    def cancel(self) -> None:
        """Cancel the run: this budget, its parent, and every budget made from them expire."""
        self._flag.set = True

    @property
    def cancelled(self) -> bool:
        return self._flag.set

    def __repr__(self) -> str:
        left = self.left()
        return f"Budget({'no limit' if math.isinf(left) else f'{left:.3f} s left'}{', cancelled' * self.cancelled})"


@dataclass(frozen=True)
class Events:
    """What a run tells while it runs; each receiver may be None.

    ``schedule(found)``: a schedule found, better than the last; ``bound(value)``: a lower bound
    proved; ``progress(info)``: a dict with ``lower``, ``best`` and ``elapsed`` at least."""

    on_schedule: Callable[[Any], None] | None = None
    on_bound: Callable[[int], None] | None = None
    on_progress: Callable[[dict], None] | None = None

    def schedule(self, found) -> None:
        if self.on_schedule is not None:
            self.on_schedule(found)

    def bound(self, value: int) -> None:
        if self.on_bound is not None:
            self.on_bound(value)

    def progress(self, info: dict) -> None:
        if self.on_progress is not None:
            self.on_progress(info)


@dataclass(frozen=True)
class Run:
    """One run's context: its budget (by default one without a limit, started when the run is
    made) and its events (module docstring)."""

    budget: Budget = field(default_factory=Budget)
    events: Events = Events()

    @classmethod
    def limited(cls, seconds: float) -> Run:
        """A run of ``seconds`` on the real clock, telling no one."""
        return cls(Budget(seconds))

    def part(self, budget: Budget) -> Run:
        """The same run with a part's budget."""
        return Run(budget, self.events)


__all__ = ["INTERRUPTED", "TIME_LIMIT", "Budget", "Events", "Run"]
