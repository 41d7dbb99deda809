"""The executor's journal: one JSON line per event, flushed to disk before the executor goes on.

Events: ``run`` (the instance, schedule, fleet and robots, with SHA-256 of both files),
``released`` and ``finished`` (one line per step), ``fault``, ``replan`` (a new schedule for the
steps after ``step``), ``resume`` and ``done``. :func:`replay` rebuilds the executed plan and
the world after the last finished step from the journal alone; ``bille run --resume`` starts from
there, so no step is released again once it is journaled as finished.

A journal is checked before it is trusted (:func:`replay`): the events in the order an executor
writes them, each ``finished`` step released before, every step within the plan, both files'
SHA-256 as journaled. With a fleet secret (``BILLE_FLEET_SECRET``) every line carries
``signature``, the HMAC-SHA256 of the previous line's signature and the line's canonical JSON
without it, so a changed, removed or reordered line is detected.
"""
from __future__ import annotations

import hashlib
import hmac
import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bille.instances import BilleError, load_instance
from bille.instances.rules import State, Violation, run
from bille.solvers import bind, load_schedule

from .protocol import ExecutionError, canonical, is_signature, now

SECRET_ENV = "BILLE_FLEET_SECRET"
EVENTS = ("run", "released", "finished", "fault", "replan", "resume", "done")


def sha256_file(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def fleet_secret() -> bytes | None:
    """The fleet secret that signs journals, from ``BILLE_FLEET_SECRET`` (None when unset)."""
    value = os.environ.get(SECRET_ENV)
    return value.encode() if value else None


def line_signature(secret: bytes, previous: str, event: dict) -> str:
    """The HMAC-SHA256 of the previous line's signature and this event's canonical JSON."""
    body = {k: v for k, v in event.items() if k != "signature"}
    return hmac.new(secret, previous.encode() + b"\n" + canonical(body), hashlib.sha256).hexdigest()


class Journal:
    """Appends events to ``path``; every line is flushed and synced before :meth:`write` returns.
    With ``secret`` each line is signed, chained on ``previous`` (the last signature of the
    journal appended to)."""

    def __init__(self, path: str | Path, *, append: bool = False, secret: bytes | None = None, previous: str = ""):
        self.path = Path(path)
        self.secret, self.previous = secret, previous
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
        line = {"event": event, "time": now(), **fields}
        if self.secret is not None:
            line["signature"] = self.previous = line_signature(self.secret, self.previous, line)
        self._file.write(json.dumps(line) + "\n")
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
    per step), the world after each step, the last released and finished steps, and the last
    line's signature (to chain appended lines on)."""

    run: dict
    instance: object
    plan: np.ndarray
    states: list[State]
    released: int
    finished: int
    done: bool
    signature: str = ""


def _no_constant(name: str):
    raise ValueError(name)


def read_events(path: str | Path, secret: bytes | None = None) -> list[dict]:
    """The journal's events with their line numbers (``_line``). With ``secret``, every line's
    signature is checked; without, a signed journal is refused (its secret is needed)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
    except UnicodeDecodeError as exc:
        raise ExecutionError(f"{path}: not a bille run journal (not UTF-8 text, byte {exc.start})") from None
    except OSError as exc:
        raise ExecutionError(f"{path}: cannot read the journal ({exc.strerror})") from None
    events = []
    previous = ""
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            event = json.loads(line, parse_constant=_no_constant)
        except (ValueError, RecursionError):
            if n == len(lines) and not text.endswith("\n"):  # cut short by a crash: the event never happened
                break
            raise ExecutionError(f"{path}:{n}: not a journal line (expected one JSON object)") from None
        if not isinstance(event, dict) or event.get("event") not in EVENTS:
            raise ExecutionError(f"{path}:{n}: not a journal event (expected 'event': one of {', '.join(EVENTS)})")
        sig = event.get("signature")
        if secret is not None:
            if not isinstance(sig, str):
                raise ExecutionError(f"{path}:{n}: the line is not signed, but a fleet secret is set ({SECRET_ENV})")
            if not is_signature(sig) or not hmac.compare_digest(sig, line_signature(secret, previous, event)):
                raise ExecutionError(f"{path}:{n}: bad signature (the line was changed, moved or removed, or "
                                     f"{SECRET_ENV} is not the fleet secret the run was signed with)")
            previous = sig
        elif sig is not None:
            raise ExecutionError(f"{path}:{n}: the journal is signed: set {SECRET_ENV} to the fleet secret to resume it")
        event["_line"] = n
        events.append(event)
    if not events or events[0]["event"] != "run":
        raise ExecutionError(f"{path}: not a bille run journal (the first line must be a 'run' event)")
    if any(e["event"] == "run" for e in events[1:]):
        n = next(e["_line"] for e in events[1:] if e["event"] == "run")
        raise ExecutionError(f"{path}:{n}: a second 'run' event (one journal holds one run)")
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


# the fields of each event and their types (the executor writes more; these are relied on)
_HEAD = {"instance": str, "instance_sha256": str, "schedule": str, "schedule_sha256": str, "fleet": str,
         "robots": list, "simulated": bool, "steps": int}


def _check_head(head: dict, where: str) -> None:
    for key, kind in _HEAD.items():
        value = head.get(key)
        if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
            raise ExecutionError(f"{where}: field '{key}': expected {kind.__name__}, got {value!r}"[:300])
    if not head["robots"] or not all(isinstance(r, str) and r for r in head["robots"]):
        raise ExecutionError(f"{where}: field 'robots': expected a list of robot ids")
    for key in ("broker", "secrets"):
        if head.get(key) is not None and not isinstance(head[key], str):
            raise ExecutionError(f"{where}: field '{key}': expected a string or null")


def _step(event: dict, where: str, key: str = "step") -> int:
    value = event.get(key)
    if not isinstance(value, int) or isinstance(value, bool):
        raise ExecutionError(f"{where}: field '{key}': expected a whole number, got {value!r}"[:300])
    return value


def _load(what: str, file: str, sha: str, where: str, loader):
    try:
        if sha256_file(file) != sha:
            raise ExecutionError(f"{where}: {file} changed since it was journaled (its SHA-256 differs)")
        return loader(file)
    except OSError as exc:
        raise ExecutionError(f"{where}: cannot read the run's {what} {file} ({exc.strerror})") from None
    except BilleError as exc:
        if isinstance(exc, ExecutionError):
            raise
        raise ExecutionError(f"{where}: {exc}") from None


def _check_order(kind: str, step: int, length: int, released: int, finished: int, where: str) -> None:
    """A ``released``, ``finished`` or ``fault`` line in its place: its step inside the plan,
    released and finished one after the other, finished only once released."""
    if not 1 <= step <= length:
        raise ExecutionError(f"{where}: step {step} is outside the plan (steps 1 to {length})")
    if kind == "released" and step != finished + 1:
        raise ExecutionError(f"{where}: step {step} released after step {finished} finished (expected step "
                             f"{finished + 1})")
    if kind == "fault" and step != finished + 1:
        raise ExecutionError(f"{where}: a fault of step {step} after step {finished} finished")
    if kind == "finished" and (step != finished + 1 or step > released):
        raise ExecutionError(f"{where}: step {step} finished, but " + (
            f"step {finished} was the last finished" if step != finished + 1 else "it was never released"))


def replay(path: str | Path, secret: bytes | None = None) -> Replayed:
    """Rebuild a run from its journal, checked line by line (see the module docstring); raises
    :class:`ExecutionError` naming the first line that an executor cannot have written."""
    secret = fleet_secret() if secret is None else secret
    events = read_events(path, secret)
    head = events[0]
    at = lambda e: f"{path}:{e['_line']}"  # noqa: E731
    _check_head(head, at(head))
    instance = _load("instance", head["instance"], head["instance_sha256"], at(head), load_instance)
    schedule = _load("schedule", head["schedule"], head["schedule_sha256"], at(head), load_schedule)
    try:
        plan = bind(instance, schedule)
    except BilleError as exc:
        raise ExecutionError(f"{at(head)}: {exc}") from None
    if head["steps"] != plan.shape[1] or len(head["robots"]) != plan.shape[0]:
        raise ExecutionError(f"{at(head)}: the run has {head['steps']} steps and {len(head['robots'])} robots, "
                             f"its schedule {plan.shape[1]} and {plan.shape[0]}")
    released = finished = 0
    done = False
    for event in events[1:]:
        kind, where = event["event"], at(event)
        if done:
            raise ExecutionError(f"{where}: '{kind}' after 'done' (nothing follows the end of a run)")
        length = plan.shape[1]
        if kind == "resume":
            if (event.get("finished"), event.get("released")) != (finished, released):
                raise ExecutionError(f"{where}: 'resume' says finished {event.get('finished')!r}, released "
                                     f"{event.get('released')!r}; the lines before say {finished} and {released}")
            continue
        step = _step(event, where)
        if kind == "replan":
            if step != finished:
                raise ExecutionError(f"{where}: 'replan' after step {step}, but step {finished} is the last finished")
            tail = _load("re-planned schedule", str(event.get("schedule")), event.get("schedule_sha256"), where,
                         load_schedule)
            try:
                plan = np.concatenate([plan[:, :step], bind(instance, tail)], axis=1)
            except BilleError as exc:
                raise ExecutionError(f"{where}: {exc}") from None
            continue
        if kind == "done":
            if step != length or finished != length:
                raise ExecutionError(f"{where}: 'done' at step {step}, but {finished} of the plan's {length} steps "
                                     "finished")
            done = True
            continue
        _check_order(kind, step, length, released, finished, where)
        if kind == "released":
            released = step
        elif kind == "finished":
            finished = step
    states = plan_states(instance, plan, f"{path}: the journaled plan")
    last = events[-1].get("signature", "") if secret is not None else ""
    return Replayed(head, instance, plan, states, released, finished, done, last)
