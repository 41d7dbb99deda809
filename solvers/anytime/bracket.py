"""The optimal makespan bracketed: the best valid schedule found so far (an upper bound) and the
highest lower bound proved, as an anytime search holds them. The parts of the search offer
schedules and prove bounds here; whoever wants to know (the command line's live line, a sweep,
a test, the pipe of a child process) subscribes to ``on_schedule`` and ``on_bound``. A callback
may raise ``KeyboardInterrupt`` to stop the search: it then ends with what it holds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from bille.instances.run import Budget

from ..incumbent import Incumbent


@dataclass
class Bracket:
    """``lower`` <= the optimal makespan <= ``best.makespan``. ``improvements`` and
    ``lower_bounds`` list ``[seconds since start, value]`` of every change, read from ``budget``
    (the run's; by default one without a limit, started with the bracket)."""

    lower: int
    budget: Budget = field(default_factory=Budget)
    best: Incumbent | None = None
    improvements: list = field(default_factory=list)
    lower_bounds: list = field(default_factory=list)
    on_schedule: list[Callable[[Incumbent], None]] = field(default_factory=list)
    on_bound: list[Callable[[int], None]] = field(default_factory=list)

    @property
    def closed(self) -> bool:
        """Whether the best schedule is proved optimal."""
        return self.best is not None and self.lower >= self.best.makespan

    def elapsed(self) -> float:
        return self.budget.elapsed()

    def offer(self, found: Incumbent) -> bool:
        """Keep ``found`` (a validated schedule) if it is shorter than the best; whether it was."""
        if self.best is not None and found.makespan >= self.best.makespan:
            return False
        self.best = found
        self.improvements.append([round(self.elapsed(), 3), found.makespan])
        for tell in self.on_schedule:
            tell(found)
        return True

    def prove(self, value: int) -> bool:
        """Raise the lower bound to ``value`` (proved: no schedule is shorter) if it is higher."""
        if value <= self.lower:
            return False
        self.lower = value
        self.lower_bounds.append([round(self.elapsed(), 3), value])
        for tell in self.on_bound:
            tell(value)
        return True
