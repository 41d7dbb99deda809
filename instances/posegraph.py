"""The compiled pose graph: moveset x grid -> integer poses and numpy tables (docs/decisions.md).

Compiled once per (moveset, grid size, obstacles); the rules, the validator, the planners and the
encodings all read these tables, so motions are derived in exactly one place (``_world``).

Poses. ``biped``: ``pose = 4 * front_cell + heading`` (0 N, 1 E, 2 S, 3 W), back foot at
``front - heading``. ``point``: ``pose = cell``. A pose is *valid* when its feet are inside the
grid and not on obstacles (tiles change over time and are checked by the rules).

Tables (``P`` poses, ``A`` actions; -1 means none):

==============  ====================  ==========================================================
``feet``        ``int32[P, 2]``       front and back cell (point: the cell twice)
``succ``        ``int32[P, A]``       successor pose, -1 if a collision cell leaves the grid or
                                      hits an obstacle (rule 2 without a carried tile)
``coll``        ``int32[P, A, K]``    collision cells: feet before and after, swept, target
``carry``       ``int32[P, A, Kc]``   carried-tile cells (count only when carrying)
``carry_ok``    ``bool[P, A]``        every carried-tile cell inside the grid and free of obstacles
``need``        ``int32[P, A, 2]``    cells that must be tiles after the action (the new feet)
``target``      ``int32[P, A]``       pick/place target cell (-1 if outside the grid)
``kind``        ``int8[A]``           :class:`~.moveset.Kind` of each action
==============  ====================  ==========================================================
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .grid import HEADING_VECTORS, rotate
from .lru import LRU
from .moveset import Action, Moveset

Offset = tuple[int, int]


def _heading_index(dx: int, dy: int) -> int:
    return HEADING_VECTORS.index((dx, dy))


def _collision_offsets(action: Action, footprint: str) -> tuple[Offset, ...]:
    """The collision set of an action in the local frame, without carried-tile cells.

    Rotation and translation are injective, so distinct local offsets stay distinct cells: the
    set is deduplicated here once for every pose.
    """
    before = [(0, 0), (0, 1)] if footprint == "biped" else [(0, 0)]
    after = [action.front] + ([action.back] if action.back is not None else [])
    extra = list(action.swept) + ([action.target] if action.target is not None else [])
    return tuple(dict.fromkeys(before + after + extra))


@dataclass(frozen=True, eq=False)
class PoseGraph:
    """Compiled tables of one moveset on one grid (see the module docstring)."""

    moveset: Moveset
    width: int
    height: int
    obstacles: np.ndarray
    feet: np.ndarray
    valid: np.ndarray
    succ: np.ndarray
    coll: np.ndarray
    carry: np.ndarray
    carry_ok: np.ndarray
    need: np.ndarray
    target: np.ndarray
    kind: np.ndarray

    @property
    def footprint(self) -> str:
        return self.moveset.footprint

    @property
    def num_poses(self) -> int:
        return self.feet.shape[0]

    @property
    def num_actions(self) -> int:
        return self.succ.shape[1]

    @property
    def nbytes(self) -> int:
        return sum(getattr(self, f).nbytes for f in ("feet", "valid", "succ", "coll", "carry", "carry_ok", "need", "target"))

    # ---- poses <-> coordinates (edges only) ------------------------------------------------

    def pose_of(self, front: Offset, back: Offset | None = None) -> int:
        """Pose id of feet given as ``(x, y)`` pairs, or -1 if they form no valid pose."""
        fx, fy = front
        if not (0 <= fx < self.width and 0 <= fy < self.height):
            return -1
        cell = fy * self.width + fx
        if self.footprint == "point":
            pose = cell
        else:
            if back is None:
                return -1
            try:
                pose = 4 * cell + _heading_index(fx - back[0], fy - back[1])
            except ValueError:
                return -1
        return pose if self.valid[pose] else -1

    def feet_xy(self, pose: int) -> tuple[Offset, ...]:
        """Front (and back) foot of a pose as ``(x, y)`` pairs."""
        cells = self.feet[pose].tolist()
        cells = cells[:1] if self.footprint == "point" else cells
        return tuple((c % self.width, c // self.width) for c in cells)

    def heading(self, pose: int) -> int:
        return pose % 4 if self.footprint == "biped" else 0

    # ---- geometry of one motion, for messages and pictures ---------------------------------

    def world_cells(self, pose: int, action: int, *, carrying: bool = False) -> dict[str, list[Offset]]:
        """World coordinates (possibly outside the grid) of each part of a motion's collision set.

        Keys: ``collision`` (feet before and after, swept, target), ``carried`` (empty unless
        ``carrying``), ``swept``, ``target``.
        """
        act = self.moveset.actions[action]
        fx, fy = self.feet_xy(pose)[0]
        h = self.heading(pose)

        def place(offsets):
            return [tuple(int(v) for v in _world(o, fx, fy, h, self.footprint)) for o in offsets]

        return {
            "collision": place(_collision_offsets(act, self.footprint)),
            "carried": place(act.carried) if carrying else [],
            "swept": place(act.swept),
            "target": place([act.target]) if act.target is not None else [],
        }

    # ---- derived views for planners --------------------------------------------------------

    @cached_property
    def wait(self) -> int:
        return self.moveset.wait


def _world(offset: Offset, fx, fy, h, footprint: str):
    """Place a local offset in the world for front cell ``(fx, fy)`` and heading ``h``.

    The one place where motions are rotated and translated; ``fx``, ``fy``, ``h`` may be arrays.
    """
    dx, dy = offset
    if footprint == "biped":
        rx = np.array([rotate(dx, dy, k)[0] for k in range(4)])
        ry = np.array([rotate(dx, dy, k)[1] for k in range(4)])
        return fx + rx[h], fy + ry[h]
    return fx + dx, fy + dy


def compile_posegraph(moveset: Moveset, width: int, height: int, obstacles: np.ndarray) -> PoseGraph:
    """Compile ``moveset`` on a ``width x height`` grid with the given flat obstacle mask.

    Results are cached by moveset, size and obstacles.

    >>> import numpy as np
    >>> from bille.instances.moveset import load_moveset
    >>> g = compile_posegraph(load_moveset("S5"), 3, 1, np.zeros(3, bool))
    >>> p = g.pose_of((1, 0), (0, 0))            # heading E
    >>> g.feet_xy(g.succ[p, g.moveset.index["fwd"]])
    ((2, 0), (1, 0))
    """
    obstacles = np.asarray(obstacles, dtype=bool).reshape(-1)
    key = (moveset, width, height, obstacles.tobytes())
    return _CACHE.get(key, lambda: _compile(moveset, width, height, obstacles))


_CACHE: LRU[PoseGraph] = LRU(16)


def _compile(moveset: Moveset, width: int, height: int, obstacles: np.ndarray) -> PoseGraph:
    n = width * height
    fp = moveset.footprint
    headings = 4 if fp == "biped" else 1
    num_poses = n * headings
    pose = np.arange(num_poses, dtype=np.int64)
    cell, h = pose // headings, pose % headings
    fx, fy = cell % width, cell // width
    blocked_cells = np.append(obstacles, True)  # index -1 (outside) counts as blocked

    def to_cells(offset):
        x, y = _world(offset, fx, fy, h, fp)
        inside = (x >= 0) & (x < width) & (y >= 0) & (y < height)
        return np.where(inside, y * width + x, -1)

    def blocked(cells):
        return blocked_cells[cells]

    front = cell
    back = to_cells((0, 1)) if fp == "biped" else cell
    valid = ~blocked(front) & ~blocked(back)
    feet = np.stack([np.where(valid, front, -1), np.where(valid, back, -1)], axis=1).astype(np.int32)

    actions = moveset.actions
    num_actions = len(actions)
    coll_offsets = [_collision_offsets(a, fp) for a in actions]
    k_coll = max(len(o) for o in coll_offsets)
    k_carry = max([len(a.carried) for a in actions] + [1])

    succ = np.full((num_poses, num_actions), -1, dtype=np.int32)
    coll = np.full((num_poses, num_actions, k_coll), -1, dtype=np.int32)
    carry = np.full((num_poses, num_actions, k_carry), -1, dtype=np.int32)
    carry_ok = np.zeros((num_poses, num_actions), dtype=bool)
    need = np.full((num_poses, num_actions, 2), -1, dtype=np.int32)
    target = np.full((num_poses, num_actions), -1, dtype=np.int32)
    kind = np.array([a.kind for a in actions], dtype=np.int8)

    for a, act in enumerate(actions):
        ok = valid.copy()
        for k, off in enumerate(coll_offsets[a]):
            cells = to_cells(off)
            coll[:, a, k] = np.where(valid, cells, -1)
            ok &= ~blocked(cells)
        c_ok = valid.copy()
        for k, off in enumerate(act.carried):
            cells = to_cells(off)
            carry[:, a, k] = np.where(valid, cells, -1)
            c_ok &= ~blocked(cells)
        carry_ok[:, a] = c_ok
        new_front = to_cells(act.front)
        if fp == "biped":
            new_back = to_cells(act.back)
            turn = _heading_index(act.front[0] - act.back[0], act.front[1] - act.back[1])
            new_pose = 4 * new_front + (h + turn) % 4
        else:
            new_back, new_pose = new_front, new_front
        succ[:, a] = np.where(ok, new_pose, -1)
        need[:, a, 0] = np.where(ok, new_front, -1)
        need[:, a, 1] = np.where(ok, new_back, -1)
        if act.target is not None:
            target[:, a] = np.where(valid, to_cells(act.target), -1)

    tables = dict(feet=feet, valid=valid, succ=succ, coll=coll, carry=carry, carry_ok=carry_ok,
                  need=need, target=target, kind=kind, obstacles=obstacles.copy())
    for arr in tables.values():
        arr.flags.writeable = False
    return PoseGraph(moveset=moveset, width=width, height=height, **tables)
