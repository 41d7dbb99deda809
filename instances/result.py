"""What every solver returns (docs/decisions.md, "The solve() contract")."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .claim import EVERY, Claim
from .counters import Counters
from .failure import Failure
from .metrics import Metrics
from .schedule import Schedule

STATUSES = ("optimal", "feasible", "infeasible", "timeout", "unsolved", "interrupted", "error")


@dataclass(frozen=True)
class Result:
    """A solver's answer.

    ``status`` (docs/decisions.md, "The solve() contract"):
    ``optimal`` (schedule with proof of its ``claim``: the makespan over every schedule,
    unless the claim names another objective or fewer schedules), ``feasible`` (schedule, no proof),
    ``infeasible`` (proof that no schedule exists at all), ``timeout`` (the time limit ended the
    run, no schedule), ``unsolved`` (the method gave up before its time limit, no schedule, never
    a proof: the reason in ``failure``), ``interrupted`` (the user stopped it: the best
    schedule found so far, if any, and the best bound proved are kept), ``error`` (the method
    failed, or its proofs contradict its schedule; see ``stats``). ``lower_bound``: the best
    proved lower bound on the makespan over every schedule (None with ``infeasible``, and where
    none was computed). ``claim`` (:class:`~bille.instances.claim.Claim`): what the proofs are
    about, with the bound proved over fewer schedules or of another objective. ``failure``
    (:class:`~bille.instances.failure.Failure`): why a run without its answer ended (its
    time limit, Ctrl-C, a cap, a heuristic stuck, ...), None otherwise.
    """

    method: str
    status: str
    schedule: Schedule | None = None
    metrics: Metrics | None = None
    lower_bound: int | None = None
    time_s: float = 0.0
    stats: dict[str, Any] = field(default_factory=dict, hash=False)
    claim: Claim = EVERY
    failure: Failure | None = None

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"unknown status {self.status!r} (expected one of {STATUSES})")

    @property
    def counters(self) -> Counters:
        """The counts in ``stats`` that tools read, typed (:class:`~bille.instances.counters.Counters`)."""
        return Counters.of(self.stats)

    def to_json(self) -> dict:
        return {
            "method": self.method,
            "status": self.status,
            "metrics": None if self.metrics is None else self.metrics.to_json(),
            "lower_bound": self.lower_bound,
            "time_s": round(self.time_s, 6),
            "claim": self.claim.to_json(),
            "failure": None if self.failure is None else self.failure.to_json(),
            "stats": self.stats,
        }
