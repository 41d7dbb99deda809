"""Writing instance files (docs/files.md, "Instance"): the canonical YAML text of an instance."""
from __future__ import annotations

import json
import re
from pathlib import Path
from typing import TYPE_CHECKING

import yaml

from .errors import InstanceError
from .files import write_atomic

if TYPE_CHECKING:
    from .grid import Grid
    from .instance import XY, Instance


def dump_instance(inst: Instance) -> str:
    """The canonical YAML text of an instance (``load(dump(x)) == x``)."""
    out = [f"name: {_scalar(inst.name)}", f"moveset: {_scalar(inst.moveset.ref or inst.moveset.name)}"]
    if inst.collisions != "bille":
        out.append(f"collisions: {inst.collisions}")
    out += _block("grid", inst.start)
    if inst.goal is not None:
        out += _block("goal", inst.goal)
    out.append("robots:" if inst.robots else "robots: []")
    for r in inst.robots:
        parts = [f"front: {_xy(r.front)}", f"back: {_xy(r.back)}"] if r.back is not None else [f"at: {_xy(r.front)}"]
        if r.carrying:
            parts.append("carrying: true")
        if r.moveset is not None:
            parts.append(f"moveset: {_scalar(r.moveset.ref or r.moveset.name)}")
        out.append("  - {" + ", ".join(parts) + "}")
    if inst.robot_goals is not None:
        out.append("robot_goals: [" + ", ".join("null" if g is None else _xy(g) for g in inst.robot_goals) + "]")
    if inst.tasks is not None:
        out.append("tasks:" if inst.tasks else "tasks: []")
        out += [f"  - {{pick: {_xy(t.pick)}, place: {_xy(t.place)}}}" for t in inst.tasks]
    if inst.meta is not None:
        text = yaml.safe_dump(inst.meta, sort_keys=False, default_flow_style=False, width=100).rstrip()
        out.append("meta: {}" if not inst.meta else "meta:")
        if inst.meta:
            out += ["  " + line for line in text.splitlines()]
    return "\n".join(out) + "\n"


def save_instance(inst: Instance, path: str | Path) -> None:
    """Write an instance file atomically (a failed write leaves no partial file)."""
    write_atomic(path, dump_instance(inst), InstanceError)


def _block(key: str, grid: Grid) -> list[str]:
    return [f"{key}: |"] + ["  " + row for row in grid.rows]


def _xy(xy: XY) -> str:
    return f"[{xy[0]}, {xy[1]}]"


_PLAIN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-/]*$")


def _scalar(s: str) -> str:
    """A string as a YAML scalar: plain when that reads back as the same string, else quoted."""
    if _PLAIN.match(s) and yaml.safe_load(s) == s:
        return s
    return json.dumps(s)
