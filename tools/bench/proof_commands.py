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


@click.command("peers")
@click.option("--cbsh2-rtc", "cbsh2", type=click.Path(exists=True, dir_okay=False), default=None,
              help="CBSH2-RTC's program (its build/cbs), built from its own repository.")
@click.option("--eecbs", type=click.Path(exists=True, dir_okay=False), default=None,
              help="EECBS's program (run with --suboptimality=1: optimal).")
@click.option("--mrp-cbs", type=click.Path(exists=True, dir_okay=False), default=None,
              help="libMultiRobotPlanning's cbs program.")
@click.option("--lacam3", type=click.Path(exists=True, dir_okay=False), default=None,
              help="lacam3's program (its build/main): first schedules, against bille's lacam -O improve=0.")
@click.option("--optimal-rows", default=None, metavar="MAP:N,N;...",
              help="Rows for the optimal peers (default: random-32-32-10:30,40,50,60;room-32-32-4:20,30,40;"
                   "warehouse-10-20-10-2-1:20,40,60).")
@click.option("--first-rows", default=None, metavar="MAP:N,N;...",
              help="Rows for lacam3 (default: random-32-32-10:400;room-32-32-4:200;warehouse-10-20-10-2-1:500;"
                   "random-64-64-20:500;den312d:200).")
@click.option("--maps", "folder", type=click.Path(file_okay=False, exists=True), default=None,
              help="Folder of MovingAI NAME.map files, each with NAME-random-1.scen or one other NAME-*.scen "
                   "(default: the maps shipped with bille).")
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=60.0, show_default=True, help="Seconds per run.")
def bench_peers(cbsh2, eecbs, mrp_cbs, lacam3, optimal_rows, first_rows, folder, time_limit: float) -> int:
    """bille's cbs and lacam beside the C++ peers named (each built from its own repository,
    never by bille) on the same MovingAI rows, one after the other: times, sums of costs, and
    the geometric mean of the time ratios (bille / peer) per peer."""
    from pathlib import Path

    from .maps import scenario_of, shipped_maps
    from .optimal import executable
    from .sidebyside import FIRST_PEERS, FIRST_ROWS, OPTIMAL_PEERS, OPTIMAL_ROWS, parse_rows, side_by_side, table

    given = {"cbsh2-rtc": cbsh2, "eecbs": eecbs, "mrp-cbs": mrp_cbs, "lacam3": lacam3}
    peers = {name: Path(path) for name, path in given.items() if path is not None}
    if not peers:
        raise click.BadParameter("name at least one peer's program",
                                 param_hint="--cbsh2-rtc/--eecbs/--mrp-cbs/--lacam3")
    for name, path in peers.items():
        if not executable(str(path)):
            raise click.BadParameter(f"{path}: not an executable program", param_hint=f"--{name}")
    where = shipped_maps() if folder is None else Path(folder)
    plans = []
    for option, text, default, names in (("--optimal-rows", optimal_rows, OPTIMAL_ROWS, OPTIMAL_PEERS),
                                         ("--first-rows", first_rows, FIRST_ROWS, FIRST_PEERS)):
        try:
            rows = default if text is None else parse_rows(text)
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint=option) from None
        missing = [m for m, _ in rows if not ((where / f"{m}.map").is_file() and scenario_of(where, m).is_file())]
        if missing:
            raise click.BadParameter(f"{', '.join(missing)}: no NAME.map with a NAME-*.scen in {where}",
                                     param_hint=option)
        chosen = {n: p for n, p in peers.items() if n in names}
        if chosen:
            plans.append(("optimal" if option == "--optimal-rows" else "first", rows, chosen))

    def told(row: dict) -> None:
        peers_said = ", ".join(f"{n} {r.get('soc', r.get('status'))}" for n, r in row["peers"].items())
        click.echo(f"{row['map']} {row['agents']} agents: bille {row['bille'].get('soc', row['bille']['status'])}, "
                   f"{peers_said}", err=True)

    for kind, rows, chosen in plans:
        measured = list(side_by_side(where, rows, chosen, time_limit, kind, told))
        click.echo("optimal sum of costs (bille -m cbs):" if kind == "optimal" else
                   "first schedule (bille -m lacam -O improve=0):")
        for line in table(measured, list(chosen), kind):
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
