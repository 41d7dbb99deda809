"""The answer: schedules and their files, the validator, metrics, results, and ``solve()``.

``METHODS`` maps a method name to its record (:mod:`.registry`: the planning function
``plan(instance, options, run) -> Result``, its options class, what it plans for and proves); the
command line and the parametrized tests read it. A method's module is imported when the method
is first looked up, and the bounds (scipy) when a solve needs them, so that commands that do not
solve start fast.
"""
from __future__ import annotations

import dataclasses as _dataclasses

from bille.instances import Instance, OptionError
from bille.instances.failure import Failure
from bille.instances.interrupts import cancelling as _cancelling
from bille.instances.metrics import Metrics, metrics
from bille.instances.result import STATUSES, Result
from bille.instances.run import INTERRUPTED, Budget, Events, Run
from bille.instances.schedule import Schedule, bind, dump_schedule, load_schedule, save_schedule, schedule_from_text

from .options import check_options
from .registry import CLASSIC, METHODS
from .validate import Report, validate

__all__ = ["Bounds", "Budget", "CLASSIC", "METHODS", "Metrics", "OptionError", "Report", "Result", "Run", "STATUSES",
           "Schedule", "bind", "dump_schedule", "load_schedule", "lower_bound", "metrics", "save_schedule",
           "schedule_from_text", "solve", "validate"]


_DEFAULT = object()  # time_limit not given: the method's default (its record's time_limit)


def solve(instance: Instance | str, method: str = "auto", progress=None, *, bound: bool = False,
          time_limit: float | None = _DEFAULT, budget: Budget | None = None, on_schedule=None, on_bound=None,
          **options) -> Result:
    """Solve ``instance`` (an :class:`Instance`, or a file's path or a bundled name) with
    ``method`` (a key of :data:`METHODS`; ``auto`` picks one by the instance, :mod:`.auto`).

    ``options`` are the method's (its options class, :mod:`.registry`), checked by type and
    range before anything runs. ``progress``, ``on_schedule`` and ``on_bound`` (callables, or
    None) are the run's events (:class:`~bille.instances.run.Events`): the methods that report
    tell them (anytime: each shorter schedule, each higher bound, progress; the exact methods:
    each horizon decided), and ``progress`` is told the static bound as soon as it is known.

    The static lower bound (:mod:`.bounds`) is computed once, here, where it is used: before the
    methods that search from it (their records say so: auto, the exact and the anytime methods),
    which get the time left; and, with ``bound=True``, after any other method
    (so it does not change the schedule found). Without it the result's ``lower_bound`` is the
    method's own proof, or None. ``time_limit`` (seconds; None: no limit; by default 60 for
    ``auto``, ``cbs`` and ``anytime`` and none for the others) covers the whole call, the bound
    included: past it the bound leaves out its slow part (the routing LP), and a method left no
    time does not run (status ``timeout``). ``budget``, if given, is the run's budget
    (:class:`~bille.instances.run.Budget`: a caller's clock, or its own way to cancel the run);
    the time limit is then a part of it.

    The returned schedule is validated here, once: a schedule that breaks a rule turns the result
    into status ``error`` (with the violation in ``stats``) instead of reaching the user. So does a
    contradiction between proofs: a lower bound above the makespan found, a schedule where a
    static argument proved that none exists, or ``optimal`` makespan without a matching proof.

    Wherever the static bound is computed on an instance that moves tiles, the bounds of the
    classes of schedules (:mod:`.bounds.classes`) are computed too, in the time left, into
    ``stats["class_bounds"]``, and the classes the schedule belongs to into ``stats["classes"]``
    (read from the schedule). They are never the result's ``lower_bound``, which holds for every
    schedule; a schedule of a class shorter than the class's bound is a contradiction too.

    Ctrl-C, in the main thread, cancels the run's budget (:mod:`bille.instances.interrupts`): the
    method stops where it polls its budget, as when time runs out, and the call returns status
    ``interrupted`` with the best schedule and bound found; nothing unwinds through a solver. So
    does a cancel of ``budget`` from elsewhere. A second Ctrl-C (or a ``KeyboardInterrupt`` from
    a callback) unwinds: the result then keeps the last schedule and the best bound the method
    told through the run's events, and the static bound if it was computed.

    >>> from bille.instances import instance_from_text
    >>> inst = instance_from_text("grid: |\\n  TTT\\nmoveset: point\\nrobots: [{at: [0, 0]}]\\nrobot_goals: [[2, 0]]")
    >>> solve(inst, "bfs").metrics.makespan
    2
    """
    instance = _instance(instance)
    if method not in METHODS:
        raise OptionError(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})")
    if instance.collisions == "classic" and method not in CLASSIC:
        raise OptionError(f"instance '{instance.name}' uses classic collisions; {method} plans under the Bill-E "
                          f"rule only (classic: {', '.join(CLASSIC)})")
    whole = Budget() if budget is None else budget
    with _cancelling(whole):  # from here on (the method's libraries are loaded next), Ctrl-C cancels
        record = METHODS[method]
        limit = record.time_limit if time_limit is _DEFAULT else time_limit
        parsed = check_options(method, {**options, "time_limit": limit})
        parsed.check_instance(instance)
        for name, tell in (("on_schedule", on_schedule), ("on_bound", on_bound), ("progress", progress)):
            if tell is not None and not callable(tell):
                raise OptionError(f"{method}: {name} must be a function, got {tell!r}")
        budget = whole.child(limit)
        result, bounds, bound_s = _run(instance, record, parsed, budget, Events(on_schedule, on_bound, progress),
                                       bound)
    if budget.cancelled and result.status in ("feasible", "timeout", "unsolved"):
        result = _dataclasses.replace(result, status="interrupted")
    return _checked(instance, method, result, bounds, bound_s, budget.elapsed(),
                    _raised(None if bounds is None else bounds.classes, result))


def _instance(given) -> Instance:
    """``solve()``'s instance: an :class:`Instance`, or a file's path or a bundled name (read
    here); anything else is a :class:`TypeError` naming what was given."""
    import os

    if isinstance(given, Instance):
        return given
    if isinstance(given, (str, os.PathLike)):
        from bille.instances import InstanceError, load_instance
        from bille.instances.bundled import resolve

        return load_instance(resolve(os.fspath(given), InstanceError))
    raise TypeError(f"solve() takes an Instance, a file's path or a bundled name, not {type(given).__name__}")


def _run(instance: Instance, record, options, budget: Budget, told: Events, bound: bool):
    """The method's result, the static bound with the class bounds (or None) and the seconds they
    took: the body of :func:`solve` under its Ctrl-C handler."""
    method, bounds, bound_s, progress = record.name, None, None, told.on_progress
    kept = _Kept()  # what the method tells is kept here too, in case a KeyboardInterrupt ends it
    events = Events(_both(kept.schedule, told.on_schedule), _both(kept.bound, told.on_bound), progress)
    internal = {}
    try:
        if record.bound:  # the method searches from the bound: first, and it gets the time left
            bounds, bound_s = _static_bound(instance, budget, progress)
            internal["bounds"] = bounds
        before = "computing the lower bound" if record.bound else "before the method ran"
        if budget.cancelled:
            result = Result(method, "interrupted", failure=Failure("interrupted", f"interrupted {before}"))
        elif budget.expired():
            result = Result(method, "timeout", failure=Failure("time-limit", f"the time limit ran out {before}"))
        else:
            result = record(instance, options, Run(budget, events), **internal)
    except KeyboardInterrupt:  # the method let it through: what it told before is kept
        result = kept.result(instance, method)
    if bound and bounds is None and result.status != "interrupted" and not budget.cancelled:
        try:  # after the method, in the time left
            bounds, bound_s = _static_bound(instance, budget, progress)
        except KeyboardInterrupt:
            result = _dataclasses.replace(result, status="interrupted")
    return result, bounds, bound_s


class _Kept:
    """The last schedule and the best bound a method told while it ran."""

    def __init__(self) -> None:
        self.ids, self.lower = None, None

    def schedule(self, found) -> None:
        self.ids = found.ids

    def bound(self, value: int) -> None:
        self.lower = value if self.lower is None else max(self.lower, value)

    def result(self, instance: Instance, method: str) -> Result:
        schedule = None if self.ids is None else Schedule.from_ids(instance, self.ids, meta={"method": method})
        return Result(method, "interrupted", schedule, lower_bound=self.lower, failure=INTERRUPTED)


def _both(first, second):
    if second is None:
        return first

    def tell(value) -> None:
        first(value)
        second(value)
    return tell


def _static_bound(instance: Instance, budget: Budget, progress):
    """The static bound, its slow part left out once ``budget`` expires, with the class bounds in
    its ``classes`` (:mod:`.bounds.classes`; None on a fixed structure, where the bound proves the
    instance infeasible, or when the time is up), and the seconds they took; ``progress`` is
    told the static bound (with the seconds since the run began)."""
    from .bounds import lower_bound
    from .bounds.classes import applies, class_bounds

    began = budget.now()
    bounds = lower_bound(instance, budget=budget)
    if progress is not None:
        progress({"lower": bounds.lower, "best": None, "elapsed": budget.elapsed()})
    if applies(instance) and not bounds.impossible and not budget.expired():
        bounds.classes = class_bounds(instance, budget=budget, unconditional=bounds.lower)
    return bounds, budget.now() - began


def _raised(classes: dict | None, result: Result) -> dict | None:
    """The class bounds raised by what the method proved: its bound for every schedule, and a
    restricted exact search's bound within its class. None after a proof that no schedule
    exists."""
    if classes is None or result.status == "infeasible":
        return None
    from .bounds.classes import ClassBound, nested

    out = {key: c if c.empty else ClassBound(key, max(c.lower, result.lower_bound or 0)) for key, c in classes.items()}
    for key, value in {**result.stats.get("class_lower_bounds", {}), **result.stats.get("class_optima", {})}.items():
        if key in out and not out[key].empty:  # proved by an exact search of the class (anytime's)
            out[key] = ClassBound(key, max(out[key].lower, value))
    key, restricted = result.claim.bounds, result.claim.lower
    if key in out and restricted is not None and not out[key].empty:  # a restricted search's bound
        out[key] = ClassBound(key, max(out[key].lower, restricted))
    return nested(out)


def __getattr__(name: str):
    if name in ("Bounds", "lower_bound"):  # imported on use: scipy is slow to load
        from . import bounds

        return getattr(bounds, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _checked(instance: Instance, method: str, result: Result, bounds, bound_s: float | None, elapsed: float,
             classes: dict | None = None) -> Result:
    """The method's result as solve() returns it: its schedule validated (once), the best lower
    bound known, the class bounds and the schedule's classes, contradictions between proofs
    turned into status ``error``."""
    fields = dict(method=method, status=result.status, schedule=result.schedule, metrics=result.metrics,
                  lower_bound=_lower(result, bounds), time_s=elapsed, stats=dict(result.stats), claim=result.claim,
                  failure=result.failure)
    if bounds is not None:
        fields["stats"].setdefault("bound_parts", bounds.parts)
        fields["stats"]["bound_s"] = round(bound_s, 3)
    if classes is not None:
        fields["stats"]["class_bounds"] = {key: c.to_json() for key, c in classes.items()}
    if result.schedule is not None:
        report = validate(instance, result.schedule)
        if report.valid:
            fields["metrics"] = report.metrics
            if classes is not None:
                from .bounds.classes import classes_of

                fields["stats"]["classes"] = classes_of(instance, result.schedule)
            _contradiction(fields, result, bounds, classes)
        else:
            fields.update(status="error", metrics=None)
            fields["stats"]["violation"] = str(report.violation)
    return Result(**fields)


def _lower(result: Result, bounds) -> int | None:
    """The best lower bound known: the method's proof, or the static bound if computed and
    higher. None for a proof that no schedule exists, and where neither is known."""
    if result.status == "infeasible":
        return None
    if bounds is None:
        return result.lower_bound
    return max(bounds.lower, result.lower_bound or 0)


def _contradiction(fields: dict, result: Result, bounds, classes: dict | None = None) -> None:
    """Turn a result whose proofs contradict its valid schedule into status ``error``."""
    makespan, lower, stats = fields["metrics"].makespan, fields["lower_bound"], fields["stats"]
    why = None
    broken = [key for key in stats.get("classes", ()) if classes[key].empty or classes[key].lower > makespan]
    if bounds is not None and bounds.impossible:
        why = f"a valid schedule of makespan {makespan}, but no schedule should exist: {'; '.join(bounds.impossible)}"
    elif lower is not None and lower > makespan:
        why = f"lower bound {lower} above the makespan {makespan} of a valid schedule"
    elif broken:
        said = classes[broken[0]]
        why = (f"a valid {broken[0]} schedule of makespan {makespan}, but "
               + ("that class should have no schedule" if said.empty else f"the class's lower bound is {said.lower}"))
    elif result.status == "optimal" and result.claim.unconditional and result.lower_bound != makespan:
        why = f"optimal makespan {makespan} claimed with a proof of {result.lower_bound}"
    if why is not None:
        fields["status"] = "error"
        stats["contradiction"] = why

