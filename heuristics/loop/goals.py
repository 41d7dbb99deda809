"""Goals, step 3 of the reconfiguration loop (paper, Methods, "Temporal A*"): where each robot
is bound this step.

A robot with legs is bound for the poses facing its next leg's cell, if that pick or place
could happen now (:meth:`.Manipulation.ready`); otherwise it has no goal for now, so that it
gives way instead of holding a pose others need (a relay tile not dropped yet, a pick that must
wait for another job). An idle robot is bound for its goal cell if it has one; else, with
*parking* (the LaCAM* motion layer), for a pose out of the way of the work at hand; else, when
it stands on a tile that a pending job must pick, for any pose whose feet are off those tiles;
else, when the loop has *evicted* it (:meth:`Goals.evict`, its last resort before a deadlock),
for any pose whose feet are off the cells the busy robots' goal poses need; any other idle
robot is free (it only keeps out of the way).

A goal is a distance table over the robot's poses, named by what it means (the robot type, the
tiles, whether it carries, and the goal itself), so that a table and its plain-list copies for
the planners' inner loops are made once per meaning.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from bille.instances import Instance
from bille.instances.grid import articulation_points
from bille.instances.lru import LRU
from bille.instances.moveset import Kind
from bille.instances.walking import UNREACHABLE, Walk, walk_for

from .loopstate import LoopState
from .manipulation import Manipulation

PARKING = 5  # parking: an idle robot keeps its feet this far (Manhattan) from the work at hand


@dataclass(frozen=True, eq=False)
class Goal:
    """``dist[p]``: steps from pose ``p`` to the goal's poses (:data:`UNREACHABLE` where none);
    ``key`` names it: the robot type, the tiles, the carrying flag and the goal."""

    key: tuple
    dist: np.ndarray

    @cached_property
    def lists(self) -> tuple[list[int], list[bool]]:
        """``(dist, home)`` as plain lists (the inner loops of the planners read lists):
        ``home[p]`` whether pose ``p`` is one of the goal's poses."""
        return self.dist.tolist(), (self.dist == 0).tolist()


class Goals:
    """Each robot's goal (module docstring); ``parking`` for the LaCAM* motion layer."""

    def __init__(self, instance: Instance, manipulation: Manipulation, parking: bool = False,
                 size: int = 512) -> None:
        """``size``: goals kept (at least 512; one per robot at least, or the tables of robots
        bound for their goal cells would be made again every step)."""
        self.instance, self.manipulation, self.parking = instance, manipulation, parking
        self.cells = instance.goal_cells  # each robot's goal cell (-1: none)
        self._type = {int(i): k for k, (_, robots) in enumerate(instance.world.groups) for i in robots}
        self._goals: LRU[Goal] = LRU(max(512, size))
        self.evicted: dict[int, frozenset[int]] = {}  # idle robot -> cells it must leave

    def evict(self, s: LoopState) -> bool:
        """Bind every idle robot (no legs, no goal cell) that stands on a cell a busy robot needs
        (of its goal poses, or swept on one shortest walk to them) for a pose off those cells;
        whether one was. The loop's last resort when it goes round in circles: Temporal A*
        moves a blocked robot up, but a robot with no goal only waits, wherever it stands. With
        parking every idle robot has a goal already: none is evicted."""
        if self.parking:
            return False
        needed: set[int] = set()
        for j in range(s.num_robots):
            goal = self.of(s, j)
            if goal is not None and (s.legs[j] or self.cells[j] >= 0):
                walk = s.walk(j)
                feet = walk.graph.feet[np.flatnonzero(goal.dist == 0)]
                needed.update(int(c) for c in feet.ravel() if c >= 0)
                needed.update(_downhill(walk, goal, s.poses[j]))
        found = False
        for i in range(s.num_robots):
            if s.legs[i] or self.cells[i] >= 0 or i in self.evicted:
                continue
            if needed.intersection(s.cells_now(i)):
                self.evicted[i] = frozenset(needed)
                found = True
        return found

    def all(self, s: LoopState) -> list[Goal | None]:
        return [self.of(s, i) for i in range(s.num_robots)]

    def of(self, s: LoopState, i: int) -> Goal | None:
        """Robot ``i``'s goal now, or None (free)."""
        walk = s.walk(i)
        legs = s.legs[i]
        if legs:
            if i not in self.manipulation.ready(s):
                return None  # its pick or place cannot happen yet: give way meanwhile
            leg = legs[0]
            if leg.kind == Kind.PICK and len(legs) > 1 and legs[1].kind == Kind.PLACE:
                return self._pick_towards(s, i, walk, leg.cell, legs[1].cell)
            return self._goal(i, walk, ("facing", leg.cell), lambda: walk.facing_distances(leg.cell))
        cell = self.cells[i]
        if cell >= 0:
            return self._goal(i, walk, ("front", cell), lambda: walk.distances(cell))
        if self.parking:
            return self._parking(s, i, walk)
        if i in self.evicted:
            return self._off(i, walk, self.evicted[i], s.poses[i])
        needed = s.pending_picks()
        feet = walk.graph.feet
        if needed.intersection(feet[s.poses[i]].tolist()):  # off the tiles still to be picked
            def clear():
                return np.flatnonzero(walk.standing & ~np.isin(feet, list(needed)).any(axis=1))

            key = ("clear", frozenset(needed))
            return self._goal(i, walk, key, lambda: walk.distances_to(key, clear))
        return None

    def _off(self, i: int, walk: Walk, cells: frozenset[int], pose: int) -> Goal | None:
        """The poses whose feet are off ``cells``; None (free) if the robot can reach none."""
        feet = walk.graph.feet
        key = ("off", cells)
        goal = self._goal(i, walk, key, lambda: walk.distances_to(
            key, lambda: np.flatnonzero(walk.standing & ~np.isin(feet, list(cells)).any(axis=1))))
        return None if goal.dist[pose] >= UNREACHABLE else goal

    def _goal(self, i: int, walk: Walk, name: tuple, make) -> Goal:
        key = (self._type[i], walk.tiles.tobytes(), walk.carrying, name)
        return self._goals.get(key, lambda: Goal(key, make()))

    def _parking(self, s: LoopState, i: int, walk: Walk) -> Goal | None:
        """The nearest pose whose feet keep at least :data:`PARKING` cells (Manhattan) from the
        work at hand (the cells of the robots' legs and of the next jobs to hand out) and off the
        structure's articulation points (a narrow passage), so that an idle robot does not stand
        where a pick, a place or the way to one needs it; None (free) if there is no such pose.
        The poses depend on the work, not on the robots' walks, so they stay put while the robots
        go about it."""
        w = self.instance.width
        soon = s.jobs[s.next_job:s.next_job + s.num_robots]
        work = {leg.cell for legs in s.legs for leg in legs} | {c for j in soon for c in (j.pick, j.place)
                                                                 if c is not None}
        if not work:
            return None
        key = ("park", frozenset(work))

        def sources():
            cells = np.array(sorted(work))
            feet = walk.graph.feet
            cut = articulation_points(s.state.tiles, w, self.instance.height)
            near = np.zeros(walk.graph.feet.shape[0], bool)
            for k in range(feet.shape[1]):
                f = np.maximum(feet[:, k], 0)
                d = np.abs(f[:, None] % w - cells[None, :] % w) + np.abs(f[:, None] // w - cells[None, :] // w)
                near |= (d < PARKING).any(axis=1) | cut[f]
            return np.flatnonzero(walk.standing & ~near)

        goal = self._goal(i, walk, key, lambda: walk.distances_to(key, sources))
        return None if goal.dist[s.poses[i]] >= UNREACHABLE else goal

    def _pick_towards(self, s: LoopState, i: int, walk: Walk, pick: int, place: int) -> Goal:
        """The poses facing ``pick`` from which the tile, once picked, can be carried to a pose
        facing ``place`` (a pose facing the pick on the far side of a gap may have no way round
        with the tile). All poses facing the pick if none can."""
        def sources():
            rest = s.state.tiles.copy()
            rest[pick] = False
            carry = walk_for(walk.graph, rest, carrying=True).facing_distances(place)
            facing = walk.facing_poses(pick)
            able = facing[carry[facing] < UNREACHABLE]
            return able if len(able) else facing

        key = ("pick", pick, place)
        return self._goal(i, walk, key, lambda: walk.distances_to(key, sources))


def _downhill(walk: Walk, goal: Goal, pose: int) -> set[int]:
    """The cells swept on one shortest walk from ``pose`` to ``goal`` (none if unreachable)."""
    cells: set[int] = set()
    dist = goal.dist
    while UNREACHABLE > dist[pose] > 0:
        step = next(((c, q) for _, q, c in walk.moves(pose) if dist[q] == dist[pose] - 1), None)
        if step is None:  # no move down from here (cannot happen with distances of this walk)
            break
        swept, pose = step
        cells |= swept
    return cells
