"""``bille methods`` and ``bille solve -m METHOD -O help``: what each method plans for, what it
proves, and its options with their defaults and ranges, read from the method records."""
from __future__ import annotations

import click

from bille.solvers import METHODS

from .common import EXIT_OK


def options_of(method: str) -> list[tuple[str, str, str, str]]:
    """``(name, type, default and range, what it does)`` of each option of ``method``:
    ``time_limit`` first, then its options record's fields."""
    record = METHODS[method]
    limit = "none" if record.time_limit is None else record.time_limit
    kind = "float" if record.limit_required else "float or none"
    return [("time_limit", kind, f"{limit} (> 0 s)", "seconds for the whole call, the lower bound included"),
            *record.options().rows()]


def described(method: str) -> dict:
    """The same as :func:`describe`, as one JSON object."""
    record = METHODS[method]
    return {"method": method, "plans": record.plans, "proves": record.proves, "classic": record.classic,
            "options": [{"name": n, "type": kind, "default": default, "help": help_}
                        for n, kind, default, help_ in options_of(method)]}


def describe(method: str) -> list[str]:
    record = METHODS[method]
    lines = [f"{method}: {record.plans}", f"  proves: {record.proves}",
             f"  collisions: {'classic and Bill-E' if record.classic else 'Bill-E'}"]
    rows = options_of(method)
    width = max(len(n) for n, *_ in rows)
    lines.append("  options (-O NAME=VALUE):")
    for n, kind, default, help_ in rows:
        lines += [f"    {n.ljust(width)}  {help_}", f"    {' ' * width}    {kind}, default {default}"]
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
