"""``bille bench anytime`` and ``bille bench gaps``: anytime certified solving measured per map."""
from __future__ import annotations

from typing import Callable

import click

from ..common import EXIT_OK, instance_arg
from .args import names as _names, stopped


def _measure(names: list[str], measure: Callable[[str], list[dict] | dict], table: Callable, what: str) -> int:
    """Measure each name in turn (a progress line each on stderr) and print the table; Ctrl-C
    prints the rows measured before it."""
    for name in names:
        instance_arg(name)  # a bad file or name fails here, before any work
    found: list[dict] = []
    try:
        for name in names:
            click.echo(f"  {name} ...", err=True)
            found.append(measure(name))
    except KeyboardInterrupt:
        return stopped(table(found), f"{len(found)} of {len(names)} {what} measured")
    for line in table(found):
        click.echo(line)
    return EXIT_OK


@click.command("anytime")
@click.option("--time-limit", type=click.FloatRange(min=1), default=60.0, show_default=True,
              help="Seconds per run (three runs per map).")
@click.option("--maps", default=",".join(f"lt-{k}" for k in range(1, 9)), show_default=True,
              help="Comma-separated instance files or bundled names.")
def bench_anytime(time_limit: float, maps: str) -> int:
    """How far anytime certified solving improves the paper's method: makespans, the lower bound
    proved, certified gaps."""
    from .anytime import row, table

    return _measure(_names(maps), lambda name: row(name, time_limit), table, "maps")


@click.command("gaps")
@click.option("--time-limit", type=click.FloatRange(min=1), default=60.0, show_default=True,
              help="Seconds of anytime solving per instance.")
@click.option("--maps", default=",".join([f"lt-{k}" for k in range(1, 9)] + ["bridge-2"]), show_default=True,
              help="Comma-separated instance files or bundled names.")
@click.option("--class-exact", type=click.FloatRange(min=1), default=None,
              help="Seconds per instance for the exact search among the schedules without scaffold, after "
                   "anytime: the class's optimum or a higher class bound (columns N exact, N best, N gap).")
def bench_gaps(time_limit: float, maps: str, class_exact: float | None) -> int:
    """Certified gaps of anytime solving, and what proved each end: the static bound and its
    strongest part, the bound reached and how, the best schedule and which search shortened it."""
    from .gaps import row, table

    return _measure(_names(maps), lambda name: row(name, time_limit, class_exact), table, "instances")
