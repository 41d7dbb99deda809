"""``bille methods`` and ``bille solve -m METHOD -O help``: what each method plans for, what it
proves, and its options with their defaults and ranges, read from the registry and the methods'
own signatures."""
from __future__ import annotations

import inspect
import typing

import click

from bille.solvers import METHODS
from bille.solvers.options import _AT_LEAST
from bille.solvers.registry import ABOUT, CLASSIC, DEFAULT_TIME_LIMIT

from .common import EXIT_OK

INTERNAL = ("instance", "bounds", "progress", "on_schedule", "on_bound", "run")


def options_of(method: str) -> list[tuple[str, str, str]]:
    """``(name, type, default and range)`` of each option of ``method``."""
    plan = METHODS[method]
    hints = typing.get_type_hints(plan)
    rows = [("time_limit", "float or none", f"{DEFAULT_TIME_LIMIT.get(method, 'none')} (> 0 s)")]
    for name, param in inspect.signature(plan).parameters.items():
        if name in INTERNAL:
            continue
        hint = hints.get(name)
        kind = getattr(hint, "__name__", None) or str(hint).replace("typing.", "")
        default = "none" if param.default is None else str(param.default).lower() \
            if isinstance(param.default, bool) else str(param.default)
        low = f">= {_AT_LEAST[name]}" if name in _AT_LEAST else ""
        rows.append((name, kind.replace(" | None", " or none"), default + (f" ({low})" if low else "")))
    return rows


def describe(method: str) -> list[str]:
    plans, proves = ABOUT.get(method, ("", ""))
    lines = [f"{method}: {plans}", f"  proves: {proves}",
             f"  collisions: {'classic and Bill-E' if method in CLASSIC else 'Bill-E'}"]
    rows = options_of(method)
    width = max((len(n) for n, _, _ in rows), default=0)
    lines.append("  options (-O NAME=VALUE):" if rows else "  no options")
    lines += [f"    {n.ljust(width)}  {kind}, default {default}" for n, kind, default in rows]
    return lines


@click.command()
@click.argument("method", required=False)
def methods(method: str | None) -> int:
    """List the methods of bille solve: what each plans for, what it proves, and (with METHOD)
    its options with defaults and ranges."""
    if method is not None and method not in METHODS:
        raise click.BadParameter(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})",
                                 param_hint="METHOD")
    for name in [method] if method else METHODS:
        for line in describe(name) if method else describe(name)[:2]:
            click.echo(line)
    if method is None:
        click.echo("bille methods METHOD (or bille solve INSTANCE -m METHOD -O help) lists a method's options.")
    return EXIT_OK
