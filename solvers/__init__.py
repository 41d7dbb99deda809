"""The answer: schedules and their files, the validator, metrics, results, and ``solve()``.

``METHODS`` maps a method name to its planning function ``plan(instance, **options) -> Result``;
the command line and the parametrized tests read it.
"""
from __future__ import annotations

import inspect
import time

from bille.instances import Instance, OptionError

from .metrics import Metrics, metrics
from .registry import METHODS
from .result import STATUSES, Result
from .schedule import Schedule, bind, dump_schedule, load_schedule, save_schedule, schedule_from_text
from .validate import Report, validate


def solve(instance: Instance, method: str, **options) -> Result:
    """Solve ``instance`` with ``method`` (a key of :data:`METHODS`).

    The returned schedule is validated here: a schedule that breaks a rule turns the result into
    status ``error`` (with the violation in ``stats``) instead of reaching the user.

    >>> from bille.instances import instance_from_text
    >>> inst = instance_from_text("grid: |\\n  TTT\\nmoveset: point\\nrobots: [{at: [0, 0]}]\\nrobot_goals: [[2, 0]]")
    >>> solve(inst, "bfs").metrics.makespan
    2
    """
    if method not in METHODS:
        raise OptionError(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})")
    plan = METHODS[method]
    accepted = inspect.signature(plan).parameters
    for name in options:
        if name not in accepted:
            known = ", ".join(p for p in accepted if p != "instance")
            raise OptionError(f"{method}: unknown option '{name}' (expected one of: {known})")
    start = time.perf_counter()
    result = plan(instance, **options)
    elapsed = time.perf_counter() - start
    fields = dict(method=method, status=result.status, schedule=result.schedule, metrics=result.metrics,
                  lower_bound=result.lower_bound, time_s=elapsed, stats=dict(result.stats))
    if result.schedule is not None:
        report = validate(instance, result.schedule)
        if report.valid:
            fields["metrics"] = report.metrics
        else:
            fields.update(status="error", metrics=None)
            fields["stats"]["violation"] = str(report.violation)
    return Result(**fields)


__all__ = [
    "METHODS", "Metrics", "Report", "Result", "STATUSES", "Schedule", "bind", "dump_schedule",
    "load_schedule", "metrics", "save_schedule", "schedule_from_text", "solve", "validate",
]
