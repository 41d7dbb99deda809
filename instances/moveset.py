"""Movesets as data (docs/rules.md, "Motions"; paper, Fig. Neighbors: S5 and S7).

A moveset is a footprint (``biped``: Bill-E's two feet; ``point``: one cell, the paper's
complexity model) and a list of actions written in the robot's local frame. For ``biped`` the
local frame has the front foot at ``(0, 0)``, heading N, the back foot at ``(0, 1)``; an action
gives the new front and back feet, the extra cells its swinging foot sweeps, the cells a carried
tile passes over, and a ``pick`` or ``place`` target. For ``point`` the robot is at ``(0, 0)``
and an action gives its new cell ``at`` (no rotation: a point has no heading).

``S5``, ``S7`` and ``point`` ship as YAML files next to this module; an instance may name one of
them or give a path to its own file.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from enum import IntEnum
from functools import cached_property
from importlib import resources
from pathlib import Path

from .errors import MovesetError
from .yamlsource import (
    Source,
    expect_list,
    expect_mapping,
    expect_str,
    expect_xy,
    load_yaml_file,
    load_yaml_text,
)

BUILTIN = ("S5", "S7", "point")
FOOTPRINTS = ("biped", "point")
_NAME = re.compile(r"^[a-z][a-z0-9-]*$")

Offset = tuple[int, int]


class Kind(IntEnum):
    """What an action does, for the metrics: waits, motions (tiles traveled), picks, places."""

    WAIT = 0
    MOTION = 1
    PICK = 2
    PLACE = 3


@dataclass(frozen=True)
class Action:
    """One motion of a moveset, in the local frame.

    ``front``/``back`` are the new feet (``point``: ``front`` is the new cell, ``back`` is None);
    ``swept`` the extra cells swept; ``carried`` the cells a carried tile occupies during the
    action (only when the robot carries one); ``pick``/``place`` the manipulation target.
    """

    name: str
    front: Offset
    back: Offset | None
    swept: tuple[Offset, ...] = ()
    carried: tuple[Offset, ...] = ()
    pick: Offset | None = None
    place: Offset | None = None

    @property
    def target(self) -> Offset | None:
        return self.pick if self.pick is not None else self.place

    @property
    def kind(self) -> Kind:
        if self.pick is not None:
            return Kind.PICK
        if self.place is not None:
            return Kind.PLACE
        stays = self.front == (0, 0) and self.back in (None, (0, 1))
        return Kind.WAIT if stays and not self.swept else Kind.MOTION


@dataclass(frozen=True)
class Moveset:
    """A footprint and its actions. ``ref`` is how an instance named it (a builtin or a path)."""

    name: str
    footprint: str
    actions: tuple[Action, ...]
    description: str = ""
    ref: str = field(default="", compare=False)

    @cached_property
    def index(self) -> dict[str, int]:
        """Action name -> action id (its position in the file)."""
        return {a.name: i for i, a in enumerate(self.actions)}

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.actions)

    @property
    def wait(self) -> int:
        return self.index["wait"]


def box_rule(front: Offset, back: Offset) -> tuple[Offset, ...]:
    """Carried-tile cells of a biped motion: the box spanning the tile's start cell ``(0, -1)``
    and its end cell (new front + new heading).

    >>> box_rule((1, 0), (0, 0))   # fwd-right
    ((0, -1), (1, -1), (2, -1), (0, 0), (1, 0), (2, 0))
    """
    end = (2 * front[0] - back[0], 2 * front[1] - back[1])
    xs = range(min(0, end[0]), max(0, end[0]) + 1)
    ys = range(min(-1, end[1]), max(-1, end[1]) + 1)
    return tuple((x, y) for y in ys for x in xs)


def load_moveset(ref: str, base_dir: str | Path | None = None) -> Moveset:
    """Load a moveset by builtin name (``S5``, ``S7``, ``point``) or by path.

    A relative path is taken relative to ``base_dir`` (the instance file's folder).

    >>> load_moveset("S5").names
    ('wait', 'fwd', 'back', 'fwd-right', 'fwd-left', 'pick', 'place')
    """
    if ref in BUILTIN:
        return _builtin(ref)
    path = Path(ref)
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    if not path.is_file():
        raise MovesetError(
            f"unknown moveset '{ref}' (expected {', '.join(BUILTIN)} or a path to a moveset YAML file)"
        )
    data, src = load_yaml_file(path, MovesetError)
    return parse_moveset(data, src, ref)


_CACHE: dict[str, Moveset] = {}


def _builtin(name: str) -> Moveset:
    if name not in _CACHE:
        text = resources.files(__package__).joinpath("movesets", f"{name}.yaml").read_text()
        data, src = load_yaml_text(text, f"<builtin moveset {name}>", MovesetError)
        _CACHE[name] = parse_moveset(data, src, name)
    return _CACHE[name]


def parse_moveset(data, src: Source, ref: str) -> Moveset:
    """Check and build a moveset from parsed YAML data."""
    top = expect_mapping(data, src, (), required=("name", "footprint", "actions"), optional=("description",))
    name = expect_str(top["name"], src, ("name",))
    footprint = expect_str(top["footprint"], src, ("footprint",))
    if footprint not in FOOTPRINTS:
        raise src.fail(("footprint",), f"unknown footprint '{footprint}' (expected biped or point)")
    description = top.get("description", "")
    if not isinstance(description, str):
        raise src.fail(("description",), "expected a string")
    raw = top["actions"]
    if not isinstance(raw, dict) or not raw:
        raise src.fail(("actions",), "expected a non-empty mapping from action name to motion")
    actions = tuple(_parse_action(key, value, footprint, src) for key, value in raw.items())
    if "wait" not in {a.name for a in actions}:
        raise src.fail(("actions",), "a moveset needs an action named 'wait'")
    wait = next(a for a in actions if a.name == "wait")
    if wait.kind != Kind.WAIT:
        raise src.fail(("actions", "wait"), "'wait' must leave the robot where it is")
    return Moveset(name, footprint, actions, description.strip(), ref)


def _parse_action(key, value, footprint: str, src: Source) -> Action:
    path = ("actions", key)
    if not isinstance(key, str) or not _NAME.match(key):
        raise src.fail(path, "action names are lower-case words joined by '-'")
    if footprint == "biped":
        fields = expect_mapping(value, src, path, required=("front", "back"), optional=("swept", "carried", "pick", "place"))
        front = expect_xy(fields["front"], src, path + ("front",))
        back = expect_xy(fields["back"], src, path + ("back",))
        if abs(front[0] - back[0]) + abs(front[1] - back[1]) != 1:
            raise src.fail(path, f"feet {list(front)} and {list(back)} are not 4-adjacent")
    else:
        fields = expect_mapping(value, src, path, required=("at",), optional=("swept", "carried", "pick", "place"))
        front, back = expect_xy(fields["at"], src, path + ("at",)), None

    def cells(name: str) -> tuple[Offset, ...]:
        items = expect_list(fields.get(name, []), src, path + (name,), "a list of [x, y] pairs")
        return tuple(expect_xy(v, src, path + (name, i)) for i, v in enumerate(items))

    pick = expect_xy(fields["pick"], src, path + ("pick",)) if "pick" in fields else None
    place = expect_xy(fields["place"], src, path + ("place",)) if "place" in fields else None
    if pick is not None and place is not None:
        raise src.fail(path, "an action picks or places, not both")
    if (pick or place) and (front != (0, 0) or back not in (None, (0, 1))):
        raise src.fail(path, "pick and place actions must leave the robot where it is")
    if "carried" in fields:
        carried = cells("carried")
    elif footprint == "biped" and pick is None and place is None:
        carried = box_rule(front, back)
    else:
        carried = ()
    return Action(key, front, back, cells("swept"), carried, pick, place)
