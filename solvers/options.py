"""Every method option checked in one place, by the type its planning function declares.

``solve()`` reads the annotations of ``plan(instance, *, name: type = default, ...)`` and checks
each option given against them before the method runs: an integer where ``int`` is declared
(not a boolean), a finite number where ``float`` is (an integer is accepted), ``true``/``false``
where ``bool`` is, a list of integers where ``list[int]`` is, and ``None`` only where the default
or the annotation allows it. Common names carry a range: counts (``max_*``, ``threads``,
``chunk``, ``horizon``) are at least 1, ``epsilon`` at least 1, ``d_tr`` and ``seed`` at least 0
Every method also takes ``time_limit``, a positive number of seconds or None (``solve()`` turns
it into the run's budget; the planning functions take the run, never a number of seconds). What is particular to one method (a solver name, a
connectivity encoding) the method checks itself, with an :class:`OptionError` naming it.
"""
from __future__ import annotations

import math
import types
import typing
from typing import Any, Callable

from bille.instances import OptionError

_AT_LEAST = {"threads": 1, "chunk": 1, "horizon": 1, "max_steps": 0, "max_states": 1, "max_expansions": 1,
             "max_shifts": 0, "max_nodes": 1, "improve": 0, "window": 2, "max_makespan": 1, "first_horizon": 1, "travel_time": 0, "epsilon": 1, "w": 1, "d_tr": 0, "seed": 0}


INTERNAL = ("bounds", "progress", "run")  # handed to a method by solve(), never given as options


def check_options(method: str, plan: Callable, options: dict[str, Any], internal: tuple[str, ...] = ()) -> dict:
    """The options, checked against ``plan``'s signature (see the module docstring); raises
    :class:`OptionError` with one line naming the method, the option and what was expected."""
    hints = {**typing.get_type_hints(plan), "time_limit": float | None}
    accepted = [n for n in hints if n not in ("instance", "return") and n not in INTERNAL + internal]
    for name, value in options.items():
        if name not in accepted:
            raise OptionError(f"{method}: unknown option '{name}' (expected one of: {', '.join(accepted)})")
        _check(method, name, value, hints[name])
    return dict(options)


def _check(method: str, name: str, value: Any, hint) -> None:
    args = typing.get_args(hint)
    optional = type(None) in args
    base = next((a for a in args if a is not type(None)), hint) if _is_union(hint) else hint

    def fail(expected: str):
        raise OptionError(f"{method}: option {name} expects {expected}, got {_show(value)}")

    if value is None:
        if not optional:
            fail(_describe(base))
        return
    if base is bool:
        if not isinstance(value, bool):
            fail("true or false")
    elif base is int:
        if isinstance(value, bool) or not isinstance(value, int):
            fail("a whole number")
    elif base is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            fail("a finite number")
    elif base is str:
        if not isinstance(value, str):
            fail("a name")
    elif typing.get_origin(base) is list:
        if not isinstance(value, list) or not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            fail("a list of whole numbers")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if name == "time_limit" and value <= 0:
            fail("a positive number of seconds")
        low = _AT_LEAST.get(name)
        if low is not None and value < low:
            fail(f"a number of at least {low}")


def _is_union(hint) -> bool:
    return typing.get_origin(hint) in (typing.Union, types.UnionType)


def _describe(base) -> str:
    return {bool: "true or false", int: "a whole number", float: "a finite number", str: "a name"}.get(base, "a value")


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
