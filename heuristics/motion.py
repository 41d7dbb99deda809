"""Goals and motion, steps 3 and 5 of the reconfiguration loop (paper, Methods, "Temporal A*").

Each robot is bound for the poses facing its next leg's cell when that pick or place could
happen now, else for its goal cell, else it only keeps out of the way; the robots that do not
manipulate this step then move with Temporal A* windows (:func:`.spacetime.reservation_step`)
or a cached joint plan of M* or LaCAM*.
"""
from __future__ import annotations

import time

import numpy as np

from bille.instances.grid import articulation_points
from bille.instances.moveset import Kind
from bille.instances.walking import UNREACHABLE, walk_for

from . import lacam, mstar, pibt
from .joint import JointProblem
from .spacetime import reservation_step

MSTAR_EXPANSIONS = 100_000  # per M* replan: a joint plan that needs more ends the run
LACAM_NODES = 2_000  # per LaCAM* plan of a replan (a goal set that needs more is relaxed)
PARKING = 5  # LaCAM* motion: an idle robot keeps its feet this far (Manhattan) from the work at hand


class Motion:
    """The loop's goals and motion planners (a part of :class:`.reconfigure.Loop`)."""

    def goal(self, i: int) -> np.ndarray | None:
        """Robot ``i``'s distance table to its current goal poses, or None (free)."""
        walk = self.walk(i)
        if self.legs[i]:
            if i not in self.ready():
                return None  # its pick or place cannot happen yet: give way meanwhile
            leg = self.legs[i][0]
            if leg.kind == Kind.PICK and len(self.legs[i]) > 1 and self.legs[i][1].kind == Kind.PLACE:
                return self._pick_towards(walk, i, leg.cell, self.legs[i][1].cell)
            return walk.facing_distances(leg.cell)
        if self.goal_cells[i] >= 0:
            return walk.distances(self.goal_cells[i])
        if self.motion == "lacam":
            return self._parking(walk, i)
        needed = self._pending_picks()
        feet = self.world.graphs[i].feet
        if needed.intersection(feet[self.state.poses[i]].tolist()):  # off the tiles still to be picked
            def clear():
                return np.flatnonzero(walk.standing & ~np.isin(feet, list(needed)).any(axis=1))

            return walk.distances_to(("clear", frozenset(needed)), clear)
        return None

    def _parking(self, walk, i: int) -> np.ndarray | None:
        """LaCAM* motion: an idle robot heads for the nearest pose whose feet keep at least
        :data:`PARKING` cells (Manhattan) from the work at hand (the cells of the robots' legs and
        of the next jobs to hand out) and off the structure's articulation points (a narrow
        passage), so that it does not stand where a pick, a place or the way to one needs it;
        None (free) if there is no such pose. (Keeping off the robots' shortest walks as well
        was measured and dropped: the parking poses then change every step, and the robots go
        round in circles.)"""
        w = self.instance.width
        soon = self.jobs[self.next_job:self.next_job + len(self.legs)]
        work = {leg.cell for legs in self.legs for leg in legs} | {c for j in soon for c in (j.pick, j.place)
                                                                   if c is not None}
        if not work:
            return None
        key = ("park", frozenset(work))

        def sources():
            cells = np.array(sorted(work))
            feet = walk.graph.feet
            cut = articulation_points(self.state.tiles, w, self.instance.height)
            near = np.zeros(walk.graph.feet.shape[0], bool)
            for k in range(feet.shape[1]):
                f = np.maximum(feet[:, k], 0)
                d = np.abs(f[:, None] % w - cells[None, :] % w) + np.abs(f[:, None] // w - cells[None, :] // w)
                near |= (d < PARKING).any(axis=1) | cut[f]
            return np.flatnonzero(walk.standing & ~near)

        dist = walk.distances_to(key, sources)
        return None if dist[self.state.poses[i]] >= UNREACHABLE else dist

    def _pick_towards(self, walk, i: int, pick: int, place: int) -> np.ndarray:
        """Distances to the poses facing ``pick`` from which the tile, once picked, can be
        carried to a pose facing ``place`` (a pose facing the pick on the far side of a gap may
        have no way round with the tile). All poses facing the pick if none can."""
        rest = self.state.tiles.copy()
        rest[pick] = False
        carry = walk_for(self.world.graphs[i], rest, carrying=True).facing_distances(place)

        def sources():
            facing = walk.facing_poses(pick)
            able = facing[carry[facing] < UNREACHABLE]
            return able if len(able) else facing

        return walk.distances_to(("pick", pick, place), sources)

    def _as_lists(self, dist: np.ndarray | None):
        if dist is None:
            return None, None
        key = id(dist)
        got = self._lists.get(key)
        if got is None or got[0] is not dist:
            got = (dist, dist.tolist(), (dist == 0).tolist())
            self._lists[key] = got
            if len(self._lists) > 512:
                self._lists.pop(next(iter(self._lists)))
        return got[1], got[2]

    # ---- 5. motion --------------------------------------------------------------------------

    def _temporal(self, fixed: dict[int, int], goals: list, intents: dict[int, frozenset],
                  cautious: bool = False) -> tuple[list[int] | None, int | None]:
        """Temporal A* windows for the robots not in ``fixed``: ``(joint action, None)`` or
        ``(None, blocked robot)``. The manipulating robots' cells are reserved for the whole
        window; a robot with an intent waits, and the cells of its manipulation are reserved
        from the second step on, so that the robot standing there must leave. ``cautious``: a
        robot keeps off the lower-priority robots' cells for the whole window, not only the
        first step (with no intents, then no robot is ever blocked: waiting is always left)."""
        H, poses = self.horizon, self.state.poses
        reserved: list[set[int]] = [set() for _ in range(H + 1)]
        joint = [0] * len(poses)
        for i, a in fixed.items():
            cells = self.walk(i).cells(poses[i], a)
            for t in range(1, H + 1):
                reserved[t] |= cells
            joint[i] = a
        for i, cells in intents.items():
            here = self._cells_now(i)
            reserved[1] |= here
            for t in range(2, H + 1):
                reserved[t] |= here | cells
            joint[i] = self.world.graphs[i].wait
        order = [i for i in self.Q if i not in fixed and i not in intents]
        walks = {i: self.walk(i) for i in order}
        targets = {i: self._as_lists(goals[i]) for i in order}
        first, blocked = reservation_step(order, walks, targets, poses, H, reserved, self._cells_now,
                                          self.epsilon, self.stats, cautious)
        if first is None:
            return None, blocked
        for i, a in first.items():
            joint[i] = a
        return joint, None

    def _pibt(self, fixed: dict[int, int], goals: list, intents: dict[int, frozenset]) -> list[int]:
        """One step of LaCAM*'s configuration generator towards the current goals (no joint
        plan): robots in the order of their LaCAM priorities (a robot away from its goal gains
        one every step), a manipulating robot pinned to its manipulation's cells, a robot with
        an intent waiting while the robots on its manipulation's cells are pushed off."""
        poses = self.state.poses
        walks = [self.walk(i) for i in range(len(poses))]
        lists = []
        for i, g in enumerate(goals):
            dist = None if i in fixed else self._as_lists(g)[0]
            if dist is None or dist[poses[i]] >= UNREACHABLE:
                size = walks[i].succ.shape[0]
                dist = self._zeros.setdefault(size, [0] * size)
            lists.append(dist)
        self._priority = pibt.next_priorities(self._priority, (d[p] == 0 for d, p in zip(lists, poses)))
        order = sorted(range(len(poses)), key=lambda i: -self._priority[i])
        pinned = {i: walks[i].cells(poses[i], a) for i, a in fixed.items()}
        joint, _ = pibt.next_configuration(walks, lists, poses, order, pinned, self._rng, intents)
        joint = list(joint)
        for i, a in fixed.items():
            joint[i] = a
        return joint

    def _lacam(self, problem: JointProblem, fixed: dict[int, int], left: float | None):
        """A LaCAM* plan that brings every robot to its goal at once; when none is found within
        :data:`LACAM_NODES` configurations (the goals may not all be held at once: one robot's
        goal pose stands where another must end), a plan for one robot alone while the others
        only make way (within 15 times as many), the robots taken in turn from ``Q`` (one further
        at every replan). ``stats["goals_dropped"]`` counts the goals set aside for such plans."""
        pinned = {i: self.walk(i).cells(problem.start[i], a) for i, a in fixed.items()}
        dists = [None if c < 0 else d for c, d in zip(problem.goals, problem.dists)]
        status, steps, stats = lacam.joint_plan(problem, time_limit=left, max_nodes=LACAM_NODES, pinned=pinned)
        self.stats["expanded"] += stats["nodes"]
        if steps is not None or status == "timeout":
            return status, steps
        movers = [i for i in self.Q if dists[i] is not None and dists[i][problem.start[i]] > 0]
        self._turn += 1
        for i in movers[self._turn % len(movers):] + movers[:self._turn % len(movers)] if movers else []:
            self.stats["goals_dropped"] += len(movers) - 1
            alone = [d if k == i else None for k, d in enumerate(dists)]
            one = JointProblem.towards(self.instance, problem.walks, alone, problem.start)
            left = None if self.deadline is None else max(0.1, self.deadline - time.perf_counter())
            status, steps, stats = lacam.joint_plan(one, time_limit=left, max_nodes=15 * LACAM_NODES, pinned=pinned)
            self.stats["expanded"] += stats["nodes"]
            if steps is not None or status == "timeout":
                break
        return status, steps

    def _joint_step(self, fixed: dict[int, int], goals: list, planner: str) -> list[int] | None:
        """The next joint action of the cached joint plan of ``planner`` (``mstar`` or ``lacam``;
        planned again when the structure, the goals or the poses left it); manipulations replace
        waits where they fit."""
        poses = self.state.poses
        key = (self.state.key(), tuple(id(g) for g in goals), tuple(fixed))
        if self._joint_key != key or not self._joint:
            walks = [self.walk(i) for i in range(len(poses))]
            if planner == "lacam":  # a manipulating robot waits one step, then is free
                dists = [None if i in fixed else g for i, g in enumerate(goals)]
            else:  # M* keeps a manipulating robot where it is
                dists = [g if i not in fixed else walks[i].distances_to(("pose", poses[i]), lambda p=poses[i]: [p])
                         for i, g in enumerate(goals)]
            # a goal out of reach for now (the structure is changing) does not hold the others up
            dists = [None if d is not None and d[p] >= UNREACHABLE else d for d, p in zip(dists, poses)]
            problem = JointProblem.towards(self.instance, walks, dists, poses)
            left = None if self.deadline is None else max(0.1, self.deadline - time.perf_counter())
            if planner == "lacam":
                status, steps = self._lacam(problem, fixed, left)
            else:
                status, steps, stats = mstar.joint_plan(problem, epsilon=self.epsilon, time_limit=left,
                                                        max_expansions=MSTAR_EXPANSIONS)
                self.stats["expanded"] += stats["expanded"]
            self.stats["replans"] += 1
            if steps is None:
                self.stats["joint_status"] = status
                return None
            self._joint = list(steps) or [tuple(walks[i].wait for i in range(len(poses)))]
        joint = list(self._joint.pop(0))
        used: set[int] = set()
        for i, a in enumerate(joint):
            if i not in fixed:
                used |= self.walk(i).cells(poses[i], a)
        for i, a in fixed.items():
            cells = self.walk(i).cells(poses[i], a)
            if joint[i] == self.world.graphs[i].wait and cells.isdisjoint(used):
                joint[i] = a
            used |= self.walk(i).cells(poses[i], joint[i])
        return joint

