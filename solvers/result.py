"""What every solver returns (DESIGN §5)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .metrics import Metrics
from .schedule import Schedule

STATUSES = ("optimal", "feasible", "infeasible", "timeout", "error")


@dataclass(frozen=True)
class Result:
    """A solver's answer.

    ``status``: ``optimal`` (schedule with proof), ``feasible`` (schedule, no proof),
    ``infeasible`` (proof that none exists within the method's bounds), ``timeout`` (the limit
    was hit; a schedule may still be present), ``error`` (the method failed; see ``stats``).
    """

    method: str
    status: str
    schedule: Schedule | None = None
    metrics: Metrics | None = None
    lower_bound: int | None = None
    time_s: float = 0.0
    stats: dict[str, Any] = field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"unknown status {self.status!r} (expected one of {STATUSES})")

    def to_json(self) -> dict:
        return {
            "method": self.method,
            "status": self.status,
            "metrics": None if self.metrics is None else self.metrics.to_json(),
            "lower_bound": self.lower_bound,
            "time_s": round(self.time_s, 6),
            "stats": self.stats,
        }
