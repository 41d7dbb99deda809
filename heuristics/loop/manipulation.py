"""Manipulation, step 4 of the reconfiguration loop: which picks and places happen now.

A robot facing its leg's cell picks or places when the rules allow it and the structure stays
connected *and the rest of the sequence stays executable in order* from the tiles it leaves;
robots are considered in the order of the priority queue ``Q``. The same test decides which
robots are *ready* (their next pick or place could happen now as far as the tiles go, so the
goals of :mod:`.goals` send them there) and where a carrying robot may put its tile down for a
while (a temporary placement).
"""
from __future__ import annotations

from collections import Counter
from functools import cached_property

import numpy as np

from bille.instances import Instance
from bille.instances.moveset import Kind

from .legs import Leg, facing_feet
from .loopstate import LoopState, Op
from .sequence import apply_move


class Manipulation:
    """Gates the picks and places. ``stands``: whether the order of the sequence is also checked
    for a pose facing each cell on the tiles of that moment (derived sequences pass it at the
    start; a given task list may not, and is then checked for connectivity only)."""

    def __init__(self, instance: Instance, start: LoopState, stats: dict | None = None) -> None:
        self.width, self.height = instance.width, instance.height
        self.stats = Counter() if stats is None else stats
        self.world = instance.world
        self.stands = True
        self.stands = self.executable(start.state.tiles, start.pending_ops())
        self._ready_key, self._ready = None, set()

    def executable(self, tiles: np.ndarray, ops: list[Op]) -> bool:
        """Whether ``ops`` run in order from ``tiles``, each keeping the structure connected and,
        with :attr:`stands`, with a pose facing its cell that stands on the tiles of that moment
        (an early pick must not take away the tile a later place needs to stand on)."""
        tiles = tiles.copy()
        for _, kind, cell, _ in ops:
            if self.stands and not self._can_face(tiles, cell):
                return False
            if apply_move(tiles, kind == Kind.PICK, cell, self.width, self.height) is not None:
                return False
        return True

    def _can_face(self, tiles: np.ndarray, cell: int) -> bool:
        """Whether some robot could stand on ``tiles`` facing ``cell`` to pick or place there."""
        return any(bool(tiles[feet].all(axis=1).any()) for feet in self._facing_feet.get(cell, ()))

    @cached_property
    def _facing_feet(self) -> dict:
        """Per cell, the feet of the poses facing it (:func:`.legs.facing_feet`; made when first
        needed: path planning never needs it)."""
        return facing_feet(self.world)

    def allowed(self, tiles: np.ndarray, leg: Leg, rest: list[Op]) -> np.ndarray | None:
        """The tiles after ``leg`` if it may happen on ``tiles`` with ``rest`` still to run."""
        trial = tiles.copy()
        if apply_move(trial, leg.kind == Kind.PICK, leg.cell, self.width, self.height):
            return None
        return trial if self.executable(trial, rest) else None

    def ready(self, s: LoopState) -> set[int]:
        """Robots whose next pick or place could happen now as far as the tiles go: the cell
        holds a tile (pick) or not (place), and the structure and the rest of the sequence stay
        valid after it. Cached for the last tiles, legs and jobs asked about."""
        key = (s.state.tiles.tobytes(), tuple(map(tuple, s.legs)), tuple(s.jobs[s.next_job:]))
        if self._ready_key != key:
            ops = s.pending_ops()
            out = set()
            for i, legs in enumerate(s.legs):
                rest = [op for op in ops if op[3] != (i, legs[0])] if legs else []
                if legs and self.allowed(s.state.tiles, legs[0], rest) is not None:
                    out.add(i)
            self._ready_key, self._ready = key, out
        return self._ready

    def decide(self, s: LoopState) -> tuple[dict[int, int], dict[int, frozenset]]:
        """The picks and places that happen this step, ``{robot: action}``, and the *intents*:
        ``{robot: cells}`` of robots that face their leg's cell and would manipulate now but for
        another robot on the cells (module docstring). Counts the manipulations deferred
        (``deferred_manipulations``)."""
        tiles = s.state.tiles.copy()
        ops = s.pending_ops()
        taken: set[int] = set()
        out: dict[int, int] = {}
        intents: dict[int, frozenset] = {}
        for i in s.Q:
            if not s.legs[i]:
                continue
            leg, pose = s.legs[i][0], s.poses[i]
            walk = s.walk(i)
            action = walk.manipulation(pose, leg.cell, leg.kind)
            if action is None or s.state.carrying[i] != (leg.kind == Kind.PLACE):
                continue
            cells = walk.cells(pose, action)
            if not cells.isdisjoint(taken):
                continue
            rest = [op for op in ops if op[3] != (i, leg)]
            trial = self.allowed(tiles, leg, rest)
            if trial is None:
                self.stats["deferred_manipulations"] += 1
                continue
            if not cells.isdisjoint(s.occupied(but=i)):
                intents[i] = cells
                continue
            tiles, ops = trial, rest
            out[i] = action
            taken |= cells
        return out, intents

    def drop(self, s: LoopState) -> tuple[int, int, int] | None:
        """A temporary placement for a carrying robot that cannot get on: ``(robot, cell, place
        action)`` to put its tile down where it stands, on a free cell that no pending job uses,
        if the structure and the rest of the sequence stay valid with the rest of its job (pick
        the tile up again, place it) handed out next (:meth:`.LoopState.drop`); or None. Robots
        are tried from the end of ``Q``."""
        tiles, pending, k = s.state.tiles, s.pending_cells(), s.next_job
        for i in reversed(s.Q):
            legs = s.legs[i]
            if not (s.state.carrying[i] and len(legs) == 1 and legs[0].kind == Kind.PLACE):
                continue
            walk, pose = s.walk(i), s.poses[i]
            busy = s.occupied(but=i)
            for c in walk.graph.target[pose].tolist():
                action = walk.manipulation(pose, c, Kind.PLACE) if c >= 0 else None
                if action is None or tiles[c] or c in pending or not walk.cells(pose, action).isdisjoint(busy):
                    continue
                # the rest of the job runs next: after the jobs handed out, before those waiting
                ops = [op for op in s.pending_ops() if op[3] != (i, legs[0])]
                ops = sorted(ops + [((k - 0.5, 0), Kind.PICK, c, None), ((k - 0.5, 1), Kind.PLACE, legs[0].cell, None)],
                             key=lambda op: op[0])
                if self.allowed(tiles, Leg(Kind.PLACE, c, legs[0].job), ops) is not None:
                    return i, c, action
        return None
