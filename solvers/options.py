"""Every method's options checked in one place: :func:`check_options`.

A method's options are a frozen record of its own (its record's ``options()`` class, a
:class:`~bille.instances.options.MethodOptions`): each field typed, defaulted and ranged, checked
when the record is built, with what is particular to the method (a combination of options) in
its ``check``. Every method also takes ``time_limit``, a positive number of seconds or None:
``solve()`` turns it into the run's budget (the planning functions take the run, never a number
of seconds). ``solve()``, ``bille gap`` and sweep files check through here.
"""
from __future__ import annotations

from typing import Any

from bille.instances import OptionError
from bille.instances.options import MethodOptions, check_value

from .registry import METHODS


def check_options(method: str, given: dict[str, Any]) -> MethodOptions:
    """``method``'s options record from ``given`` (names and values; ``time_limit`` is checked and
    left out), or one :class:`OptionError` naming the method, the option and what was expected."""
    if method not in METHODS:
        raise OptionError(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})")
    given, record = dict(given), METHODS[method]
    if "time_limit" in given:
        kind = float if record.limit_required else float | None
        check_value(method, "time_limit", given.pop("time_limit"), kind, {"above": 0})
    return record.options().parse(given)


def gather_options(method: str, given: list[tuple[str, str, Any]]) -> dict[str, Any]:
    """``(label, name, value)`` triples as the user wrote them (a command line's flags and
    ``-O NAME=VALUE``, a ``--methods`` token) -> ``method``'s options by their own names
    (:meth:`~bille.instances.options.MethodOptions.gather`): aliases resolved, and one option
    given twice (by a flag and ``-O``, or by two aliases) an :class:`OptionError` naming both."""
    if method not in METHODS:
        raise OptionError(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})")
    return METHODS[method].options().gather(given)


__all__ = ["check_options", "gather_options"]
