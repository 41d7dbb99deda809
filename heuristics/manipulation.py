"""Manipulation, step 4 of the reconfiguration loop: which picks and places happen now.

A robot facing its leg's cell picks or places when the rules allow it and the structure stays
connected *and the rest of the sequence stays executable in order* from the tiles it leaves;
robots are considered in the order of the priority queue ``Q``.
"""
from __future__ import annotations

import numpy as np

from bille.instances.moveset import Kind

from .legs import Leg
from .sequence import Job, apply_move


class Manipulation:
    """The loop's pick and place gating (a part of :class:`.reconfigure.Loop`)."""

    def _cells_now(self, j: int) -> frozenset:
        """Robot ``j``'s feet and the tile it carries: cells every action of it touches."""
        return self.walk(j).cells(self.state.poses[j], self.world.graphs[j].wait)

    def _occupied_cells(self, but: int | None = None) -> set[int]:
        """Cells every action of the robots (except ``but``) touches this step."""
        out: set[int] = set()
        for j in range(len(self.legs)):
            if j != but:
                out |= self._cells_now(j)
        return out

    def _pending_ops(self) -> list[tuple[tuple, Kind, int, object]]:
        """Every pick and place still to do, in the order the sequence runs them: a relay's drop
        and pick-up first (the tile is borrowed), then by job, pick before place."""
        ops = []
        for i, legs in enumerate(self.legs):
            for leg in legs:
                if leg.relay:
                    key = (-2 if leg.kind == Kind.PLACE else -1, leg.job)
                else:
                    key = (leg.job, 0 if leg.kind == Kind.PICK else 1)
                ops.append((key, leg.kind, leg.cell, (i, leg)))
        for k in range(self.next_job, len(self.jobs)):
            job = self.jobs[k]
            if job.pick is not None:
                ops.append(((k, 0), Kind.PICK, job.pick, None))
            ops.append(((k, 1), Kind.PLACE, job.place, None))
        ops.sort(key=lambda o: o[0])
        return ops

    def _executable(self, tiles: np.ndarray, ops) -> bool:
        """Whether ``ops`` run in order from ``tiles``, each keeping the structure connected and,
        when the sequence allows it, with a pose facing its cell that stands on the tiles of that
        moment (an early pick must not take away the tile a later place needs to stand on)."""
        w, h = self.instance.width, self.instance.height
        tiles = tiles.copy()
        for _, kind, cell, _ in ops:
            if self._stands and not self._can_face(tiles, cell):
                return False
            if apply_move(tiles, kind == Kind.PICK, cell, w, h) is not None:
                return False
        return True

    def _can_face(self, tiles: np.ndarray, cell: int) -> bool:
        """Whether some robot could stand on ``tiles`` facing ``cell`` to pick or place there."""
        return any(bool(tiles[feet].all(axis=1).any()) for feet in self._facing_feet.get(cell, ()))

    def ready(self) -> set[int]:
        """Robots whose next pick or place could happen now as far as the tiles go: the cell
        holds a tile (pick) or not (place), and the structure and the rest of the sequence stay
        valid after it. Cached per tiles and legs."""
        key = (self.state.tiles.tobytes(), tuple(map(tuple, self.legs)), self.next_job)
        if self._ready_key != key:
            ops = self._pending_ops()
            out = set()
            for i, legs in enumerate(self.legs):
                rest = [op for op in ops if op[3] != (i, legs[0])] if legs else []
                if legs and self._allowed(self.state.tiles, legs[0], rest) is not None:
                    out.add(i)
            self._ready_key, self._ready = key, out
        return self._ready

    def _allowed(self, tiles: np.ndarray, leg: Leg, rest) -> np.ndarray | None:
        """The tiles after ``leg`` if it may happen on ``tiles`` with ``rest`` still to run."""
        trial = tiles.copy()
        if apply_move(trial, leg.kind == Kind.PICK, leg.cell, self.instance.width, self.instance.height):
            return None
        return trial if self._executable(trial, rest) else None

    def manipulations(self) -> tuple[dict[int, int], dict[int, frozenset]]:
        """The picks and places that happen this step, ``{robot: action}``, and the *intents*:
        ``{robot: cells}`` of robots that face their leg's cell and would manipulate now but for
        another robot on the cells (module docstring)."""
        tiles = self.state.tiles.copy()
        ops = self._pending_ops()
        taken: set[int] = set()
        out: dict[int, int] = {}
        intents: dict[int, frozenset] = {}
        for i in self.Q:
            if not self.legs[i]:
                continue
            leg, pose = self.legs[i][0], self.state.poses[i]
            walk = self.walk(i)
            action = walk.manipulation(pose, leg.cell, leg.kind)
            if action is None or self.state.carrying[i] != (leg.kind == Kind.PLACE):
                continue
            cells = walk.cells(pose, action)
            if not cells.isdisjoint(taken):
                continue
            rest = [op for op in ops if op[3] != (i, leg)]
            trial = self._allowed(tiles, leg, rest)
            if trial is None:
                self.stats["deferred_manipulations"] += 1
                continue
            if not cells.isdisjoint(self._occupied_cells(but=i)):
                intents[i] = cells
                continue
            tiles, ops = trial, rest
            out[i] = action
            taken |= cells
        return out, intents

    def drop(self) -> dict[int, int]:
        """A temporary placement: a carrying robot that cannot get on (no joint plan brings it to
        its place) puts its tile down where it stands, on a free cell that no pending job uses,
        if the structure and the rest of the sequence stay valid; the rest of its job (pick the
        tile up again, place it) becomes the next job to hand out. Returns ``{robot: place
        action}`` for this step, or nothing. At most ``len(jobs)`` drops per run."""
        if self.stats["drops"] >= self.max_drops:
            return {}
        tiles, pending, k = self.state.tiles, self._pending_cells(), self.next_job
        for i in reversed(self.Q):
            legs = self.legs[i]
            if not (self.state.carrying[i] and len(legs) == 1 and legs[0].kind == Kind.PLACE):
                continue
            walk, pose = self.walk(i), self.state.poses[i]
            busy = self._occupied_cells(but=i)
            for c in walk.graph.target[pose].tolist():
                action = walk.manipulation(pose, c, Kind.PLACE) if c >= 0 else None
                if action is None or tiles[c] or c in pending or not walk.cells(pose, action).isdisjoint(busy):
                    continue
                # the rest of the job runs next: after the jobs handed out, before those waiting
                ops = [op for op in self._pending_ops() if op[3] != (i, legs[0])]
                ops = sorted(ops + [((k - 0.5, 0), Kind.PICK, c, None), ((k - 0.5, 1), Kind.PLACE, legs[0].cell, None)],
                             key=lambda op: op[0])
                drop = Leg(Kind.PLACE, c, legs[0].job)
                if self._allowed(tiles, drop, ops) is not None:
                    self.jobs = self.jobs[:k] + [Job(c, legs[0].cell)] + self.jobs[k:]
                    self.legs[i] = [drop]
                    self.stats["drops"] += 1
                    self._ready_key = None
                    return {i: action}
        return {}
