"""What ``bille bench`` commands share: comma-separated options, and the end of an interrupted run."""
from __future__ import annotations

import click

from ..common import EXIT_INTERRUPTED


def stopped(lines, what: str) -> int:
    """Print what a benchmark measured before Ctrl-C, and the exit code of an interruption."""
    for line in lines:
        click.echo(line)
    click.echo(f"bille bench: interrupted; {what}", err=True)
    return EXIT_INTERRUPTED


def names(text: str) -> list[str]:
    """The non-empty entries of a comma-separated option."""
    return [part.strip() for part in text.split(",") if part.strip()]


def counts(text: str, option: str, what: str) -> list[int]:
    """The whole numbers (each at least 1) of a comma-separated option; ``what`` names them."""
    try:
        values = [int(v) for v in names(text)]
    except ValueError:
        raise click.BadParameter(f"{text!r}: expected numbers like 10,50", param_hint=option) from None
    if not values or min(values) < 1:
        raise click.BadParameter(f"{text!r}: {what} must be at least 1", param_hint=option)
    return values
