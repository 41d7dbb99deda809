"""The canonical rules of one time step (docs/rules.md, "One time step" and "Goal").

All robots act at once. Robot ``i``'s collision set ``C_i`` is its feet before and after, its
swept cells, its carried-tile cells (when it carries a tile) and a pick/place target. A joint
action on a state (tiles ``T``, poses, carrying flags) is valid iff

1. ``precondition``: ``pick`` needs no carried tile and a tile at the target; ``place`` needs a
   carried tile and an empty (non-tile, non-obstacle) target;
2. ``workspace``: every cell of every ``C_i`` is inside the grid and not an obstacle;
3. ``collision``: the ``C_i`` are pairwise disjoint;
4. ``support``: with ``T' = T - picked + placed``, every robot's new feet stand on tiles of ``T'``;
5. ``connectivity``: ``T'`` is non-empty and 4-connected.

The *first* violation is ordered by step, then by rule number, then by robot index (for
``collision``: the lexicographically smallest colliding pair ``(i, j)``, reported as robot ``i``).
After the last step the ``goal`` rule checks the tile set, that no robot carries a tile, and the
robots' goal cells, in that order.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator, Sequence

import numpy as np

from .grid import detached_cells, is_connected
from .moveset import Kind
from .posegraph import PoseGraph

RULES = ("precondition", "workspace", "collision", "support", "connectivity", "goal")
COLLISIONS = ("bille", "classic")  # rule 3, or docs/rules.md, "Classic collisions" (point robots)
PICK, PLACE = int(Kind.PICK), int(Kind.PLACE)


@dataclass(frozen=True, eq=False)
class State:
    """Tiles (flat bool mask, read-only), robot poses and carrying flags after some step."""

    tiles: np.ndarray
    poses: tuple[int, ...]
    carrying: tuple[bool, ...]

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, State)
            and self.poses == other.poses
            and self.carrying == other.carrying
            and np.array_equal(self.tiles, other.tiles)
        )

    def key(self) -> tuple:
        """A hashable key for searches over states."""
        return (self.tiles.tobytes(), self.poses, self.carrying)


@dataclass(frozen=True)
class Violation:
    """The first broken rule: 1-based ``step``, ``robot`` (or None), ``rule`` name, the
    offending ``cells`` as ``(x, y)`` and a sentence for people."""

    step: int
    robot: int | None
    rule: str
    cells: tuple[tuple[int, int], ...]
    message: str
    other: int | None = None  # the second robot of a collision

    def to_json(self) -> dict:
        return {"step": self.step, "robot": self.robot, "rule": self.rule, "cells": [list(c) for c in self.cells]}

    def __str__(self) -> str:
        return f"step {self.step}: {self.rule}: {self.message}"


@dataclass(frozen=True, eq=False)
class World:
    """The compiled, time-independent part of an instance: grid size, obstacles, and each
    robot's pose graph (robots with the same moveset share one)."""

    width: int
    height: int
    obstacles: np.ndarray
    graphs: tuple[PoseGraph, ...]
    classic: bool = False  # docs/rules.md, "Classic collisions" instead of rule 3 (point robots)
    groups: tuple[tuple[PoseGraph, np.ndarray], ...] = field(init=False)

    def __post_init__(self) -> None:
        by_graph: dict[int, list[int]] = {}
        for i, g in enumerate(self.graphs):
            by_graph.setdefault(id(g), []).append(i)
        groups = tuple((self.graphs[idx[0]], np.array(idx, dtype=np.int64)) for idx in by_graph.values())
        object.__setattr__(self, "groups", groups)

    @property
    def num_robots(self) -> int:
        return len(self.graphs)

    def xy(self, cell: int) -> tuple[int, int]:
        return int(cell % self.width), int(cell // self.width)

    def xys(self, cells) -> tuple[tuple[int, int], ...]:
        return tuple(self.xy(c) for c in sorted(set(int(c) for c in cells)))


@dataclass
class _Joint:
    """Per-robot table rows of one joint action, gathered once for all rule checks."""

    kind: np.ndarray  # (m,)
    succ: np.ndarray  # (m,)
    target: np.ndarray  # (m,)
    carry_ok: np.ndarray  # (m,)
    coll: np.ndarray  # (m, K) padded -1; includes carried cells of carrying robots
    need: np.ndarray  # (m, 2)


def _gather(world: World, state: State, actions: np.ndarray) -> _Joint:
    m = world.num_robots
    poses = np.asarray(state.poses, dtype=np.int64)
    carrying = np.asarray(state.carrying, dtype=bool)
    if len(world.groups) == 1:  # one moveset: every row at once (the same rows as below)
        g = world.groups[0][0]
        carried = np.where(carrying[:, None], g.carry[poses, actions], -1)
        return _Joint(kind=g.kind[actions].astype(np.int8), succ=g.succ[poses, actions].astype(np.int64),
                      target=g.target[poses, actions].astype(np.int64),
                      carry_ok=g.carry_ok[poses, actions].astype(bool),
                      coll=np.concatenate([g.coll[poses, actions], carried], axis=1).astype(np.int64),
                      need=g.need[poses, actions].astype(np.int64))
    k = max(g.coll.shape[2] + g.carry.shape[2] for g, _ in world.groups) if m else 1
    j = _Joint(
        kind=np.zeros(m, np.int8), succ=np.zeros(m, np.int64), target=np.zeros(m, np.int64),
        carry_ok=np.zeros(m, bool), coll=np.full((m, k), -1, np.int64), need=np.zeros((m, 2), np.int64),
    )
    for g, idx in world.groups:
        p, a = poses[idx], actions[idx]
        j.kind[idx] = g.kind[a]
        j.succ[idx] = g.succ[p, a]
        j.target[idx] = g.target[p, a]
        j.carry_ok[idx] = g.carry_ok[p, a]
        kc = g.coll.shape[2]
        j.coll[idx, :kc] = g.coll[p, a]
        carried = g.carry[p, a]
        j.coll[idx, kc : kc + carried.shape[1]] = np.where(carrying[idx, None], carried, -1)
        j.need[idx] = g.need[p, a]
    return j


def apply(world: World, state: State, actions: Sequence[int], step: int = 1) -> State | Violation:
    """Apply one joint action (one action id per robot) to ``state``.

    Returns the new :class:`State`, or the first :class:`Violation` (``step`` is used to label
    it). Never mutates ``state``.
    """
    actions = np.asarray(actions, dtype=np.int64)
    j = _gather(world, state, actions)
    carrying = np.asarray(state.carrying, dtype=bool)
    tiles = state.tiles
    free = ~(tiles | world.obstacles)

    # 1. precondition
    is_pick, is_place = j.kind == PICK, j.kind == PLACE
    has_target = j.target >= 0
    tgt = np.where(has_target, j.target, 0)
    bad = (is_pick & (carrying | ~has_target | ~tiles[tgt])) | (is_place & (~carrying | ~has_target | ~free[tgt]))
    if bad.any():
        return _precondition(world, state, actions, int(np.flatnonzero(bad)[0]), step)

    # 2. workspace: succ is -1 when a non-carried cell is outside or on an obstacle
    bad = (j.succ < 0) | (carrying & ~j.carry_ok)
    if bad.any():
        return _workspace(world, state, actions, int(np.flatnonzero(bad)[0]), step)

    # 3. collision: every cell in at most one collision set
    # (a robot's carried-tile cells may repeat its own feet: deduplicate per robot first)
    if world.classic:
        clash = _classic_collision(world, state, j, step)
        if clash is not None:
            return clash
    else:
        clash = _bille_collision(world, j, step)
        if clash is not None:
            return clash

    # 4. support
    new_tiles = tiles.copy()
    new_tiles[j.target[is_pick]] = False
    new_tiles[j.target[is_place]] = True
    on_tile = new_tiles[j.need]
    bad = ~on_tile.all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        off = j.need[i][~on_tile[i]]
        return Violation(step, i, "support", world.xys(off),
                         f"robot {i} would stand off the structure at {_fmt(world.xys(off))}")

    # 5. connectivity (only picks and places change the tiles)
    if (is_pick | is_place).any() and not is_connected(new_tiles, world.width, world.height):
        if not new_tiles.any():
            return Violation(step, None, "connectivity", (), "no tile would be left")
        lost = world.xys(detached_cells(new_tiles, world.width, world.height))
        return Violation(step, None, "connectivity", lost,
                         f"the structure would fall apart: {_fmt(lost)} cut off from the rest")

    new_tiles.flags.writeable = False
    new_carrying = (carrying & ~is_place) | is_pick
    return State(new_tiles, tuple(j.succ.tolist()), tuple(new_carrying.tolist()))


def run(world: World, state: State, actions: np.ndarray) -> Iterator[State | Violation]:
    """Apply the columns of an ``int[m, L]`` action matrix one step at a time.

    Yields the state after each step, or a violation and then stops.
    """
    for t in range(actions.shape[1] if actions.ndim == 2 else 0):
        nxt = apply(world, state, actions[:, t], step=t + 1)
        yield nxt
        if isinstance(nxt, Violation):
            return
        state = nxt


def goal_violation(world: World, state: State, goal_tiles: np.ndarray, robot_goals: Sequence[int],
                   step: int) -> Violation | None:
    """Check the goal after the last step (``robot_goals``: front-foot cell per robot, -1 = any)."""
    diff = np.flatnonzero(state.tiles != goal_tiles)
    if len(diff):
        cells = world.xys(diff)
        return Violation(step, None, "goal", cells, f"the tiles differ from the goal's at {_fmt(cells)}")
    for i, carrying in enumerate(state.carrying):
        if carrying:
            return Violation(step, i, "goal", (), f"robot {i} still carries a tile")
    for i, cell in enumerate(robot_goals):
        front = int(world.graphs[i].feet[state.poses[i], 0])
        if cell >= 0 and front != cell:
            return Violation(step, i, "goal", (world.xy(cell),),
                             f"robot {i} ends with its front at {world.xy(front)}, not at its goal {world.xy(cell)}")
    return None


def _bille_collision(world: World, j: _Joint, step: int) -> Violation | None:
    """Rule 3: the collision sets are pairwise disjoint."""
    seen: set = set()
    for row in j.coll.tolist():  # the common case, no clash, in plain sets (a few robots)
        cells = set(row)
        cells.discard(-1)
        if not seen.isdisjoint(cells):
            return _bille_clash(world, j, step)
        seen |= cells
    return None


def _bille_clash(world: World, j: _Joint, step: int) -> Violation | None:
    """The first clash of rule 3, described."""
    n = world.width * world.height
    owner = np.repeat(np.arange(world.num_robots), j.coll.shape[1])
    cells = j.coll.reshape(-1)
    used = cells >= 0
    pairs = np.unique(owner[used] * n + cells[used])
    cells, owner = pairs % n, pairs // n
    if len(np.unique(cells)) < len(cells):
        return _collision(world, cells, owner, step)
    return None


def _classic_collision(world: World, state: State, j: _Joint, step: int) -> Violation | None:
    """Classic collisions (point robots): no two robots end in one cell (vertex conflict) or
    exchange cells (swap conflict); a pick or place target is no other robot's cell before or
    after the step, nor another target."""
    before = np.asarray(state.poses, dtype=np.int64)  # point robots: pose = cell
    after, target = j.succ, j.target
    m = world.num_robots
    who = np.full(world.width * world.height, -1, dtype=np.int64)
    who[before] = np.arange(m)
    ahead = who[after]  # the robot standing now where each robot ends
    swap = (ahead >= 0) & (ahead != np.arange(m)) & (after[np.maximum(ahead, 0)] == before)
    manipulating = target >= 0
    if len(np.unique(after)) == m and not swap.any() and not manipulating.any():
        return None
    for i in range(m):  # a conflict may exist: find the first pair, to describe it
        for k in range(i + 1, m):
            why = None
            if after[i] == after[k]:
                why, cells = "end the step in the same cell", [after[i]]
            elif after[i] == before[k] and after[k] == before[i] and after[i] != before[i]:
                why, cells = "exchange cells", [before[i], before[k]]
            else:
                mine = {int(before[i]), int(after[i])}
                theirs = {int(before[k]), int(after[k])}
                hit = [t for t, other in ((target[i], theirs | {int(target[k])}), (target[k], mine | {int(target[i])}))
                       if t >= 0 and t in other]
                if hit:
                    why, cells = "need the same cell for a pick or place", hit[:1]
            if why is not None:
                xys = world.xys(cells)
                return Violation(step, i, "collision", xys, f"robots {i} and {k} {why} at {_fmt(xys)}", other=k)
    return None


# ---- slow paths: only run once a violation is known, to describe it ------------------------------


def _precondition(world, state, actions, i, step) -> Violation:
    g = world.graphs[i]
    p, a = state.poses[i], int(actions[i])
    act = g.moveset.actions[a]
    cells = tuple(g.world_cells(p, a)["target"])
    where = _fmt(cells)
    if act.kind == Kind.PICK:
        why = "it already carries a tile" if state.carrying[i] else f"there is no tile at {where}"
        return Violation(step, i, "precondition", cells, f"robot {i} cannot {act.name}: {why}")
    if not state.carrying[i]:
        why = "it carries no tile"
    elif g.target[p, a] < 0:
        why = f"{where} is outside the grid"
    elif world.obstacles[g.target[p, a]]:
        why = f"{where} is an obstacle"
    else:
        why = f"{where} already holds a tile"
    return Violation(step, i, "precondition", cells, f"robot {i} cannot {act.name}: {why}")


def _workspace(world, state, actions, i, step) -> Violation:
    g = world.graphs[i]
    parts = g.world_cells(state.poses[i], int(actions[i]), carrying=state.carrying[i])
    bad = []
    for x, y in parts["collision"] + parts["carried"]:
        if not (0 <= x < world.width and 0 <= y < world.height) or world.obstacles[y * world.width + x]:
            bad.append((x, y))
    bad = tuple(sorted(set(bad), key=lambda c: (c[1], c[0])))
    name = g.moveset.actions[int(actions[i])].name
    return Violation(step, i, "workspace", bad,
                     f"robot {i}'s {name} reaches {_fmt(bad)}, outside the grid or on an obstacle")


def _collision(world, cells, owner, step) -> Violation:
    sets = [set(cells[owner == i].tolist()) for i in range(world.num_robots)]
    for i in range(len(sets)):
        for k in range(i + 1, len(sets)):
            common = sets[i] & sets[k]
            if common:
                xys = world.xys(common)
                return Violation(step, i, "collision", xys,
                                 f"robots {i} and {k} both need {_fmt(xys)}", other=k)
    raise RuntimeError("unreachable: a repeated cell implies a colliding pair")


def _fmt(cells) -> str:
    return ", ".join(f"({x}, {y})" for x, y in cells) or "nothing"
