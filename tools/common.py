"""What the commands share: loading arguments, output checks, JSON, recordings, exit codes."""
from __future__ import annotations

import json
import os
from pathlib import Path

import click

from bille.instances import BilleError, InstanceError, ScheduleError, load_instance
from bille.instances.claim import shown_status
from bille.instances.bundled import resolve
from bille.solvers import load_schedule

EXIT_OK, EXIT_NO, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


def instance_arg(arg: str, *, check: bool = True):
    """An instance from a file or a bundled name: bille YAML, libMultiRobotPlanning YAML (named
    ``*.mrp.yaml``, or recognized by its ``map`` and ``agents``) or a MovingAI ``.scen`` (every
    agent of it, on the ``.map`` it names)."""
    from bille.instances.yamlsource import load_yaml_file, mrp_name

    path = resolve(arg, InstanceError)
    if path.suffix == ".scen":
        from bille.instances.generators.movingai import from_movingai, scen_map

        return from_movingai(scen_map(path), path, agents=None, name=path.stem)
    if not mrp_name(path):
        try:
            return load_instance(path, check=check)
        except InstanceError:
            from bille.instances.interop import is_mrp

            if not is_mrp(_yaml_or_none(path)):
                raise
    from bille.instances.interop import from_mrp

    data, src = load_yaml_file(path, InstanceError)
    return from_mrp(data, path.name.split(".")[0], src)


def _yaml_or_none(path: Path):
    """The YAML data of ``path``, None if it cannot be read as YAML."""
    from bille.instances.yamlsource import load_yaml_file

    try:
        return load_yaml_file(path, InstanceError)[0]
    except InstanceError:
        return None


def schedule_arg(arg: str):
    """A schedule from a file or a bundled name."""
    return load_schedule(resolve(arg, ScheduleError))


def schedule_for(arg: str, instance):
    """A schedule for ``instance``: where it names another instance, a warning on stderr."""
    from bille.instances.schedule import written_for

    schedule = schedule_arg(arg)
    why = written_for(instance, schedule)
    if why is not None:
        click.echo(f"warning: {why}", err=True)
    return schedule


def robots(count: int) -> str:
    """``"1 robot"``, ``"3 robots"``."""
    return f"{count} robot" + ("" if count == 1 else "s")


JSON_PRINTED = [False]  # whether this process printed its JSON object (an interrupt then prints none)


def print_json(obj) -> None:
    click.echo(json.dumps(obj))
    JSON_PRINTED[0] = True


def interrupted_json(argv: list[str]) -> None:
    """With ``--json`` among ``argv`` and no JSON object printed yet, the one object of an
    interrupted command (Ctrl-C before it had anything to say)."""
    if "--json" in argv and not JSON_PRINTED[0]:
        print_json({"status": "interrupted",
                    "failure": {"kind": "interrupted", "text": "interrupted before the command finished"}})


def stderr_console():
    from rich.console import Console

    return Console(stderr=True)


class LiveLine:
    """One line on the terminal while a solve runs, from its first second: the method, the
    bound and the best makespan known, the horizon being decided, the seconds elapsed (a
    ``rich.progress`` line on stderr, only when it is a terminal; silent otherwise, and with
    ``--json``). Used as a context manager and as the ``progress`` of ``solve()``."""

    def __init__(self, method: str, enabled: bool) -> None:
        import sys

        self.method, self.stream = method, sys.stderr
        self.enabled = enabled and self.stream.isatty()
        self.lower = self.best = self.horizon = None
        self.bar = None

    def __enter__(self) -> "LiveLine":
        if self.enabled:
            from rich.console import Console
            from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

            self.bar = Progress(SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
                                console=Console(file=self.stream), transient=True, refresh_per_second=4)
            self.task = self.bar.add_task(self._text())
            self.bar.start()
        return self

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None

    def __call__(self, event: dict) -> None:
        if "horizon" in event:
            self.horizon = f"horizon {event['horizon']} {event['answer']} in {event['time_s']:.1f} s"
        else:
            self.lower = self.lower if event.get("lower") is None else event["lower"]
            self.best = self.best if event.get("best") is None else event["best"]
        if self.bar is not None:
            self.bar.update(self.task, description=self._text())

    def _text(self) -> str:
        text = f"{self.method}: makespan lower bound {'-' if self.lower is None else self.lower}, best schedule "
        text += "none yet" if self.best is None else str(self.best)
        return text + ("" if self.horizon is None else f"; {self.horizon}")


class EventLog:
    """``bille solve --log FILE``: every event of the run (``solve()``'s ``on_schedule``,
    ``on_bound`` and ``progress``) as one JSON line, with ``t``, the seconds since the log was
    opened, and ``event``: ``schedule`` (its ``makespan``), ``bound`` (a makespan ``lower`` bound
    proved for every schedule) or ``progress`` (what the method tells: ``lower`` and ``best``
    where it knows them, and its own counters such as ``depth``, ``states``, ``steps``,
    ``expanded``, ``cost``). Each line is flushed as it is written, so the file can be followed
    while the run goes on. Without a path it writes nothing; used as a context manager."""

    def __init__(self, path: str | None, also=None) -> None:
        self.path, self.also, self.file, self.lines = path, also, None, 0

    def __enter__(self) -> "EventLog":
        import time

        if self.path:
            self.file = open(self.path, "w", encoding="utf-8")
        self.began = time.monotonic()
        return self

    def __exit__(self, kind, *exc) -> None:
        if self.file is not None:
            self.file.close()
            self.file = None
            if kind is not None and self.lines == 0:  # refused before it ran: no empty file left behind
                os.remove(self.path)

    def _write(self, event: str, data: dict) -> None:
        import time

        if self.file is not None:
            line = {"t": round(time.monotonic() - self.began, 6), "event": event, **data}
            self.file.write(json.dumps(line, default=_plain) + "\n")
            self.file.flush()
            self.lines += 1

    def schedule(self, found) -> None:
        makespan = getattr(found, "makespan", None)
        self._write("schedule", {"makespan": int(found.length if makespan is None else makespan)})

    def bound(self, value: int) -> None:
        self._write("bound", {"lower": int(value)})

    def progress(self, info: dict) -> None:
        self._write("progress", dict(info))
        if self.also is not None:
            self.also(info)


def _plain(value):
    """numpy numbers and anything else JSON does not know, as a JSON value."""
    return value.item() if hasattr(value, "item") else str(value)


def writable(*paths) -> None:
    """Fail before any work when an output file cannot be created (a missing folder, a folder
    in its place, no permission)."""
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


def label_of(arg: str) -> str:
    """A schedule's label from its file name, without the YAML suffix."""
    name = Path(arg).name
    for suffix in (".yaml", ".yml"):
        name = name.removesuffix(suffix)
    return name


def unique(names: list[str]) -> list[str]:
    """The names, a repeated one numbered (``plan``, ``plan-2``)."""
    seen: dict[str, int] = {}
    out = []
    for n in names:
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n}-{seen[n]}")
    return out


def trace_of(inst, schedule, label: str):
    """A schedule's trace for recordings and pictures, labelled as given (a recording makes the
    label an entity path itself)."""
    from .trace import trace

    return trace(inst, schedule, label)


def record_traces(traces, path, *, spawn: bool = False, quiet: bool = False) -> None:
    """Write the traces to a rerun recording at ``path`` (and say so unless ``quiet``)."""
    from .recording import record

    info = record(traces, path, spawn=spawn)
    if info["viewer"]:
        click.echo(f"bille: note: the viewer was not opened: {info['viewer']}", err=True)
    if path and not quiet:
        click.echo(f"recording written to {path} (steps 0..{info['frames'] - 1}, {info['bytes'] / 1e3:.0f} kB)")


def output_folder(out: str) -> Path:
    """The folder ``out``, created if needed; one clear error if it cannot be."""
    folder = Path(out)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BilleError(f"{folder}: cannot create the output folder ({exc.strerror})") from None
    return folder


def status_text(result) -> str:
    """The status as the user reads it: ``optimal`` names its claim where it is not the makespan
    over every schedule (``optimal (sum of costs)``)."""
    return shown_status(result.status, result.claim)


def summary_line(label: str, result) -> str:
    """One line: the status, the time, the schedule's metrics (the sum of costs where robots have
    goal cells), the sum-of-costs bound a method proved short of an optimum, and the makespan
    lower bound (or that none was computed)."""
    m = result.metrics
    text = f"{label}: {status_text(result)} in {result.time_s:.3f} s"
    if m is not None:
        unproved = " (not minimized)" if result.stats.get("tiles_traveled_optimal") is False else ""
        soc = "" if m.sum_of_costs is None else f"sum of costs {m.sum_of_costs}, "
        text += f"; {soc}makespan {m.makespan}, tiles traveled {m.tiles_traveled}{unproved}, waits {m.waits}"
    claim = result.claim
    if claim.objective == "sum-of-costs" and claim.lower is not None and result.status != "optimal":
        walking = " over walking-only schedules" if claim.walking_only else ""
        text += f"; sum of costs >= {claim.lower}{walking} (proved)"
    if result.lower_bound is not None:
        text += f"; makespan lower bound {result.lower_bound}"
    elif result.status != "infeasible":
        text += "; no makespan lower bound computed (--bound to compute one)"
    return text


def exit_code(result) -> int:
    """130 for ``interrupted`` (what was found is printed and written all the same), 0 with a
    schedule, 1 without."""
    if result.status == "interrupted":
        return EXIT_INTERRUPTED
    return EXIT_OK if result.schedule is not None else EXIT_NO


def solved(result):
    """``result``, or Ctrl-C passed on when the user stopped it (``interrupted``): a loop of
    solves, such as a benchmark, stops with the solve that was stopped."""
    if result.status == "interrupted":
        raise KeyboardInterrupt
    return result
