"""Schedules and the schedule file (docs/files.md, "Schedule").

A schedule is one list of action names per robot, all of one length; step ``t`` (1-based) is the
joint action made of every robot's ``t``-th action. Names are bound to action ids of each robot's
moveset by :func:`bind`, which is where a schedule is matched to its instance. Solvers work on ids:
a schedule they build from ids (:meth:`Schedule.from_ids`) is named once and keeps its ids, which
:func:`bind` hands back for the same movesets without reading the names again.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .instance import Instance
from .errors import ScheduleError
from .files import write_atomic
from .yamlsource import Source, expect_list, expect_mapping, load_yaml_file, load_yaml_text


@dataclass(frozen=True)
class Schedule:
    """Action names per robot (``actions[i][t]``); ``origin`` remembers the file it came from,
    ``ids`` the movesets and action ids it was built from (:meth:`from_ids`)."""

    actions: tuple[tuple[str, ...], ...]
    meta: dict[str, Any] | None = field(default=None, hash=False)
    origin: Source | None = field(default=None, compare=False, hash=False, repr=False)
    ids: tuple | None = field(default=None, compare=False, hash=False, repr=False)
    instance: dict[str, str] | None = field(default=None, compare=False, hash=False)  # :func:`identity`

    @property
    def num_robots(self) -> int:
        return len(self.actions)

    @property
    def length(self) -> int:
        return len(self.actions[0]) if self.actions else 0

    @classmethod
    def from_ids(cls, instance: Instance, ids, meta: dict | None = None) -> "Schedule":
        """Build a schedule from an ``int[m, L]`` matrix of action ids (the inverse of :func:`bind`).
        With no robots the schedule is empty (length 0), whatever the matrix's shape."""
        ids = np.asarray(ids, dtype=np.int64)
        if instance.num_robots == 0:
            return cls((), meta, instance=identity(instance))
        movesets = instance.movesets
        ids = ids.reshape(instance.num_robots, -1).copy()
        ids.flags.writeable = False
        names = tuple(tuple(ms.actions[a].name for a in row) for ms, row in zip(movesets, ids.tolist()))
        return cls(names, meta, None, (movesets, ids), identity(instance))


def identity(instance: Instance) -> dict[str, str]:
    """What a schedule records of the instance it was made for: its name and the SHA-256 of its
    canonical text (:func:`~.writing.dump_instance`) without the name and the metadata: the same
    for the same problem whatever its file's name, comments, layout or notes. Computed once per
    instance."""
    found = _IDENTITIES.get(id(instance))
    if found is None or found[0] is not instance:
        import dataclasses
        import hashlib

        from .writing import dump_instance

        problem = dataclasses.replace(instance, name="instance", meta=None)
        digest = hashlib.sha256(dump_instance(problem).encode()).hexdigest()
        if len(_IDENTITIES) > 256:
            _IDENTITIES.clear()
        found = _IDENTITIES[id(instance)] = (instance, {"name": instance.name, "sha256": digest})
    return dict(found[1])


_IDENTITIES: dict[int, tuple[Instance, dict[str, str]]] = {}


def written_for(instance: Instance, schedule: Schedule) -> str | None:
    """Why ``schedule`` may not be meant for ``instance``: it names another instance (by content;
    a renamed copy of the same instance is the same). None when it names this one or none."""
    named = schedule.instance
    if not named or named.get("sha256") == identity(instance)["sha256"]:
        return None
    where = schedule.origin.name if schedule.origin is not None and schedule.origin.name else "the schedule"
    if named.get("name") == instance.name:
        return f"{where} was written for another version of '{instance.name}' (its content differs)"
    return f"{where} was written for '{named.get('name')}', not '{instance.name}'"


def bind(instance: Instance, schedule: Schedule) -> np.ndarray:
    """Action ids ``int64[m, L]`` of a schedule for an instance.

    Raises :class:`ScheduleError` (naming the file and line when known) if the robot count differs
    or an action is not in the robot's moveset.
    """
    if schedule.ids is not None and _same(schedule.ids[0], instance.movesets):
        return schedule.ids[1].copy()  # built from these ids for these movesets: no names to read
    src = schedule.origin or Source(None, ScheduleError)
    if schedule.num_robots != instance.num_robots:
        raise src.fail(("robots",), f"{schedule.num_robots} robots, but instance '{instance.name}' "
                                    f"has {instance.num_robots}")
    ids = np.zeros((schedule.num_robots, schedule.length), dtype=np.int64)
    for i, (ms, row) in enumerate(zip(instance.movesets, schedule.actions)):
        index = ms.index
        try:
            ids[i] = [index[a] for a in row]
        except KeyError:
            t = next(t for t, a in enumerate(row) if a not in index)
            raise src.fail(("robots", i, t), f"unknown action {row[t]!r} for robot {i}'s moveset "
                                             f"{ms.name} (expected one of: {', '.join(ms.names)})") from None
    return ids


def _same(movesets: tuple, others: tuple) -> bool:
    return len(movesets) == len(others) and all(a is b for a, b in zip(movesets, others))


def load_schedule(path: str | Path) -> Schedule:
    """Read a schedule file; raises :class:`ScheduleError` naming file, line and field."""
    data, src = load_yaml_file(path, ScheduleError)
    return parse_schedule(data, src)


def schedule_from_text(text: str, name: str | None = None) -> Schedule:
    data, src = load_yaml_text(text, name, ScheduleError)
    return parse_schedule(data, src)


def parse_schedule(data, src: Source) -> Schedule:
    top = expect_mapping(data, src, (), required=("robots",), optional=("instance", "meta"))
    named = None
    if "instance" in top:
        named = expect_mapping(top["instance"], src, ("instance",), required=("name", "sha256"))
        for key in ("name", "sha256"):
            if not isinstance(named[key], str) or not named[key]:
                raise src.fail(("instance", key), f"expected the instance's {key} as text, got {named[key]!r}")
        if not all(c in "0123456789abcdef" for c in named["sha256"]):
            raise src.fail(("instance", "sha256"), f"expected hexadecimal digits, got {named['sha256'][:80]!r}")
        named = {"name": named["name"], "sha256": named["sha256"]}
    robots = expect_list(top["robots"], src, ("robots",), "a list with one list of actions per robot")
    rows = []
    for i, row in enumerate(robots):
        row = expect_list(row, src, ("robots", i), "a list of action names")
        for t, a in enumerate(row):
            if not isinstance(a, str) or not a:
                shown = "nothing" if a is None else repr(a)
                raise src.fail(("robots", i, t), f"expected an action name, got {shown}")
        if rows and len(row) != len(rows[0]):
            raise src.fail(("robots", i), f"{len(row)} actions, expected {len(rows[0])} like robots[0] "
                                          "(every robot has one action per step)")
        rows.append(tuple(row))
    meta = top.get("meta")
    if meta is not None and not isinstance(meta, dict):
        raise src.fail(("meta",), "expected a mapping")
    return Schedule(tuple(rows), meta, src, instance=named)


def dump_schedule(schedule: Schedule) -> str:
    """The canonical YAML text of a schedule (one flow list per robot), with the instance it was
    made for where known."""
    out = []
    if schedule.instance:
        out.append(f"instance: {{name: {_flow(schedule.instance['name'])}, sha256: {schedule.instance['sha256']}}}")
    out.append("robots:" if schedule.actions else "robots: []")
    out += ["  - [" + ", ".join(row) + "]" for row in schedule.actions]
    if schedule.meta is not None:
        text = yaml.safe_dump(schedule.meta, sort_keys=False, default_flow_style=False, width=100).rstrip()
        out += ["meta:"] + ["  " + line for line in text.splitlines()] if schedule.meta else ["meta: {}"]
    return "\n".join(out) + "\n"


def _flow(text: str) -> str:
    """``text`` as a YAML flow scalar (quoted where it must be)."""
    return yaml.safe_dump([text], default_flow_style=True, width=10_000).strip()[1:-1]


def save_schedule(schedule: Schedule, path: str | Path) -> None:
    """Write a schedule file atomically."""
    write_atomic(path, dump_schedule(schedule), ScheduleError)
