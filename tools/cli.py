"""The ``bille`` command line: load -> (solve) -> validate -> save -> print, each a library call.

Exit codes (DESIGN §5): 0 success, 1 a negative answer (invalid schedule, invalid instance shown,
infeasible, timeout without schedule), 2 bad input or usage. A user error is one line on stderr.
"""
from __future__ import annotations

import json
import sys
from importlib.metadata import version

import click
import yaml

from bille.instances import BilleError, InstanceError, ScheduleError, check_instance, load_instance
from bille.instances.bundled import bundled_names, bundled_path, resolve
from bille.solvers import METHODS, load_schedule, save_schedule, solve, validate

from .render import describe, draw

EXIT_OK, EXIT_NO, EXIT_USAGE = 0, 1, 2


def _instance(arg: str, *, check: bool = True):
    return load_instance(resolve(arg, InstanceError), check=check)


def _schedule(arg: str):
    return load_schedule(resolve(arg, ScheduleError))


def _print_json(obj) -> None:
    click.echo(json.dumps(obj))


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(version("bille"), "--version", prog_name="bille", message="%(prog)s %(version)s")
def cli() -> None:
    """Multi-robot reconfiguration of 2D tile structures by Bill-E inchworm robots.

    INSTANCE and SCHEDULE are YAML files, or the names of bundled ones (see 'bille list').
    """


@cli.command()
@click.argument("instance")
@click.argument("schedule")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Also write a rerun recording; a violation is marked at its step.")
def check(instance: str, schedule: str, as_json: bool, rrd: str | None) -> int:
    """Check SCHEDULE against the rules for INSTANCE (exit 0 valid, 1 invalid, 2 bad input)."""
    _writable(rrd)
    inst = _instance(instance)
    sched = _schedule(schedule)
    report = validate(inst, sched)
    if rrd:
        _record([_trace(inst, sched, _label(schedule))], rrd, quiet=as_json)
    if as_json:
        _print_json(report.to_json())
    elif report.valid:
        m = report.metrics
        click.echo(f"valid: makespan {m.makespan}, tiles traveled {m.tiles_traveled}, "
                   f"waits {m.waits}, picks {m.picks}, places {m.places}")
    else:
        v = report.violation
        robot = "" if v.robot is None else f", robot {v.robot}"
        click.echo(f"invalid: step {v.step}{robot}, rule {v.rule}: {v.message}")
    return EXIT_OK if report.valid else EXIT_NO


@cli.command()
@click.argument("instance")
def show(instance: str) -> int:
    """Draw INSTANCE (robots as letters: front foot upper case, back foot lower case, '*' a
    carried tile) with its sizes, movesets and validity (exit 1 if invalid)."""
    inst = _instance(instance, check=False)
    try:
        check_instance(inst)
        validity, code = "valid", EXIT_OK
    except InstanceError as exc:
        validity, code = f"INVALID: {exc}", EXIT_NO
    start_tiles, goal_tiles = int(inst.start.tiles.sum()), int(inst.goal_grid.tiles.sum())
    moved = int((inst.start.tiles != inst.goal_grid.tiles).sum())
    kind = "reconfiguration" if inst.is_reconfiguration else "path planning"
    click.echo(f"{inst.name}: {inst.width}x{inst.height} grid, moveset {inst.moveset.name}, "
               f"{inst.num_robots} robots, {kind}")
    click.echo(f"tiles: {start_tiles} at start, {goal_tiles} in the goal, {moved} cells differ; "
               f"tasks: {len(inst.tasks) if inst.tasks is not None else 'none'}")
    click.echo(f"instance: {validity}")
    for line in draw(inst) + ["robots:"] + describe(inst):
        click.echo(line)
    return code


@cli.command("list")
def list_() -> int:
    """List the bundled instances."""
    for name in bundled_names():
        inst = load_instance(bundled_path(name))
        kind = "reconfiguration" if inst.is_reconfiguration else "path planning"
        click.echo(f"{name:<16} {inst.width}x{inst.height}, {inst.num_robots} robots, moveset {inst.moveset.name}, {kind}")
    return EXIT_OK


@cli.command("solve")
@click.argument("instance")
@click.option("--method", "-m", type=click.Choice(list(METHODS)), default="temporal-astar", show_default=True)
@click.option("--epsilon", type=click.FloatRange(min=1.0), help="Heuristic weight (astar, mstar, temporal-astar).")
@click.option("--horizon", "-H", type=click.IntRange(min=1), help="Steps planned ahead (temporal-astar).")
@click.option("--time-limit", type=float, help="Seconds before giving up.")
@click.option("--threads", type=click.IntRange(min=1), help="Solver workers (cpsat).")
@click.option("--load-transfer", is_flag=True, default=None,
              help="Reconfiguration (temporal-astar, mstar): robots exchange loads (paper, equations 1-3).")
@click.option("--d-tr", type=click.IntRange(min=0), help="Manhattan distance within which robots consider a load transfer.")
@click.option("-O", "--option", "extra", multiple=True, metavar="NAME=VALUE",
              help="Another option of the method, e.g. -O od=false or -O max_steps=200.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the schedule here.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Write a rerun recording of the schedule found.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
def solve_(instance: str, method: str, epsilon, horizon, time_limit, threads, load_transfer, d_tr, extra, output, rrd,
           as_json) -> int:
    """Solve INSTANCE with METHOD; print the status and metrics (exit 1 if no schedule).

    On an instance that moves tiles, temporal-astar and mstar run the reconfiguration loop: the
    instance's tasks (or a derived sequence) are handed to the robots and carried out."""
    if time_limit is not None and time_limit <= 0:
        raise click.BadParameter("must be positive", param_hint="--time-limit")
    _writable(output, rrd)
    given = dict(epsilon=epsilon, horizon=horizon, time_limit=time_limit, threads=threads,
                 load_transfer=load_transfer, d_tr=d_tr)
    options = {k: v for k, v in given.items() if v is not None}
    options.update(_parse_options(extra))
    inst = _instance(instance)
    result = solve(inst, method, **options)
    if output and result.schedule is not None:
        save_schedule(result.schedule, output)
    if rrd:  # without a schedule the recording shows the instance
        _record([_trace(inst, result.schedule, method)], rrd, quiet=as_json)
    if as_json:
        _print_json(result.to_json())
        return EXIT_OK if result.schedule is not None else EXIT_NO
    m = result.metrics
    text = f"{method}: {result.status} in {result.time_s:.3f} s"
    if m is not None:
        text += f"; makespan {m.makespan}, tiles traveled {m.tiles_traveled}, waits {m.waits}"
    if result.lower_bound is not None:
        text += f"; makespan lower bound {result.lower_bound}"
    click.echo(text)
    for key in ("unreachable", "failure", "violation"):
        if key in result.stats:
            click.echo(f"{key}: {_explain(inst, key, result.stats[key])}")
    if result.stats.get("load_transfer"):
        click.echo(f"load transfers: {result.stats['relays']} relays, {result.stats['swaps']} swaps "
                   f"({result.stats['pairs_considered']} robot pairs within d_tr considered)")
    if output and result.schedule is not None:
        click.echo(f"schedule written to {output}")
    return EXIT_OK if result.schedule is not None else EXIT_NO


@cli.command("plan-sequence")
@click.argument("instance")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
def plan_sequence(instance: str, as_json: bool) -> int:
    """Print the reconfiguration sequence of INSTANCE: its tasks (checked), or one derived so
    that running it one task at a time keeps the structure connected."""
    from bille.heuristics.sequence import NoSequence, sequence_of

    inst = _instance(instance)
    try:
        jobs = sequence_of(inst)
    except NoSequence as exc:
        click.echo(f"{inst.name}: {exc}", err=True)
        return EXIT_NO
    source = "given" if inst.tasks is not None else "derived"
    xy = inst.world.xy
    rows = [{"pick": None if j.pick is None else list(xy(j.pick)), "place": list(xy(j.place)),
             **({"carrier": j.carrier} if j.pick is None else {})} for j in jobs]
    if as_json:
        _print_json({"instance": inst.name, "source": source, "tasks": rows})
        return EXIT_OK
    click.echo(f"{inst.name}: {len(jobs)} tasks ({source}); each keeps the structure connected when run in order")
    click.echo("tasks:")
    for j in jobs:
        if j.pick is None:
            click.echo(f"  - {{place: {list(xy(j.place))}}}  # the tile robot {j.carrier} carries at the start")
        else:
            click.echo(f"  - {{pick: {list(xy(j.pick))}, place: {list(xy(j.place))}}}")
    return EXIT_OK


def _parse_options(items) -> dict:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise click.BadParameter(f"expected NAME=VALUE, got {item!r}", param_hint="-O/--option")
        try:
            out[name.replace("-", "_")] = yaml.safe_load(value)
        except yaml.YAMLError:
            raise click.BadParameter(f"cannot read the value of {item!r}", param_hint="-O/--option") from None
    return out


def _explain(inst, key: str, value) -> str:
    if key == "unreachable":
        return "; ".join(f"robot {i} cannot reach its goal {inst.robot_goals[i]} even alone" for i in value)
    return str(value)


@cli.command()
@click.argument("instances", nargs=-1)
@click.option("--methods", default=",".join(("temporal-astar", "mstar", "astar", "cpsat", "sat")), show_default=True,
              help="Comma-separated methods.")
@click.option("--time-limit", type=click.FloatRange(min=0, min_open=True), default=60.0, show_default=True,
              help="Seconds per method and instance.")
@click.option("--threads", type=click.IntRange(min=1), default=2, show_default=True, help="CP-SAT workers.")
@click.option("--csv", "csv_path", type=click.Path(dir_okay=False), default="gap.csv", show_default=True,
              help="Where to write the table as CSV.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Write every schedule found to one rerun recording, side by side per instance.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of the table.")
def gap(instances, methods: str, time_limit: float, threads: int, csv_path: str, rrd: str | None, as_json: bool) -> int:
    """How far the heuristics are from the exact optimum: one table over INSTANCES (default:
    the bundled point-4), with each method's makespan gap to the proved optimum."""
    from pathlib import Path

    from .gap import run, table, write_csv

    names = [m.strip() for m in methods.split(",") if m.strip()]
    for name in names:
        if name not in METHODS:
            raise click.BadParameter(f"unknown method {name!r} (expected: {', '.join(METHODS)})", param_hint="--methods")
    _writable(csv_path, rrd)
    loaded = [_instance(arg) for arg in (instances or ("point-4",))]

    def progress(inst, method):
        if not as_json:
            click.echo(f"  running {method} on {inst} ...", err=True)

    schedules: dict = {}
    rows = run(loaded, names, time_limit, threads, progress, schedules=schedules)
    write_csv(rows, Path(csv_path))
    if rrd:
        by_name = {inst.name: inst for inst in loaded}
        traces = [_trace(by_name[name], sched, f"{name}/{method}") for (name, method), sched in schedules.items()]
        if traces:
            _record(traces, rrd, quiet=as_json)
    if as_json:
        _print_json({"rows": rows, "csv": csv_path})
    else:
        for line in table(rows):
            click.echo(line)
        click.echo(f"written to {csv_path}")
    return EXIT_OK


@cli.command()
@click.argument("instance")
@click.argument("schedules", nargs=-1)
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Write a rerun recording (schedules side by side; open it with 'rerun OUT.rrd').")
@click.option("--spawn", is_flag=True, help="Also open the rerun viewer, where a display exists.")
@click.option("--png", type=click.Path(dir_okay=False), metavar="OUT.png",
              help="Write a picture: one row per schedule, the chosen frames side by side.")
@click.option("--gif", type=click.Path(dir_okay=False), metavar="OUT.gif",
              help="Write an animation of the whole schedule(s).")
@click.option("--frames", default="auto", show_default=True,
              help="Frames of the PNG: auto (start, end, three between), all, end, or numbers like 0,5,9.")
@click.option("--fps", type=click.FloatRange(min=0.1, max=50), default=4.0, show_default=True, help="GIF frames per second.")
@click.option("--cell", type=click.IntRange(4, 256), default=32, show_default=True, help="Pixels per grid cell.")
@click.option("--label", "labels", multiple=True, help="A name per schedule, in order (default: the file names).")
def view(instance: str, schedules, rrd, spawn: bool, png, gif, frames: str, fps: float, cell: int, labels) -> int:
    """Look at SCHEDULES (any number, none for the instance alone) on INSTANCE: a rerun
    recording, a picture or an animation (exit 1 if a schedule breaks a rule)."""
    if not (rrd or spawn or png or gif):
        raise click.UsageError("nothing to do: give --rerun, --spawn, --png or --gif")
    if labels and len(labels) != len(schedules):
        raise click.BadParameter(f"{len(labels)} labels for {len(schedules)} schedules", param_hint="--label")
    _writable(rrd, png, gif)
    inst = _instance(instance)
    names = list(labels) or _unique([_label(arg) for arg in schedules])
    traces = [_trace(inst, _schedule(arg), name) for arg, name in zip(schedules, names)] or [_trace(inst, None, inst.name)]
    if png:
        from .pictures import choose_frames

        choose_frames(frames, max(t.steps for t in traces))  # a bad --frames fails before any file is written
    if rrd or spawn:
        _record(traces, rrd, spawn=spawn)
    if png:
        from .pictures import save_png

        layout = save_png(traces, png, frames, cell)
        click.echo(f"picture written to {png} ({layout.size_px[0]}x{layout.size_px[1]} pixels)")
    if gif:
        from rich.progress import Progress

        from .pictures import save_gif

        with Progress(transient=True, console=_stderr_console()) as bar:
            task = bar.add_task("drawing frames", total=max(t.steps for t in traces) + 1)
            layout = save_gif(traces, gif, fps, cell, progress=lambda done, total: bar.update(task, completed=done))
        click.echo(f"animation written to {gif} ({max(t.steps for t in traces) + 1} frames)")
    bad = [t for t in traces if t.violation is not None]
    for t in bad:
        click.echo(f"{t.label}: invalid: {t.violation}")
    return EXIT_NO if bad else EXIT_OK


def _stderr_console():
    from rich.console import Console

    return Console(stderr=True)


def _writable(*paths) -> None:
    """Fail before any work when an output file cannot be created (a missing folder, a folder
    in its place, no permission)."""
    import os
    from pathlib import Path

    for p in paths:
        if not p:
            continue
        path = Path(p)
        folder = path.parent if str(path.parent) else Path(".")
        if path.is_dir():
            raise BilleError(f"{path}: cannot write (a folder of that name exists)")
        if not folder.is_dir():
            raise BilleError(f"{path}: cannot write (no folder {folder})")
        if not os.access(folder, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
            raise BilleError(f"{path}: cannot write (permission denied)")


def _label(arg: str) -> str:
    from pathlib import Path

    name = Path(arg).name
    for suffix in (".yaml", ".yml"):
        name = name.removesuffix(suffix)
    return name


def _unique(names: list[str]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n}-{seen[n]}")
    return out


def _trace(inst, schedule, label: str):
    from .recording import entity_label
    from .trace import trace

    return trace(inst, schedule, entity_label(label))


def _record(traces, path, *, spawn: bool = False, quiet: bool = False) -> None:
    from .recording import record

    info = record(traces, path, spawn=spawn)
    if info["viewer"]:
        click.echo(f"bille: note: the viewer was not opened: {info['viewer']}", err=True)
    if path and not quiet:
        click.echo(f"recording written to {path} (steps 0..{info['frames'] - 1}, {info['bytes'] / 1e3:.0f} kB)")


def _register_gen() -> None:
    from .execute.commands import robot_sim, run
    from .gen import gen

    cli.add_command(gen)
    cli.add_command(run)
    cli.add_command(robot_sim)


_register_gen()


@cli.group()
def bench() -> None:
    """Benchmarks: figures measured on this machine, with ratios to baselines of the same run."""


@bench.command("core")
@click.option("--size", type=click.IntRange(8, 512), default=64, show_default=True, help="Structure side for validation.")
@click.option("--robots", type=click.IntRange(1, 200), default=20, show_default=True)
@click.option("--steps", type=click.IntRange(1, 100_000), default=1000, show_default=True)
@click.option("--compile-size", type=click.IntRange(8, 1024), default=128, show_default=True, help="Structure side for compiling.")
@click.option("--seed", type=int, default=0, show_default=True)
def bench_core(size: int, robots: int, steps: int, compile_size: int, seed: int) -> int:
    """Time the validator on a long random schedule and the pose-table compiler."""
    from .bench_core import report

    for line in report(size, robots, steps, compile_size, seed):
        click.echo(line)
    return EXIT_OK


@bench.command("execute")
@click.option("--robots", "sizes", default="10,50", show_default=True, help="Comma-separated fleet sizes (1 is the baseline).")
@click.option("--steps", type=click.IntRange(2, 100_000), default=200, show_default=True)
@click.option("--broker", metavar="URL", help="mqtt://host:port (default: the embedded broker).")
def bench_execute(sizes: str, steps: int, broker: str | None) -> int:
    """Steps per second and round-trip latency of the execution layer with simulated robots."""
    from .bench_execute import report
    from .execute.broker import parse_url

    try:
        counts = sorted({int(s) for s in sizes.split(",") if s.strip()})
    except ValueError:
        raise click.BadParameter(f"{sizes!r}: expected numbers like 10,50", param_hint="--robots") from None
    if not counts or counts[0] < 1:
        raise click.BadParameter(f"{sizes!r}: fleet sizes must be at least 1", param_hint="--robots")
    if broker:
        parse_url(broker)
    for line in report(counts, steps, broker):
        click.echo(line)
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
    """The paper's planner comparison: A*, M*, Temporal A* on the comparison maps."""
    from pathlib import Path

    from .bench_planners import default_jobs, plot, run_grid, tables, write_csv

    names = [m.strip() for m in maps.split(",") if m.strip()]
    for name in names:
        bundled_path(name)  # unknown names fail here, before any work
    sets = [m.strip() for m in movesets.split(",") if m.strip()]
    for ms in sets:
        if ms not in ("S5", "S7", "point"):
            raise click.BadParameter(f"unknown moveset {ms!r}", param_hint="--movesets")
    folder = Path(out)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BilleError(f"{folder}: cannot create the output folder ({exc.strerror})") from None
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
@click.option("--only", type=click.Choice(["optimum", "connectivity", "pruning", "presolve"]), multiple=True,
              help="Run only these sections (repeatable).")
def bench_exact(time_limit: float, threads: int, only) -> int:
    """Exact solvers: time to optimum per map, eager vs lazy connectivity, pruning, presolve."""
    from .bench_exact import report

    report(time_limit, threads, only or ("optimum", "connectivity", "pruning", "presolve"), echo=click.echo)
    return EXIT_OK


@bench.command("hampath")
@click.option("--size", type=click.IntRange(2, 40), default=10, show_default=True, help="Largest grid graph side.")
@click.option("--scale", "-s", type=click.IntRange(min=1), default=1, show_default=True)
@click.option("--robots", "-m", type=click.IntRange(min=1), default=1, show_default=True)
def bench_hampath(size: int, scale: int, robots: int) -> int:
    """Time and size of Theorem 1's instance for k x k grid graphs up to SIZE."""
    from .bench_gen import report

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
    from .bench_view import report

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
@click.option("--out", type=click.Path(file_okay=False), default="bench-out", show_default=True,
              help="Folder for load-transfer.csv and load-transfer.png.")
def bench_load_transfer(maps: str, horizon: int, d_tr: int, time_limit: float, random_runs: int, exact_limit: float,
                        out: str) -> int:
    """The paper's load-transfer experiment: each map with and without load transfer (Temporal A*,
    epsilon 1), the percentage decrease in time steps and tiles traveled, and a bar plot."""
    from pathlib import Path

    from .bench_transfer import plot, random_report, run_maps, table, write_csv

    names = [m.strip() for m in maps.split(",") if m.strip()]
    instances = [_instance(name) for name in names]  # unknown names fail here, before any work
    folder = Path(out)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BilleError(f"{folder}: cannot create the output folder ({exc.strerror})") from None
    rows = run_maps(instances, horizon, d_tr, time_limit)
    for line in table(rows):
        click.echo(line)
    write_csv(rows, folder / "load-transfer.csv")
    plot(rows, folder / "load-transfer.png")
    click.echo(f"wrote {folder / 'load-transfer.csv'} and {folder / 'load-transfer.png'}")
    if random_runs:
        for line in random_report(random_runs, horizon, d_tr, time_limit, exact_limit):
            click.echo(line)  # one line per size as soon as it is measured
    return EXIT_OK


@bench.command("crowd")
@click.option("--size", type=click.IntRange(8, 512), default=64, show_default=True)
@click.option("--robots", type=click.IntRange(1, 1000), default=50, show_default=True)
@click.option("--horizon", "-H", type=click.IntRange(min=1), default=5, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True)
def bench_crowd(size: int, robots: int, horizon: int, seed: int) -> int:
    """Temporal A* with many robots: mean replanning time per step."""
    from .bench_planners import bench_crowd as run

    for line in run(size, robots, horizon, seed):
        click.echo(line)
    return EXIT_OK


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bille`` console script."""
    try:
        code = cli.main(args=argv, prog_name="bille", standalone_mode=False)
    except click.exceptions.UsageError as exc:
        cmd = exc.ctx.command_path if exc.ctx else "bille"
        click.echo(f"{cmd}: {exc.format_message().rstrip('.')} (see '{cmd} --help')", err=True)
        code = EXIT_USAGE
    except click.exceptions.Abort:
        click.echo("bille: aborted", err=True)
        code = 130
    except BilleError as exc:
        click.echo(f"bille: error: {exc}", err=True)
        code = EXIT_USAGE
    except BrokenPipeError:
        code = EXIT_OK
    sys.exit(code if isinstance(code, int) else EXIT_OK)


if __name__ == "__main__":
    main()
