"""A method's options: one frozen record per method that checks itself.

Each method declares its options as a frozen dataclass derived from :class:`MethodOptions`, one
field per option with its type, default and range (:func:`option`), next to the method. Building
one checks every field (the type by its annotation, then the range) and raises one
:class:`~.errors.OptionError` naming the method, the option and what was expected; a method
adds what is particular to it in :meth:`MethodOptions.check`. :meth:`MethodOptions.parse` builds
one from a dict of names and values (a command line's ``-O NAME=VALUE``), :meth:`MethodOptions.rows`
lists them for ``bille methods``.

>>> from dataclasses import dataclass
>>> @dataclass(frozen=True)
... class Walk(MethodOptions):
...     METHOD = "walk"
...     epsilon: float = option(1.0, at_least=1)
>>> Walk.parse({"epsilon": 2}).epsilon
2
>>> try:
...     Walk.parse({"epsilon": 0.5})
... except OptionError as error:
...     print(error)
walk: option epsilon expects a number of at least 1, got 0.5
"""
from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any, ClassVar

from .errors import OptionError


def option(default: Any, *, at_least: float | None = None, above: float | None = None,
           choices: tuple | None = None, help: str = "", aliases: tuple[str, ...] = ()) -> Any:
    """A field of a :class:`MethodOptions`: its default, its range (``at_least``, strictly
    ``above``, or one of ``choices``), a line saying what it does (``bille methods METHOD``
    prints it) and other names it may be given by (``H`` for ``horizon``)."""
    return dataclasses.field(default=default, metadata={"at_least": at_least, "above": above, "choices": choices,
                                                        "help": help, "aliases": tuple(aliases)})


@dataclasses.dataclass(frozen=True)
class MethodOptions:
    """The base of every method's options (module docstring). ``METHOD``: the method's name, for
    the messages."""

    METHOD: ClassVar[str] = "method"

    def __post_init__(self) -> None:
        hints = typing.get_type_hints(type(self))
        for f in dataclasses.fields(self):
            check_value(self.METHOD, f.name, getattr(self, f.name), hints[f.name], f.metadata)
        self.check()

    def check(self) -> None:
        """What is particular to the method (a combination of options); raise OptionError."""

    def check_instance(self, instance) -> None:
        """Raise OptionError if an option given has no effect on ``instance`` (the reason in the
        message): a method adds its own, :func:`refuse` helps."""

    @classmethod
    def names(cls) -> dict[str, str]:
        """Every name an option may be given by (its own and its aliases) -> its own name."""
        out = {}
        for f in dataclasses.fields(cls):
            out[f.name] = f.name
            out.update((alias, f.name) for alias in f.metadata.get("aliases", ()))
        return out

    @classmethod
    def gather(cls, given: list[tuple[str, str, Any]]) -> dict[str, Any]:
        """``(label, name, value)`` triples (``label``: how the user wrote it, e.g. ``-H 3``) -> the
        options by their own names: an alias becomes the option's name (``-`` reads as ``_``), and
        one option given twice, by any two names, is an OptionError naming both."""
        names, out, seen = cls.names(), {}, {}
        for label, name, value in given:
            name = name.replace("-", "_")
            own = names.get(name, name)
            if own in seen:
                raise OptionError(f"{cls.METHOD}: option {own} is given twice: {seen[own]} and {label}")
            seen[own], out[own] = label, value
        return out

    @classmethod
    def parse(cls, given: dict[str, Any], also: tuple[str, ...] = ("time_limit",)):
        """The options from ``given`` (names or aliases and values), checked; the others take
        their defaults. ``also``: names taken elsewhere, listed in the message for an unknown
        name."""
        names = cls.names()
        for name in given:
            if name not in names:
                expected = ", ".join([*also, *(f.name for f in dataclasses.fields(cls))])
                raise OptionError(f"{cls.METHOD}: unknown option '{name}' (expected one of: {expected})")
        return cls(**cls.gather([(f"{name}={_show(value)}", name, value) for name, value in given.items()]))

    @classmethod
    def rows(cls) -> list[tuple[str, str, str, str]]:
        """``(name, type, default and range, what it does)`` of each option, for ``bille methods``;
        the help names the option's aliases."""
        hints = typing.get_type_hints(cls)
        own = cls.__dict__.get("__annotations__", {})
        out = []
        for f in sorted(dataclasses.fields(cls), key=lambda f: f.name not in own):  # the method's own first
            kind = _describe_type(hints[f.name])
            default = "none" if f.default is None else str(f.default).lower() if isinstance(f.default, bool) \
                else str(f.default)
            aliases = f.metadata.get("aliases", ())
            help_ = f.metadata.get("help", "") + (f" (also {', '.join(aliases)})" if aliases else "")
            out.append((f.name, kind, default + _describe_range(f.metadata), help_))
        return out


def refuse(options: MethodOptions, names: tuple[str, ...], why: str) -> None:
    """Raise OptionError if any of ``names`` differs from its default in ``options``; ``why``
    completes the message, e.g. ``"works on instances that move tiles; lt-1 moves none"``."""
    defaults = {f.name: f.default for f in dataclasses.fields(options)}
    given = [n for n in names if getattr(options, n) != defaults[n]]
    if given:
        raise OptionError(f"{options.METHOD}: option {', '.join(given)} {why}")


def check_value(method: str, name: str, value: Any, hint, meta) -> None:
    """Raise OptionError unless ``value`` fits the type ``hint`` and the range in ``meta`` (the
    keys of :func:`option`)."""
    args = typing.get_args(hint)
    optional = type(None) in args
    base = next((a for a in args if a is not type(None)), hint) if _is_union(hint) else hint

    def fail(expected: str):
        raise OptionError(f"{method}: option {name} expects {expected}, got {_show(value)}")

    if value is None:
        if not optional:
            fail(_describe(base))
        return
    expected = _mistyped(base, value)
    if expected is not None:
        fail(expected)
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        raise OptionError(f"{method}: unknown {name} {value!r} (expected one of: {', '.join(map(str, choices))})")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if meta.get("above") is not None and not value > meta["above"]:
            fail(f"a number above {meta['above']}")
        if meta.get("at_least") is not None and value < meta["at_least"]:
            fail(f"a number of at least {meta['at_least']}")


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


# the type of an option -> (whether a value fits it, what the message says it expects)
_SCALARS = {bool: (lambda v: isinstance(v, bool), "true or false"),
            int: (lambda v: isinstance(v, int) and not isinstance(v, bool), "a whole number"),
            float: (lambda v: _number(v) and math.isfinite(v), "a finite number"),
            str: (lambda v: isinstance(v, str), "a name")}


def _mistyped(base, value: Any) -> str | None:
    """What the type ``base`` expects, if ``value`` (not None) does not fit it; None if it fits."""
    if base in _SCALARS:
        fits, expected = _SCALARS[base]
        return None if fits(value) else expected
    if typing.get_origin(base) is list:
        inner = typing.get_args(base)[0] if typing.get_args(base) else int
        if typing.get_origin(inner) is list:  # a list of lists: cells as [x, y] pairs
            ok = isinstance(value, list) and all(isinstance(v, list) and len(v) == 2 and _whole(v) for v in value)
            return None if ok else "a list of [x, y] pairs of whole numbers"
        return None if isinstance(value, list) and _whole(value) else "a list of whole numbers"
    if isinstance(base, type) and not isinstance(value, base):
        return f"a {base.__name__}"
    return None


def _whole(values) -> bool:
    return all(isinstance(v, int) and not isinstance(v, bool) for v in values)


def _is_union(hint) -> bool:
    return typing.get_origin(hint) in (typing.Union, types.UnionType)


def _describe(base) -> str:
    return {bool: "true or false", int: "a whole number", float: "a finite number", str: "a name"}.get(base, "a value")


def _describe_type(hint) -> str:
    if _is_union(hint):
        parts = [a for a in typing.get_args(hint) if a is not type(None)]
        return " or ".join(_describe_type(a) for a in parts) + " or none"
    if typing.get_origin(hint) is list:
        inner = typing.get_args(hint)[0] if typing.get_args(hint) else int
        return "list of [x, y]" if typing.get_origin(inner) is list else "list of int"
    return getattr(hint, "__name__", str(hint))


def _describe_range(meta) -> str:
    if meta.get("choices") is not None:
        return f" ({' | '.join(map(str, meta['choices']))})"
    if meta.get("above") is not None:
        return f" (> {meta['above']})"
    if meta.get("at_least") is not None:
        return f" (>= {meta['at_least']})"
    return ""


def _show(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


__all__ = ["MethodOptions", "check_value", "option", "refuse"]
