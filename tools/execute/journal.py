"""The executor's journal: one JSON line per event, flushed to disk before the executor goes on.

Events: ``run`` (the instance, schedule, fleet and robots, with SHA-256 of both files),
``released`` and ``finished`` (one line per step), ``fault``, ``replan`` (a new schedule for the
steps after ``step``), ``resume`` and ``done``. :func:`replay` rebuilds the executed plan and
the world after the last finished step from the journal alone; ``bille run --resume`` starts from
there, so no step is released again once it is journaled as finished.
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bille.instances import BilleError, load_instance
from bille.instances.rules import State, Violation, run
from bille.solvers import bind, load_schedule

from .protocol import ExecutionError, now


def sha256_file(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


class Journal:
    """Appends events to ``path``; every line is flushed and synced before :meth:`write` returns."""

    def __init__(self, path: str | Path, *, append: bool = False):
        self.path = Path(path)
        if append:
            _drop_cut_line(self.path)
        try:
            self._file = open(self.path, "a" if append else "x", encoding="utf-8")
        except FileExistsError:
            raise ExecutionError(f"--journal: {self.path} exists (resume it with --resume, or remove it)") from None
        except OSError as exc:
            raise ExecutionError(f"--journal: {self.path}: cannot write ({exc.strerror})") from None
        self.events = 0

    def write(self, event: str, **fields) -> None:
        self.events += 1
        self._file.write(json.dumps({"event": event, "time": now(), **fields}) + "\n")
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()

    def discard(self) -> None:
        """Remove a journal that holds no more than its ``run`` line (a run that never started)."""
        self._file.close()
        if self.events <= 1:
            self.path.unlink(missing_ok=True)


def _drop_cut_line(path: Path) -> None:
    """Remove a last line that a crash cut short, so that appended events start on their own line."""
    try:
        data = path.read_bytes()
    except OSError:
        return  # reported when the file is opened
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)


@dataclass
class Replayed:
    """What a journal says: the run's settings, the plan executed so far (action ids, one column
    per step), the world after each step, and the last released and finished steps."""

    run: dict
    instance: object
    plan: np.ndarray
    states: list[State]
    released: int
    finished: int
    done: bool


def read_events(path: str | Path) -> list[dict]:
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise ExecutionError(f"{path}: not a bille run journal (not UTF-8 text, byte {exc.start})") from None
    except OSError as exc:
        raise ExecutionError(f"{path}: cannot read the journal ({exc.strerror})") from None
    events = []
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            event = json.loads(line)
        except ValueError:
            if n == len(lines):  # a line cut short by a crash: the event never happened
                break
            raise ExecutionError(f"{path}:{n}: not a journal line (expected one JSON object)") from None
        if not isinstance(event, dict) or "event" not in event:
            raise ExecutionError(f"{path}:{n}: not a journal event")
        events.append(event)
    if not events or events[0]["event"] != "run":
        raise ExecutionError(f"{path}: not a bille run journal (the first line must be a 'run' event)")
    return events


def plan_states(instance, plan: np.ndarray, what: str, start: State | None = None) -> list[State]:
    """The world after each step of ``plan`` from ``start`` (default: the instance's start),
    which is index 0. Raises :class:`ExecutionError` if a step breaks the rules."""
    states = [instance.start_state if start is None else start]
    for out in run(instance.world, states[0], plan):
        if isinstance(out, Violation):
            raise ExecutionError(f"{what}: {out}")
        states.append(out)
    return states


def replay(path: str | Path) -> Replayed:
    """Rebuild a run from its journal (see the module docstring)."""
    events = read_events(path)
    head = events[0]
    for key in ("instance", "schedule"):
        file = head[key]
        try:
            if sha256_file(file) != head[f"{key}_sha256"]:
                raise ExecutionError(f"{path}: {file} changed since the run started (its SHA-256 differs)")
        except OSError as exc:
            raise ExecutionError(f"{path}: cannot read the run's {key} {file} ({exc.strerror})") from None
    try:
        instance = load_instance(head["instance"])
        plan = bind(instance, load_schedule(head["schedule"]))
    except BilleError as exc:
        raise ExecutionError(f"{path}: {exc}") from None
    released = finished = 0
    done = False
    for event in events[1:]:
        kind = event["event"]
        if kind == "released":
            released = max(released, event["step"])
        elif kind == "finished":
            finished = max(finished, event["step"])
        elif kind == "replan":
            if sha256_file(event["schedule"]) != event["schedule_sha256"]:
                raise ExecutionError(f"{path}: {event['schedule']} changed since it was journaled")
            tail = bind(instance, load_schedule(event["schedule"]))
            plan = np.concatenate([plan[:, : event["step"]], tail], axis=1)
        elif kind == "done":
            done = True
    states = plan_states(instance, plan, f"{path}: the journaled plan")
    return Replayed(head, instance, plan, states, released, finished, done)
