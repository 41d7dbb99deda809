"""``bille bench cbs`` (against libMultiRobotPlanning's CBS) and ``bille bench interrupt``
(Ctrl-C as a terminal sends it): the benchmarks of what is proved, and of stopping."""
from __future__ import annotations

import click

from ..common import EXIT_OK
from .args import names as _names


@click.command("cbs")
@click.argument("instances", nargs=-1, required=True, type=click.Path(exists=True))
@click.option("--against", "binary", required=True, type=click.Path(exists=True, dir_okay=False),
              help="libMultiRobotPlanning's cbs program, built from its own repository (never part of bille).")
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=60.0, show_default=True, help="Seconds per run.")
def bench_cbs(instances, binary: str, time_limit: float) -> int:
    """bille's cbs against libMultiRobotPlanning's CBS on its YAML instances (files or folders):
    sums of costs compared, times side by side, their geometric mean ratio."""
    from pathlib import Path

    from .optimal import executable, peer_files, peer_rows, peer_table

    if not executable(binary):
        raise click.BadParameter(f"{binary}: not an executable program", param_hint="--against")
    files = peer_files(list(instances))
    if not files:
        raise click.BadParameter(f"no .yaml file in {', '.join(instances)}", param_hint="INSTANCES")
    rows = []
    for k, row in enumerate(peer_rows(Path(binary), files, time_limit), 1):
        rows.append(row)
        mine, theirs = row.get("bille", {}), row.get("peer", {})
        click.echo(f"[{k}/{len(files)}] {row['instance']}: bille {mine.get('soc', mine.get('status'))}, "
                   f"peer {theirs.get('soc')}", err=True)
    for line in peer_table(rows):
        click.echo(line)
    return EXIT_OK


@click.command("interrupt")
@click.option("--runs", type=click.IntRange(min=1), default=30, show_default=True, help="Runs in all.")
@click.option("--pairs", default="lt-1:anytime,lt-6:anytime,bridge-2:cpsat,bridge-2:sat,lt-6:mstar,lt-1:lacam",
              show_default=True, help="Comma-separated INSTANCE:METHOD, taken in turn.")
@click.option("--time-limit", type=click.FloatRange(min=1), default=20.0, show_default=True, help="Each solve's limit.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the moments the signal is sent.")
def bench_interrupt(runs: int, pairs: str, time_limit: float, seed: int) -> int:
    """Ctrl-C as a terminal sends it: SIGINT to each solve's process group at a random moment;
    exit codes, seconds to exit, tracebacks, schedules written, signals lost."""
    from .interrupt import runs as interrupt_runs
    from .interrupt import table

    chosen = []
    for item in _names(pairs):
        instance, _, method = item.partition(":")
        if not method:
            raise click.BadParameter(f"{item!r}: expected INSTANCE:METHOD", param_hint="--pairs")
        chosen.append((instance, method))
    rows = []
    for k, row in enumerate(interrupt_runs(chosen, runs, time_limit, seed), 1):
        rows.append(row)
        after = "" if row["after_s"] is None else f" after {row['after_s']} s"
        click.echo(f"[{k}/{runs}] {row['instance']} {row['method']}: signal at {row['at']} s, exit {row['code']}{after}",
                   err=True)
    for line in table(rows):
        click.echo(line)
    return EXIT_OK
