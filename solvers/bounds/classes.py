"""Classes of schedules, and lower bounds that hold within each (certificates per class).

A lower bound for *every* schedule (:mod:`.static`) is the only one that makes a certified gap.
Within a class of schedules much more can be proved: on the load-transfer maps, the schedules that
never set a tile down in the gap between the platforms need several steps more than the best
unconditional bound shows. A user comparing planners that build no such scaffold wants that
number, named for what it is: "makespan 59; >= 39 for every schedule; >= 45 for schedules without
scaffold, which this one is".

A class is defined by the tiles' configurations over time, so whether a schedule belongs to it is
read from the schedule (:func:`classes_of`), never assumed. Writing ``S`` and ``G`` for the cells
with a tile at the start and in the goal:

``no-scaffold``
    No tile is ever on a cell outside ``S | G``: nothing is set down, even for a while, where
    neither the start nor the goal has a tile.
``keep-structure``
    The cells where the start and the goal agree never change: picks and places only where they
    differ (the exact methods' ``keep_structure`` restriction). A subclass of ``no-scaffold``.
``single-carry``
    Besides, every cell where they differ changes once: each tile is carried once, straight from
    its start cell to its goal cell (the exact methods' ``single_carry`` restriction).

**The bound of a class** (:func:`class_bounds`) is the static bound of :mod:`.static` computed on
the class's *ground* (:class:`.ground.Ground`). In a schedule of ``no-scaffold``, every tile at
every step is on a cell of ``A = S | G``; a robot's feet stand on tiles (rule 4), so every pose it
takes has both feet in ``A``, and a pick or a place targets a cell that holds a tile just before
or just after, also in ``A``. Besides, some cells of ``A`` are *pinned* (:func:`pinned`): take
``N`` tiles in all (on the grid and carried at the start; picks and places only move them) and
``m`` robots. A robot picks at ``c`` only from a tile there (rule 1) and no robot places at ``c``
in that step (a place needs it empty before), so after the step ``c`` is empty, at least ``N - m``
tiles lie on the grid (a robot holds one at most), all in ``A - {c}``, and they are 4-connected
(rule 5): all in one component of ``A - {c}``. So where every component of ``A - {c}`` has fewer
than ``N - m`` cells, no schedule of the class ever picks at ``c``; if ``c`` holds a tile at the
start, it holds one for ever, and no place targets it either. In ``keep-structure``, besides, a pick or place changes
its cell, so it targets a cell where ``S`` and ``G`` differ; in ``single-carry``, a pick empties
a cell for good and a place fills one for good, so picks target cells of ``S - G`` and places
cells of ``G - S``. The bounds module's proofs hold for every schedule whose poses and events lie
on the ground given, so its parts on these grounds are lower bounds for the class, and its proofs
of infeasibility prove the class empty. Checked against a brute-force search restricted to each
class on tiny instances (tests/test_classes.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable

import numpy as np

from bille.instances import Instance
from bille.instances.run import Budget

from .static import lower_bound
from .ground import Ground


@dataclass(frozen=True)
class ScheduleClass:
    """One class: its key (``no-scaffold``), its name in a sentence ("schedules without
    scaffold"), its rule in words, its ground on an instance, its test on the tiles'
    configurations of a schedule (start first), and the class it is part of (whose bounds hold
    for it too)."""

    key: str
    name: str
    rule: str
    ground: Callable[[Instance], Ground]
    contains: Callable[[Instance, list[np.ndarray]], bool]
    within: str | None = None


def pinned(instance: Instance, cells: np.ndarray) -> np.ndarray:
    """Mask of the cells ``c`` of ``cells`` such that every 4-connected component of ``cells``
    without ``c`` is smaller than ``N - m`` (``N`` tiles in all, ``m`` robots): where every tile
    stays on ``cells``, no tile is ever picked at ``c`` (module docstring)."""
    from bille.instances.grid import articulation_points, components

    w, h = instance.width, instance.height
    least = int(instance.start.tiles.sum()) + int(sum(instance.start_state.carrying)) - instance.num_robots
    out = np.zeros_like(cells)
    if int(cells.sum()) - 1 < least:  # too few cells left whatever the cell taken out
        out[:] = cells
        return out
    for c in np.flatnonzero(articulation_points(cells, w, h)):
        rest = cells.copy()
        rest[c] = False
        labels, _ = components(rest, w, h)
        out[c] = np.bincount(labels)[1:].max(initial=0) < least
    return out


def _no_scaffold_ground(instance: Instance) -> Ground:
    both = instance.start.tiles | instance.goal_tiles
    fixed = pinned(instance, both)
    return Ground(feet=both, picks=both & ~fixed, places=both & ~(fixed & instance.start.tiles))


def _no_scaffold(instance: Instance, tiles: list[np.ndarray]) -> bool:
    both = instance.start.tiles | instance.goal_tiles
    return all(not (t & ~both).any() for t in tiles)


def _keep_ground(instance: Instance) -> Ground:
    start, goal = instance.start.tiles, instance.goal_tiles
    differ = start ^ goal
    return Ground(feet=start | goal, picks=differ, places=differ)


def _keeps(instance: Instance, tiles: list[np.ndarray]) -> bool:
    start, goal = instance.start.tiles, instance.goal_tiles
    same = start == goal
    return all(np.array_equal(t[same], start[same]) for t in tiles)


def _single_ground(instance: Instance) -> Ground:
    start, goal = instance.start.tiles, instance.goal_tiles
    return Ground(feet=start | goal, picks=start & ~goal, places=goal & ~start)


def _single(instance: Instance, tiles: list[np.ndarray]) -> bool:
    if not _keeps(instance, tiles):
        return False
    changes = sum((a != b).astype(int) for a, b in zip(tiles, tiles[1:])) if len(tiles) > 1 else 0
    return bool(np.all(np.asarray(changes) <= 1))


CLASSES: tuple[ScheduleClass, ...] = (
    ScheduleClass("no-scaffold", "schedules without scaffold",
                  "no tile is ever set down where neither the start nor the goal has one",
                  _no_scaffold_ground, _no_scaffold),
    ScheduleClass("keep-structure", "schedules that keep the structure",
                  "picks and places only where the start and the goal differ",
                  _keep_ground, _keeps, within="no-scaffold"),
    ScheduleClass("single-carry", "single-carry schedules",
                  "every tile carried once, straight from its start cell to its goal cell",
                  _single_ground, _single, within="keep-structure"),
)
BY_KEY = {c.key: c for c in CLASSES}  # a class comes after the class it is part of
# the exact methods' restrictions (their proofs hold within them) by the class they are
RESTRICTIONS = {"no_scaffold": "no-scaffold", "keep_structure": "keep-structure", "single_carry": "single-carry"}


@dataclass(frozen=True)
class ClassBound:
    """A lower bound on the makespan of the schedules of one class, or ``empty`` when the
    bounds module proves the class has none (its reasons in ``why``)."""

    key: str
    lower: int | None
    empty: bool = False
    why: tuple[str, ...] = ()

    def to_json(self) -> dict:
        return {"lower_bound": self.lower, "empty": True, "why": list(self.why)} if self.empty else \
            {"lower_bound": self.lower}


def nested(bounds: dict[str, ClassBound]) -> dict[str, ClassBound]:
    """``bounds`` with each class's bound at least that of the class it is part of (a bound on
    a class holds for its part; a class with no schedule has no part with one)."""
    out = dict(bounds)
    for c in CLASSES:
        outer = out.get(c.within) if c.within else None
        if c.key not in out or outer is None or out[c.key].empty:
            continue
        if outer.empty:
            out[c.key] = ClassBound(c.key, None, empty=True, why=outer.why)
        elif outer.lower > out[c.key].lower:
            out[c.key] = ClassBound(c.key, outer.lower)
    return out


def applies(instance: Instance) -> bool:
    """Whether classes say anything: the instance moves tiles (on a fixed structure every
    schedule keeps it)."""
    return bool(instance.is_reconfiguration)


def class_bounds(instance: Instance, *, budget: Budget | None = None,
                 unconditional: int | None = None) -> dict[str, ClassBound]:
    """The bound of each class (module docstring), at least ``unconditional`` (a bound for every
    schedule holds for the schedules of a class too). Empty where :func:`applies` is false."""
    if not applies(instance):
        return {}
    out = {}
    for c in CLASSES:
        got = lower_bound(instance, budget=budget, ground=c.ground(instance))
        if got.impossible:
            out[c.key] = ClassBound(c.key, None, empty=True, why=tuple(got.impossible))
        else:
            out[c.key] = ClassBound(c.key, max(got.lower, unconditional or 0))
    return nested(out)


def tiles_over_time(instance: Instance, ids: np.ndarray) -> list[np.ndarray]:
    """The tiles after each step of a valid schedule (action ids ``[m, L]``), the start first."""
    from bille.instances.rules import State, run

    out = [instance.start.tiles]
    for state in run(instance.world, instance.start_state, ids):
        if not isinstance(state, State):
            raise ValueError(f"not a valid schedule: {state}")
        out.append(state.tiles)
    return out


def classes_of(instance: Instance, schedule) -> list[str]:
    """The keys of the classes a valid schedule belongs to (checked from its tiles over time)."""
    from bille.instances.schedule import bind

    if not applies(instance):
        return []
    tiles = tiles_over_time(instance, bind(instance, schedule))
    return [c.key for c in CLASSES if c.contains(instance, tiles)]


def report(makespan: int | None, lower: int | None, bounds: dict, classes: Iterable[str] | None) -> list[str]:
    """Lines for a user: the bound for every schedule (and the certified gap of ``makespan``),
    then each class's bound, its rule, and whether the schedule belongs to it (and its gap
    within the class). ``bounds``: ``stats["class_bounds"]`` of a result; ``classes``: its
    ``stats["classes"]`` (None without a schedule)."""
    def gap(base):
        return f"{100 * (makespan - base) / base:.1f} %" if base else "undefined (bound 0)"

    out = []
    if lower is not None:
        certified = f" (certified gap {gap(lower)})" if makespan is not None else ""
        out.append(f"makespan >= {lower} for every schedule{certified}")
    member = set(classes or ())
    for c in CLASSES:
        got = bounds.get(c.key)
        if got is None:
            continue
        value = "no schedule at all" if got.get("empty") else f"makespan >= {got['lower_bound']}"
        line = f"{value} for {c.name} ({c.rule})"
        if classes is not None:
            line += f"; this schedule is one, gap within the class {gap(got['lower_bound'])}" if c.key in member \
                else "; this schedule is not one"
        out.append(line)
    return out
