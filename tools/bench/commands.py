"""``bille bench``: benchmarks that print figures measured on this machine, with ratios to
baselines of the same run."""
from __future__ import annotations

import json
import time
from pathlib import Path

import click

from bille.instances.bundled import bundled_path

from ..common import EXIT_NO, EXIT_OK, instance_arg, output_folder
from .args import counts as _counts, names as _names
from .proof_commands import bench_cbs, bench_interrupt, bench_peers
from .joint import bench_joint
from .loop_schedules import bench_loop_schedules
from .solving import bench_anytime, bench_gaps


@click.group()
def bench() -> None:
    """Benchmarks: figures measured on this machine, with ratios to baselines of the same run."""


bench.add_command(bench_anytime)
bench.add_command(bench_gaps)
bench.add_command(bench_loop_schedules)
bench.add_command(bench_joint)


@bench.command("core")
@click.option("--size", type=click.IntRange(8, 512), default=64, show_default=True, help="Structure side for validation.")
@click.option("--robots", type=click.IntRange(1, 200), default=20, show_default=True)
@click.option("--steps", type=click.IntRange(1, 100_000), default=1000, show_default=True)
@click.option("--compile-size", type=click.IntRange(8, 1024), default=128, show_default=True, help="Structure side for compiling.")
@click.option("--seed", type=int, default=0, show_default=True)
def bench_core(size: int, robots: int, steps: int, compile_size: int, seed: int) -> int:
    """Time the validator on a long random schedule and the pose-table compiler."""
    from .core import report

    for line in report(size, robots, steps, compile_size, seed):
        click.echo(line)
    return EXIT_OK


@bench.command("execute")
@click.option("--robots", "sizes", default="10,50", show_default=True, help="Comma-separated fleet sizes (1 is the baseline).")
@click.option("--steps", type=click.IntRange(2, 100_000), default=200, show_default=True)
@click.option("--broker", metavar="URL", help="mqtt://host:port (default: the embedded broker).")
@click.option("--step-timeout", type=click.FloatRange(min=0.1), default=10.0, show_default=True,
              help="Seconds a step may take before the run stops with a fault.")
@click.option("--connect-timeout", type=click.FloatRange(min=0.1),
              help="Seconds for the robots to come up (default: 30, or 1.5 per robot above 20).")
def bench_execute(sizes: str, steps: int, broker: str | None, step_timeout: float, connect_timeout) -> int:
    """Steps per second and round-trip latency of the execution layer with simulated robots.

    A fleet that does not come up or finish within its timeouts is a row of the table (exit 1
    when one did not complete), not bad input."""
    from .execute import report
    from ..execute.broker import parse_url

    counts = sorted(set(_counts(sizes, "--robots", "fleet sizes")))
    if broker:
        parse_url(broker)
    failed: list[int] = []
    for line in report(counts, steps, broker, step_timeout, connect_timeout, failed):
        click.echo(line)
    return EXIT_NO if failed else EXIT_OK


@bench.command("imports", context_settings={"ignore_unknown_options": True})
@click.argument("argv", nargs=-1, type=click.UNPROCESSED)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object (modules, edges, pairs).")
def bench_imports(argv, as_json: bool) -> int:
    """Our modules that one command loads, and the imports between them: run 'bille ARGV' in a
    fresh interpreter (default: solve lt-4 -m anytime --time-limit 10) and count modules, import
    edges and pairs of modules that import each other."""
    from .importgraph import graph, report

    argv = list(argv) or ["solve", "lt-4", "-m", "anytime", "--time-limit", "10"]
    if as_json:
        click.echo(json.dumps(graph(argv)))
        return EXIT_OK
    for line in report(argv):
        click.echo(line)
    return EXIT_OK


@bench.command("startup")
@click.option("--runs", type=click.IntRange(min=1), default=5, show_default=True, help="Runs of each command.")
def bench_startup(runs: int) -> int:
    """Start-up of the commands that do not solve, and of two tiny solves: median seconds of
    each in a fresh interpreter, and the ratio to importing numpy, click, yaml and rich in the
    same rounds."""
    from .startup import report

    for line in report(runs):
        click.echo(line)
    return EXIT_OK


@bench.command("sweep")
@click.option("--runs", type=click.IntRange(min=2), default=1000, show_default=True, help="Trivial runs (tiny instances).")
@click.option("--jobs", "-j", type=click.IntRange(min=1), default=2, show_default=True,
              help="Local processes, and Dask workers.")
def bench_sweep(runs: int, jobs: int) -> int:
    """The sweep engine's overhead: trivial runs per second on local processes and on a local
    Dask cluster (LocalCluster, one thread per worker) with the same number of workers."""
    import tempfile

    from distributed import Client, LocalCluster

    from ..sweep.commands import run_spec
    from ..sweep.spec import parse_spec

    with tempfile.TemporaryDirectory() as tmp:
        data = {"name": "overhead", "time_limit": 10,
                "instances": [{"gen": f"crowded --robots 2 --width 5 --height 3 --seed 0..{runs // 2 - 1}"}],
                "methods": {"temporal-astar": {"horizon": [2, 5]}}}
        spec = parse_spec(data, Path(tmp) / "overhead.yaml")
        click.echo(f"{len(spec.runs)} runs: Temporal A* (H 2 and 5) on tiny crowded instances, {jobs} workers")
        began = time.perf_counter()
        run_spec(spec, Path(tmp) / "local", jobs=jobs)
        local = time.perf_counter() - began
        click.echo(f"local processes: {len(spec.runs) / local:.1f} runs/s ({local:.1f} s)")
        with LocalCluster(n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
                Client(cluster) as client:
            began = time.perf_counter()
            run_spec(spec, Path(tmp) / "dask", client=client)
            dask = time.perf_counter() - began
        click.echo(f"local Dask cluster: {len(spec.runs) / dask:.1f} runs/s ({dask:.1f} s); ratio Dask / local "
                   f"{local / dask:.2f}")
    return EXIT_OK


@bench.command("planners")
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=60.0, show_default=True, help="Seconds per run.")
@click.option("--jobs", "-j", type=click.IntRange(min=1), default=None, help="Parallel processes (default: CPUs).")
@click.option("--maps", default=",".join(f"compare-{m}" for m in range(2, 7)), show_default=True,
              help="Comma-separated bundled maps.")
@click.option("--movesets", default="S5,S7", show_default=True)
@click.option("--out", type=click.Path(file_okay=False), default="bench-out", show_default=True,
              help="Folder for planners.csv and planners.png.")
def bench_planners(time_limit: float, jobs: int | None, maps: str, movesets: str, out: str) -> int:
    """The paper's planner comparison: A*, M*, Temporal A* (and LaCAM*) on the comparison maps."""
    from .planners import default_jobs, plot, run_grid, tables, write_csv

    names = _names(maps)
    for name in names:
        bundled_path(name)  # unknown names fail here, before any work
    sets = _names(movesets)
    for ms in sets:
        if ms not in ("S5", "S7", "point"):
            raise click.BadParameter(f"unknown moveset {ms!r}", param_hint="--movesets")
    folder = output_folder(out)
    rows = run_grid(time_limit, jobs or default_jobs(), names, sets)
    for line in tables(rows, time_limit):
        click.echo(line)
    write_csv(rows, folder / "planners.csv")
    plot(rows, time_limit, folder / "planners.png")
    click.echo(f"wrote {folder / 'planners.csv'} and {folder / 'planners.png'}")
    return EXIT_OK


@bench.command("exact")
@click.option("--time-limit", type=click.FloatRange(min=1), default=120.0, show_default=True, help="Seconds per run.")
@click.option("--threads", type=click.IntRange(min=1), default=2, show_default=True, help="CP-SAT workers.")
@click.option("--only", type=click.Choice(["optimum", "connectivity", "pruning", "presolve", "before-after",
                                          "sat-solver", "freedom", "families"]),
              multiple=True, help="Run only these sections (repeatable; before-after is long: every bundled "
                                  "instance, twice per back end; sat-solver: five SAT configurations; freedom: "
                                  "three models of six horizons; families: model sizes only).")
def bench_exact(time_limit: float, threads: int, only) -> int:
    """Exact solvers: time to optimum per map, eager vs lazy connectivity, pruning, presolve;
    with --only before-after, the encoding before and after the reachability with the tiles;
    with --only sat-solver, the SAT back end's solvers and horizons per model; with --only
    freedom, where a proof's time goes (all schedules against the model's restrictions); with
    --only families, where the model's size goes (variables and clauses per constraint family)."""
    from .exact import report

    report(time_limit, threads, only or ("optimum", "connectivity", "pruning", "presolve"), echo=click.echo)
    return EXIT_OK


@bench.command("limits")
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=2.0, show_default=True, help="Seconds per run.")
@click.option("--methods", default=None, help="Comma-separated methods (default: every method).")
def bench_limits(time_limit: float, methods: str | None) -> int:
    """Every method on generated instances of each family (classic and Bill-E, mixed movesets,
    unreachable goals, a thousand robots) as bille solve --json: one JSON object or one clear
    line, no traceback, the time limit held (exit 1 if any run broke one of these)."""
    from bille.solvers import METHODS

    from .limits import report

    return EXIT_NO if report(time_limit, _names(methods) if methods else list(METHODS), click.echo) else EXIT_OK


@bench.command("hampath")
@click.option("--size", type=click.IntRange(2, 40), default=10, show_default=True, help="Largest grid graph side.")
@click.option("--scale", "-s", type=click.IntRange(min=1), default=1, show_default=True)
@click.option("--robots", "-r", type=click.IntRange(min=1), default=1, show_default=True)
def bench_hampath(size: int, scale: int, robots: int) -> int:
    """Time and size of Theorem 1's instance for k x k grid graphs up to SIZE."""
    from .gen import report

    for line in report(size, scale, robots):
        click.echo(line, nl=True)
    return EXIT_OK


@bench.command("view")
@click.option("--size", type=click.IntRange(8, 512), default=64, show_default=True)
@click.option("--robots", type=click.IntRange(1, 200), default=20, show_default=True)
@click.option("--steps", type=click.IntRange(1, 100_000), default=1000, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True)
def bench_view(size: int, robots: int, steps: int, seed: int) -> int:
    """Time and size of a rerun recording and a picture of a long schedule."""
    from .view import report

    for line in report(size, robots, steps, seed):
        click.echo(line)
    return EXIT_OK


@bench.command("load-transfer")
@click.option("--maps", default=",".join(f"lt-{k}" for k in range(1, 9)), show_default=True,
              help="Comma-separated bundled maps or instance files.")
@click.option("--horizon", "-H", type=click.IntRange(min=1), default=10, show_default=True)
@click.option("--d-tr", type=click.IntRange(min=0), default=5, show_default=True)
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=120.0, show_default=True, help="Seconds per run.")
@click.option("--random", "random_runs", type=click.IntRange(min=0), default=0, show_default=True,
              help="Also run this many random reconfiguration instances per size (10-50 tiles moved, 2-10 robots).")
@click.option("--exact-limit", type=click.FloatRange(min=0), default=0.0, show_default=True,
              help="Seconds of CP-SAT per random instance for the gap to the optimum (0: skip).")
@click.option("--motion", type=click.Choice(["temporal-astar", "lacam"]), default="temporal-astar", show_default=True,
              help="The random instances' method: the paper's loop (Temporal A*) or lacam (LaCAM* motion layer).")
@click.option("--out", type=click.Path(file_okay=False), default="bench-out", show_default=True,
              help="Folder for load-transfer.csv and load-transfer.png.")
def bench_load_transfer(maps: str, horizon: int, d_tr: int, time_limit: float, random_runs: int, exact_limit: float,
                        motion: str, out: str) -> int:
    """The paper's load-transfer experiment: each map with and without load transfer (Temporal A*,
    epsilon 1), the percentage decrease in time steps and tiles traveled, and a bar plot."""
    from .transfer import plot, random_report, run_maps, table, write_csv

    names = _names(maps)
    instances = [instance_arg(name) for name in names]  # unknown names fail here, before any work
    folder = output_folder(out)
    rows = run_maps(instances, horizon, d_tr, time_limit, files=names)
    for line in table(rows):
        click.echo(line)
    write_csv(rows, folder / "load-transfer.csv")
    plot(rows, folder / "load-transfer.png")
    click.echo(f"wrote {folder / 'load-transfer.csv'} and {folder / 'load-transfer.png'}")
    if random_runs:
        for line in random_report(random_runs, horizon, d_tr, time_limit, exact_limit, motion):
            click.echo(line)  # one line per size as soon as it is measured
    return EXIT_OK


@bench.command("crowd")
@click.option("--size", type=click.IntRange(8, 512), default=64, show_default=True)
@click.option("--robots", type=click.IntRange(1, 1000), default=50, show_default=True)
@click.option("--horizon", "-H", type=click.IntRange(min=1), default=5, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True)
def bench_crowd(size: int, robots: int, horizon: int, seed: int) -> int:
    """Temporal A* with many robots: mean replanning time per step."""
    from .planners import bench_crowd as run

    for line in run(size, robots, horizon, seed):
        click.echo(line)
    return EXIT_OK


@bench.command("mapf")
@click.option("--maps", "folder", type=click.Path(file_okay=False, exists=True), default=None,
              help="Folder of MovingAI NAME.map files with their NAME-random-1.scen scenarios "
                   "(default: the maps shipped with bille that have one).")
@click.option("--names", default=None, help="Comma-separated map names in that folder (default: the shipped "
              "random-32-32-10, room-32-32-4, warehouse-10-20-10-2-1, random-64-64-20, or every map of --maps).")
@click.option("--agents", default="50,100,200,300,400", show_default=True, help="Comma-separated agent counts.")
@click.option("--time-limit", type=click.FloatRange(min=0.1), default=60.0, show_default=True)
@click.option("--improve", type=click.FloatRange(min=0), default=0.0, show_default=True,
              help="Seconds LaCAM* improves its first schedule.")
@click.option("--peers", type=click.Path(file_okay=False, exists=True), default=None,
              help="Folder with lacam3 (lacam3/build/main) and pypibt (pypibt/pypibt) built from their own "
                   "repositories: print bille's time and sum of costs against theirs.")
@click.option("--against", nargs=2, multiple=True, metavar="PEER PATH",
              type=(click.Choice(["lacam3", "pypibt"]), click.Path(exists=True)),
              help="A peer built anywhere: lacam3 and its program (build/main), or pypibt and its repository "
                   "folder; may be given for both. Like --peers, without the folder layout.")
@click.option("--optimal", is_flag=True, help="The exact methods instead: cbs, basic CBS (the baseline) and joint "
              "A*, optimal sum of costs with proof (default --agents 10,20,30,40).")
@click.option("--csv", "csv_path", type=click.Path(dir_okay=False), default="mapf-optimal.csv", show_default=True,
              help="With --optimal: where to write the table as CSV.")
def bench_mapf(folder: str | None, names: str | None, agents: str, time_limit: float, improve: float,
               peers: str | None, against: tuple, optimal: bool, csv_path: str) -> int:
    """Classic MAPF on MovingAI maps: LaCAM*'s success, sum of costs, makespan and time; with
    --optimal, the exact methods' proofs and times."""
    from pathlib import Path

    from .maps import shipped_maps
    from .mapf import MAPS, map_names, mapf_rows, mapf_table
    from .peers import available, peer_at, peers_table

    if optimal and (peers or against):
        raise click.BadParameter("the peers find schedules without proof; bille bench cbs compares the exact "
                                 "methods with libMultiRobotPlanning's CBS", param_hint="--peers")
    if optimal and agents == "50,100,200,300,400":
        agents = "10,20,30,40"
    counts = _counts(agents, "--agents", "agent counts")
    where = shipped_maps() if folder is None else Path(folder)
    found = map_names(where)
    chosen = _names(names) if names is not None else (list(MAPS) if folder is None else found)
    missing = [n for n in chosen if n not in found]
    if missing or not chosen:
        raise click.BadParameter(f"{', '.join(missing) or 'no map'}: expected NAME.map and NAME-random-1.scen in "
                                 f"{where} (found: {', '.join(found) or 'none'})", param_hint="--names")
    if optimal:
        return _optimal(where, chosen, counts, time_limit, csv_path)
    found_peers = available(Path(peers)) if peers else {}
    if peers and not found_peers:
        raise click.BadParameter(f"{peers}: neither lacam3/build/main nor pypibt/pypibt/ in it", param_hint="--peers")
    for name, path in against:
        try:
            found_peers[name] = peer_at(name, Path(path))
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint="--against") from None
    rows = []
    for row in mapf_rows(where, chosen, counts, time_limit, improve, found_peers):
        rows.append(row)
        click.echo(f"{row['map']} {row['agents']} agents: {row['status']} {row.get('reason', '')}".rstrip(), err=True)
    for line in mapf_table(rows) if not found_peers else peers_table(rows, sorted(found_peers)):
        click.echo(line)
    return EXIT_OK


def _optimal(where, chosen, counts, time_limit: float, csv_path: str) -> int:
    from pathlib import Path

    from .optimal import optimal_rows, optimal_table, write_optimal_csv

    rows = []
    for row in optimal_rows(where, chosen, counts, time_limit):
        rows.append(row)
        told = ", ".join(f"{k} {v['status']}" for k, v in row["runs"].items()) or row.get("reason", "")
        click.echo(f"{row['map']} {row['agents']} agents: {told}", err=True)
    for line in optimal_table(rows):
        click.echo(line)
    out = Path(csv_path)
    write_optimal_csv(rows, out)
    click.echo(f"written to {out}")
    return EXIT_OK


@bench.command("lacam")
@click.option("--size", type=click.IntRange(8, 512), default=64, show_default=True)
@click.option("--robots", default="50,100,200", show_default=True, help="Comma-separated robot counts.")
@click.option("--seed", type=int, default=0, show_default=True)
def bench_lacam(size: int, robots: str, seed: int) -> int:
    """LaCAM* at scale: S7 robots with random goals on a fully tiled square, time to a first schedule."""
    from .mapf import scale_rows

    click.echo(f"LaCAM* on a fully tiled {size}x{size} square, S7 robots, random goal cells (seed {seed}); "
               "target: first schedule within 10 s for 200 robots")
    for r in scale_rows(size, _counts(robots, "--robots", "robot counts"), seed):
        first = "-" if r["first_s"] is None else f"{r['first_s']:.2f} s"
        click.echo(f"  {r['robots']:>4} robots: {r['status']}, first schedule after {first}, makespan "
                   f"{r['makespan']}, {r['nodes']} configurations, total {r['time_s']:.2f} s")
    return EXIT_OK


@bench.command("scale")
@click.option("--robots", default="50,100,200,500", show_default=True, help="Comma-separated robot counts.")
@click.option("--obstacles", default="10,20", show_default=True, help="Comma-separated obstacle shares in percent.")
@click.option("--size", type=click.IntRange(16, 256), default=64, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--time-limit", type=click.FloatRange(min=1), default=120.0, show_default=True)
def bench_scale(robots: str, obstacles: str, size: int, seed: int, time_limit: float) -> int:
    """Bill-E planners at scale: LaCAM*'s first schedule for S7 robots on a map with obstacles,
    its makespan against the static bound, and Temporal A*'s time per replanning step."""
    from .scale import scale_rows, scale_table

    shares = [v / 100 for v in _counts(obstacles, "--obstacles", "obstacle shares")]
    if max(shares) >= 0.5:
        raise click.BadParameter(f"{obstacles!r}: obstacle shares must be below 50", param_hint="--obstacles")
    rows = []
    for row in scale_rows(size, _counts(robots, "--robots", "robot counts"), shares, seed, time_limit):
        rows.append(row)
        click.echo(f"{round(row['obstacles'] * 100)} % obstacles, {row['robots']} robots: {row['status']}", err=True)
    for line in scale_table(rows):
        click.echo(line)
    return EXIT_OK


for _command in (bench_cbs, bench_interrupt, bench_peers):
    bench.add_command(_command)
