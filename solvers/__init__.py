"""The answer: schedules and their files, the validator, metrics, results, and ``solve()``.

``METHODS`` maps a method name to its planning function ``plan(instance, **options) -> Result``;
the command line and the parametrized tests read it. A method's module is imported when the method
is first looked up, and the bounds (scipy) when a solve needs them, so that commands that do not
solve start fast.
"""
from __future__ import annotations

import inspect as _inspect
import time as _time

from bille.instances import Instance, OptionError
from bille.instances.metrics import Metrics, metrics
from bille.instances.result import STATUSES, Result
from bille.instances.schedule import Schedule, bind, dump_schedule, load_schedule, save_schedule, schedule_from_text

from .options import check_options
from .registry import CLASSIC, METHODS
from .validate import Report, validate

__all__ = ["Bounds", "CLASSIC", "METHODS", "Metrics", "OptionError", "Report", "Result", "STATUSES", "Schedule", "bind",
           "dump_schedule", "load_schedule", "lower_bound", "metrics", "save_schedule", "schedule_from_text", "solve",
           "validate"]


def solve(instance: Instance, method: str, progress=None, **options) -> Result:
    """Solve ``instance`` with ``method`` (a key of :data:`METHODS`).

    Options are checked by type and range first (:mod:`.options`). ``progress``, a callable, is
    handed to the methods that report progress (``anytime``; see its docstring). The static lower bound
    (:mod:`.bounds`) is computed once, here, and handed to the methods that search from it. The
    returned schedule is validated here: a schedule that breaks a rule turns the result into
    status ``error`` (with the violation in ``stats``) instead of reaching the user. So does a
    contradiction between proofs: a lower bound above the makespan found, a schedule where a
    static argument proved that none exists, or ``optimal`` makespan without a matching proof.

    >>> from bille.instances import instance_from_text
    >>> inst = instance_from_text("grid: |\\n  TTT\\nmoveset: point\\nrobots: [{at: [0, 0]}]\\nrobot_goals: [[2, 0]]")
    >>> solve(inst, "bfs").metrics.makespan
    2
    """
    if method not in METHODS:
        raise OptionError(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})")
    plan = METHODS[method]
    if instance.collisions == "classic" and method not in CLASSIC:
        raise OptionError(f"instance '{instance.name}' uses classic collisions; {method} plans under the Bill-E "
                          f"rule only (classic: {', '.join(CLASSIC)})")
    options = check_options(method, plan, options, internal=("bounds", "progress"))
    from .bounds import lower_bound

    start = _time.perf_counter()
    bounds = lower_bound(instance)
    accepted = _inspect.signature(plan).parameters
    if "bounds" in accepted:
        options["bounds"] = bounds
    if progress is not None and "progress" in accepted:
        options["progress"] = progress
    result = plan(instance, **options)
    elapsed = _time.perf_counter() - start
    fields = dict(method=method, status=result.status, schedule=result.schedule, metrics=result.metrics,
                  lower_bound=_lower(result, bounds), time_s=elapsed, stats=dict(result.stats))
    fields["stats"].setdefault("bound_parts", bounds.parts)
    if result.schedule is not None:
        report = validate(instance, result.schedule)
        if report.valid:
            fields["metrics"] = report.metrics
            _contradiction(fields, result, bounds)
        else:
            fields.update(status="error", metrics=None)
            fields["stats"]["violation"] = str(report.violation)
    return Result(**fields)


def __getattr__(name: str):
    if name in ("Bounds", "lower_bound"):  # imported on use: scipy is slow to load
        from . import bounds

        return getattr(bounds, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _lower(result: Result, bounds) -> int | None:
    """The best lower bound known: the static one, or the method's proof if higher. None for a
    proof that no schedule exists."""
    if result.status == "infeasible":
        return None
    return max(bounds.lower, result.lower_bound or 0)


def _contradiction(fields: dict, result: Result, bounds) -> None:
    """Turn a result whose proofs contradict its valid schedule into status ``error``."""
    makespan, lower, stats = fields["metrics"].makespan, fields["lower_bound"], fields["stats"]
    why = None
    if bounds.impossible:
        why = f"a valid schedule of makespan {makespan}, but no schedule should exist: {'; '.join(bounds.impossible)}"
    elif lower is not None and lower > makespan:
        why = f"lower bound {lower} above the makespan {makespan} of a valid schedule"
    elif result.status == "optimal" and "objective" not in stats and result.lower_bound != makespan:
        why = f"optimal makespan {makespan} claimed with a proof of {result.lower_bound}"
    if why is not None:
        fields["status"] = "error"
        stats["contradiction"] = why

