"""Commands that solve: ``solve`` one instance, ``plan-sequence``, and the ``gap`` report."""
from __future__ import annotations

import os

import click
import yaml

from bille.solvers import METHODS, save_schedule, solve
from bille.solvers.options import check_options, gather_options

from .common import (EXIT_INTERRUPTED, EXIT_NO, EXIT_OK, EventLog, LiveLine, exit_code, instance_arg, label_of,
                     print_json, record_traces, schedule_arg, summary_line, trace_of, writable)


@click.command("solve")
@click.argument("instance")
@click.option("--method", "-m", type=click.Choice(list(METHODS)), default="auto", show_default=True,
              help="auto: the brute force with proof on a small joint state space, cbs on classic MAPF, anytime "
                   "otherwise. 'bille methods' lists what each method proves.")
@click.option("--epsilon", type=click.FloatRange(min=1.0), help="Heuristic weight (astar, mstar, temporal-astar).")
@click.option("--horizon", "-H", type=click.IntRange(min=1), help="Steps planned ahead (temporal-astar).")
@click.option("--time-limit", type=float, help="Seconds for the whole call, the lower bound included (default: "
              "the method's own, see 'bille methods METHOD').")
@click.option("--threads", type=click.IntRange(min=1), help="CP-SAT workers (cpsat; default 1: repeatable results).")
@click.option("--load-transfer", is_flag=True, default=None,
              help="Reconfiguration (temporal-astar, mstar, lacam): robots exchange loads (paper, equations 1-3).")
@click.option("--d-tr", type=click.IntRange(min=0),
              help="Manhattan distance within which robots consider a load transfer.")
@click.option("--bound", is_flag=True,
              help="Also compute the static makespan lower bound where the method does not use it (the heuristics).")
@click.option("-O", "--option", "extra", multiple=True, metavar="NAME=VALUE",
              help="Another option of the method, e.g. -O od=false or -O max_steps=200.")
@click.option("--incumbent", metavar="SCHEDULE",
              help="A valid schedule to start from (cpsat, sat, anytime): it caps the search and is "
                   "returned if time runs out.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the schedule here.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Write a rerun recording of the schedule found.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
@click.option("--log", "log_path", type=click.Path(dir_okay=False), metavar="FILE",
              help="Write the run's events (schedules found, bounds proved, progress) here, one JSON line each.")
def solve_(instance: str, method: str, epsilon, horizon, time_limit, threads, load_transfer, d_tr, bound, extra,
           incumbent, output, rrd, as_json, log_path) -> int:
    """Solve INSTANCE with METHOD; print the status and metrics (exit 1 if no schedule).

    On an instance that moves tiles, temporal-astar and mstar run the reconfiguration loop: the
    instance's tasks (or a derived sequence) are handed to the robots and carried out.

    Ctrl-C stops the solve: the best schedule found so far is printed and written, with the best
    lower bound proved, and the exit code is 130."""
    if time_limit is not None and time_limit <= 0:
        raise click.BadParameter("must be positive", param_hint="--time-limit")
    if "help" in extra:  # -O help: the method's options, nothing solved
        return _option_help(method, as_json)
    writable(output, rrd, log_path)
    flags = (("--epsilon", "epsilon", epsilon), ("-H/--horizon", "horizon", horizon),
             ("--time-limit", "time_limit", time_limit), ("--threads", "threads", threads),
             ("--load-transfer", "load_transfer", load_transfer), ("--d-tr", "d_tr", d_tr))
    given = [(f"{flag} {_shown(value)}" if value is not True else flag, name, value) for flag, name, value in flags
             if value is not None]
    options = gather_options(method, given + _parse_options(extra))
    check_options(method, options)  # before the instance is read, and -O never reaches solve()'s own arguments
    inst = instance_arg(instance)
    if incumbent is not None:
        options["incumbent"] = schedule_arg(incumbent)
    with LiveLine(method, not as_json) as line, EventLog(log_path, also=line) as log:
        result = solve(inst, method, progress=log.progress, on_schedule=log.schedule, on_bound=log.bound,
                       bound=bound, **options)
    if output and result.schedule is not None:
        save_schedule(result.schedule, output)
    elif output and os.path.exists(output):  # never a stale file taken for this run's answer
        click.echo(f"no schedule: {output} left as it was, not written by this run", err=True)
    if rrd:  # without a schedule the recording shows the instance
        record_traces([trace_of(inst, result.schedule, method)], rrd, quiet=as_json)
    if as_json:
        schedule = None if result.schedule is None else [list(row) for row in result.schedule.actions]
        print_json({**result.to_json(), "schedule": schedule})
        return exit_code(result)
    for line in _result_lines(inst, method, result):
        click.echo(line)
    if output and result.schedule is not None:
        click.echo(f"schedule written to {output}")
    return exit_code(result)


def _option_help(method: str, as_json: bool) -> int:
    """``-O help``: the method's options (text or JSON), nothing solved."""
    from .methods_command import describe, described

    if method not in METHODS:
        raise click.BadParameter(f"unknown method '{method}' (expected one of: {', '.join(METHODS)})",
                                 param_hint="-m/--method")
    if as_json:
        print_json(described(method))
        return EXIT_OK
    for line in describe(method):
        click.echo(line)
    return EXIT_OK


def _ladder_lines(rows: list[dict]) -> list[str]:
    """anytime's widening ladder (docs/anytime.md): each rung's class and what it proved."""
    lines = ["widening ladder (the class that keeps the structure, and may change the cells listed):"]
    for row in rows:
        cells = "no-scaffold (its top, every cell where the start or the goal has a tile)" \
            if row.get("cells") == "no-scaffold" else "+" + "".join(f"({x},{y})" for x, y in row["add_cells"])
        if "optimum" in row:
            said = f"optimal {row['optimum']}"
        elif row.get("decided", True):
            said = f">= {row['lower_bound']} (nothing shorter than the best schedule then)"
        else:
            said = f">= {row['lower_bound']} (stopped)"
        lines.append(f"  {cells}: {said}, {row['s']:.1f} s")
    return lines


def _result_lines(inst, method: str, result) -> list[str]:
    """The text ``bille solve`` prints of a result: the summary, then what the claim means (the
    objective, the class bounds), why it stopped, and the load transfers."""
    stats = result.stats
    lines = [summary_line(method, result)]
    if "auto" in stats:
        lines.append(f"auto chose {stats['auto']['method']}: {stats['auto']['why']}")
    claim = result.claim
    if not claim.unconditional:  # what optimal means when it is not the makespan of every schedule
        lines.append(f"objective: {claim.text()}")
        if claim.lower is not None and claim.objective == "makespan":
            lines.append(f"lower bound among those schedules: {claim.lower}")
    if "class_bounds" in stats:
        from bille.solvers.bounds.classes import report

        makespan = result.metrics.makespan if result.metrics else None
        lines += report(makespan, result.lower_bound, stats["class_bounds"], stats.get("classes"))
    if stats.get("ladder"):
        lines += _ladder_lines(stats["ladder"])
    if "unreachable" in stats:
        lines.append("unreachable: " + "; ".join(f"robot {i} cannot reach its goal {inst.robot_goals[i]} even alone"
                                                 for i in stats["unreachable"]))
    if result.failure is not None:
        lines.append(f"failure: {_explain(result.failure)}")
    lines += [f"{key}: {stats[key]}" for key in ("stopped", "reason", "violation") if key in stats]
    if stats.get("load_transfer"):
        counts = result.counters
        lines.append(f"load transfers: {counts.relays} relays, {counts.swaps} swaps "
                     f"({counts.pairs_considered} robot pairs within d_tr considered)")
    return lines


@click.command("plan-sequence")
@click.argument("instance")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
def plan_sequence(instance: str, as_json: bool) -> int:
    """Print the reconfiguration sequence of INSTANCE: its tasks (checked), or one derived so
    that running it one task at a time keeps the structure connected."""
    from bille.heuristics.loop.sequence import NoSequence, sequence_of

    inst = instance_arg(instance)
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
        print_json({"instance": inst.name, "source": source, "tasks": rows})
        return EXIT_OK
    click.echo(f"{inst.name}: {len(jobs)} tasks ({source}); each keeps the structure connected when run in order")
    click.echo("tasks:")
    for j in jobs:
        if j.pick is None:
            click.echo(f"  - {{place: {list(xy(j.place))}}}  # the tile robot {j.carrier} carries at the start")
        else:
            click.echo(f"  - {{pick: {list(xy(j.pick))}, place: {list(xy(j.place))}}}")
    return EXIT_OK


def _parse_options(items) -> list[tuple[str, str, object]]:
    """``-O NAME=VALUE`` items -> ``(label, name, value)`` triples, values read as YAML."""
    out = []
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise click.BadParameter(f"expected NAME=VALUE, got {item!r}", param_hint="-O/--option")
        try:
            out.append((f"-O {item}", name, _number(yaml.safe_load(value))))
        except yaml.YAMLError:
            raise click.BadParameter(f"cannot read the value of {item!r}", param_hint="-O/--option") from None
    return out


def _shown(value) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def _number(value):
    """YAML 1.1 reads ``1e3`` (no dot, no sign) as text: a number written so is a number."""
    if isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            return value
        return int(number) if number.is_integer() and "." not in value and "e" not in value.lower() else number
    return value


def _explain(failure) -> str:
    """A failure as ``bille solve`` prints it: a heuristic that gave up says what to try."""
    if failure.kind == "stuck":
        complete = "-m auto or -m lacam (complete: it finds a schedule whenever one exists)"
        return f"{failure.text}: the planner gave up, which proves nothing (it is not complete); try {complete}"
    return failure.text


@click.command()
@click.argument("instances", nargs=-1)
@click.option("--methods", multiple=True, default=("auto,temporal-astar,mstar,astar",), show_default=True,
              help="Comma-separated method configurations: NAME or NAME:OPTION=VALUE,OPTION=VALUE "
                   "(e.g. temporal-astar:H=10,load_transfer=true,mstar); repeatable, each one read on its own.")
@click.option("--schedule", "schedule_files", multiple=True, metavar="SCHEDULE",
              help="Also a schedule file as a row, on every instance with its number of robots (repeatable).")
@click.option("--time-limit", type=click.FloatRange(min=0, min_open=True), default=60.0, show_default=True,
              help="Seconds per method and instance.")
@click.option("--threads", type=click.IntRange(min=1), default=1, show_default=True,
              help="CP-SAT workers (cpsat rows; 1: repeatable results).")
@click.option("--csv", "csv_path", type=click.Path(dir_okay=False), default="gap.csv", show_default=True,
              help="Where to write the table as CSV.")
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Write every schedule found to one rerun recording, side by side per instance.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of the table.")
@click.option("--wide", is_flag=True, help="Every column of the table (classes of schedules, notes), wider than 120.")
def gap(instances, methods: tuple[str, ...], schedule_files, time_limit: float, threads: int, csv_path: str, rrd: str | None,
        as_json: bool, wide: bool) -> int:
    """How far methods are from the optimum: one table over INSTANCES (default: the bundled
    point-4) with each schedule's makespan, the best lower bound proved in the run, and the
    certified gap (makespan - bound) / bound; then a summary per method. An optimum or bound in
    the instance's metadata is shown as the file's claim, never used as a proof.
    By default auto (the best schedule with the proof it can get) is the reference, against the
    paper's heuristics. Ctrl-C shows and writes the rows finished (exit 130)."""
    from pathlib import Path

    from bille.instances import OptionError

    from .gap import Interrupted, check_files, parse_configs, json_row, run, summary, table, write_csv

    try:
        configs = parse_configs(methods)
    except OptionError as exc:
        raise click.BadParameter(str(exc), param_hint="--methods") from None
    writable(csv_path, rrd)
    loaded = [instance_arg(arg) for arg in (instances or ("point-4",))]
    files = {label_of(f): schedule_arg(f) for f in schedule_files}
    try:
        check_files(loaded, files)
    except OptionError as exc:
        raise click.BadParameter(str(exc), param_hint="--schedule") from None

    def progress(inst, method):
        if not as_json:
            click.echo(f"  running {method} on {inst} ...", err=True)

    schedules: dict = {}
    interrupted = False
    try:
        rows = run(loaded, configs, time_limit, threads, progress, schedules=schedules, files=files)
    except Interrupted as stop:  # what was found is shown and written all the same
        rows, interrupted = stop.rows, True
    write_csv(rows, Path(csv_path))
    if rrd:
        by_name = {inst.name: inst for inst in loaded}
        traces = [trace_of(by_name[name], sched, f"{name}/{method}") for (name, method), sched in schedules.items()]
        if traces:
            record_traces(traces, rrd, quiet=as_json)
    if as_json:
        print_json({"rows": [json_row(r) for r in rows], "csv": csv_path, "interrupted": interrupted})
    else:
        for line in table(rows, wide):
            click.echo(line)
        click.echo("")
        for line in summary(rows):
            click.echo(line)
        click.echo(f"written to {csv_path}" + (f" and {rrd}" if rrd else ""))
    if interrupted:
        shown = "the row so far is" if len(rows) == 1 else f"the {len(rows)} rows so far are"
        click.echo(f"bille gap: interrupted; {shown} shown and written", err=True)
        return EXIT_INTERRUPTED
    return EXIT_OK
