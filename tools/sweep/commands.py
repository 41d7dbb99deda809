"""The ``bille sweep`` commands: run a sweep file, report on its results."""
from __future__ import annotations

import os
from pathlib import Path

import click

from ..common import EXIT_INTERRUPTED, EXIT_OK, stderr_console

SHIPPED = sorted(p.stem for p in (Path(__file__).resolve().parent / "files").glob("*.yaml"))


class _RunByDefault(click.Group):
    """``bille sweep SPEC.yaml`` runs it; ``bille sweep report RESULTS`` reports."""

    def resolve_command(self, ctx, args):
        if args and args[0] not in self.commands and not args[0].startswith("-"):
            args = ["run", *args]
        return super().resolve_command(ctx, args)


@click.group(cls=_RunByDefault)
def sweep() -> None:
    """Experiments at scale: bille sweep SPEC.yaml runs instances x methods x options, resumable;
    bille sweep report RESULTS reports on them.

    \b
    bille sweep SPEC.yaml [--jobs N] [--out DIR]        local processes (default: one per CPU)
    bille sweep SPEC.yaml --scheduler tcp://HOST:PORT   on a Dask cluster
    bille sweep report RESULTS                          success, certified gaps, times; plots

    The options of each: bille sweep run --help, bille sweep report --help."""


@sweep.command("run", help=f"""Run every run of SPEC.yaml (or a sweep shipped with bille: {', '.join(SHIPPED)})
    not yet recorded in the results folder. Its methods are any of 'bille solve' with their
    options (e.g. temporal-astar: {{load_transfer: [false, true]}}). Ctrl-C keeps every finished
    run (exit 130); the same command goes on from there.""")
@click.argument("spec_file", metavar="SPEC.yaml")
@click.option("--out", type=click.Path(file_okay=False), help="Results folder (default: sweep-NAME).")
@click.option("--jobs", "-j", type=click.IntRange(min=1), help="Runs at a time on this machine (default: CPUs).")
@click.option("--scheduler", metavar="tcp://HOST:PORT", help="Run on this Dask cluster instead.")
def run_sweep(spec_file: str, out: str | None, jobs: int | None, scheduler: str | None) -> int:
    from .spec import load_spec

    from .results import Store

    spec = load_spec(spec_file)
    folder = Path(out or f"sweep-{spec.name}")
    before = sum(r.key in Store(folder).keys for r in spec.runs) if folder.is_dir() else 0
    try:
        _, rows = run_spec(spec, folder, jobs=jobs, scheduler=scheduler)
    except Interrupted as stop:
        click.echo(f"{spec.name}: interrupted; {len(stop.rows)} of {len(spec.runs)} runs recorded in {folder} "
                   f"(results.parquet, results.csv, schedules/); the same command goes on from there")
        return EXIT_INTERRUPTED
    again = "none run again: every run was recorded before" if before == len(spec.runs) else \
        f"{len(spec.runs) - before} run now" + (f", {before} recorded before" if before else "")
    click.echo(f"{spec.name}: {len(rows)} runs recorded in {folder} ({again}; results.parquet, results.csv, "
               "schedules/)")
    return EXIT_OK


class Interrupted(Exception):
    """A sweep stopped by Ctrl-C: its finished runs are recorded (``rows``), the runs under way
    were killed."""

    def __init__(self, rows: list[dict]) -> None:
        super().__init__("interrupted")
        self.rows = rows


def run_spec(spec, out, *, jobs=None, scheduler=None, client=None, quiet=False):
    """Run the spec's new runs into ``out``; returns the folder and every row recorded (measured
    against the best bounds, :func:`.results.certify`). Raises
    :class:`Interrupted` on Ctrl-C, once the finished runs are written."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    from .engine import run_dask, run_local
    from .results import Store, certify

    if scheduler:  # the optional Dask client is needed before anything is written
        import distributed  # noqa: F401
    store = Store(out)
    todo = [r for r in spec.runs if r.key not in store.keys]
    skipped = len(spec.runs) - len(todo)
    failed = 0
    columns = [TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TextColumn("failed {task.fields[failed]}"),
               TimeRemainingColumn()]
    with Progress(*columns, console=stderr_console(), disable=quiet, transient=True) as bar:
        task = bar.add_task(f"{spec.name}" + (f" ({skipped} done before)" if skipped else ""), total=len(todo),
                            failed=0)

        def on_row(row):
            nonlocal failed
            store.add(row)
            failed += row["status"] == "failed"
            bar.update(task, advance=1, failed=failed)

        try:
            if client is not None or scheduler:
                from distributed import Client

                own = client is None
                client = client or Client(scheduler, timeout="10s")
                try:
                    run_dask(todo, spec.limits, client, on_row)
                finally:
                    if own:
                        client.close()
            else:
                run_local(todo, spec.limits, jobs or os.cpu_count() or 1, on_row)
        except KeyboardInterrupt:
            store.finish()
            raise Interrupted(certify(store.rows)) from None
    store.finish()
    return Path(out), certify(store.rows)


@sweep.command("report")
@click.argument("results", metavar="RESULTS", type=click.Path(file_okay=False, exists=True))
@click.option("--no-plots", is_flag=True, help="Only the table.")
def report(results: str, no_plots: bool) -> int:
    """Per method configuration: success rate, failed runs, median and worst certified gap, median
    time; and success.png, cactus.png, gaps.png in RESULTS."""
    from .report import plots, summary
    from .results import load_table

    rows = load_table(results)
    for line in summary(rows):
        click.echo(line)
    if not no_plots:
        written = plots(rows, Path(results))
        click.echo("plots: " + ", ".join(str(p) for p in written))
    return EXIT_OK
