"""The validator: the paper's NP certificate check (Observation 1), under docs/rules.md.

``validate(instance, schedule)`` replays the schedule step by step with the rules of
:mod:`bille.instances.rules` and reports the first violation, or the metrics.
"""
from __future__ import annotations

from dataclasses import dataclass

from bille.instances import Instance
from bille.instances.rules import State, Violation, goal_violation, run
from bille.instances.metrics import Metrics, metrics
from bille.instances.schedule import Schedule, bind


@dataclass(frozen=True)
class Report:
    """Outcome of validation: ``violation`` is None exactly when the schedule is valid; the
    metrics are given for valid schedules only."""

    violation: Violation | None
    metrics: Metrics | None
    final: State | None = None  # the state after the last step (valid schedules)

    @property
    def valid(self) -> bool:
        return self.violation is None

    def to_json(self) -> dict:
        return {
            "valid": self.valid,
            "violation": None if self.violation is None else self.violation.to_json(),
            "metrics": None if self.metrics is None else self.metrics.to_json(),
        }


def validate(instance: Instance, schedule: Schedule) -> Report:
    """Check ``schedule`` against ``instance``.

    Raises :class:`~bille.instances.errors.ScheduleError` when the schedule does not fit the
    instance (robot count, action names); rule violations are reported, not raised.
    """
    ids = bind(instance, schedule)
    state = instance.start_state
    for nxt in run(instance.world, state, ids):
        if isinstance(nxt, Violation):
            return Report(nxt, None)
        state = nxt
    bad = goal_violation(instance.world, state, instance.goal_tiles, instance.goal_cells, schedule.length)
    if bad is not None:
        return Report(bad, None)
    return Report(None, metrics(instance, ids), state)
