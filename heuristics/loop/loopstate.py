"""The state of the reconfiguration loop (paper, Methods, "Load transfer"), one step at a time.

:class:`LoopState` is everything the loop's parts read (:mod:`.allocation`, :mod:`.transfer`,
:mod:`.manipulation`, :mod:`.goals`, the motion layers of :mod:`.motion`): the rules' state
(tiles, poses, carried tiles), each robot's open legs, the sequence and how much of it is handed
out, the priority queue ``Q`` and the joint actions so far. The parts decide; the state applies
their decisions (:meth:`~LoopState.assign`, :meth:`~LoopState.transfer`, :meth:`~LoopState.drop`,
:meth:`~LoopState.advance`), so a part can be given any state and its decision looked at alone.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bille.instances import Instance
from bille.instances.moveset import Kind
from bille.instances.rules import State, World
from bille.instances.walking import Walk, walk_for

from .legs import Leg, Transfer
from .sequence import Job

Op = tuple[tuple, Kind, int, object]  # (order key, pick or place, cell, (robot, leg) or None)


@dataclass
class LoopState:
    """One step of the loop: ``state`` (tiles, poses, carrying), ``legs[i]`` robot ``i``'s open
    legs, ``jobs`` the sequence (a temporary placement inserts a job), ``next_job`` the first job
    not handed out, ``Q`` the priority queue (robot ids, highest first), ``steps`` the joint
    actions so far."""

    world: World = field(repr=False, compare=False)
    state: State
    legs: list[list[Leg]]
    jobs: list[Job]
    next_job: int = 0
    Q: list[int] = field(default_factory=list)
    steps: list[tuple[int, ...]] = field(default_factory=list)

    @classmethod
    def start(cls, instance: Instance, jobs: list[Job], priorities: list[int]) -> "LoopState":
        """The start: a tile a robot holds is that robot's delivery job (the sequence puts the
        deliveries first)."""
        s = cls(instance.world, instance.start_state, [[] for _ in range(instance.num_robots)], list(jobs),
                0, list(priorities))
        for k, job in enumerate(s.jobs):
            if job.pick is None:  # a delivery: the carrier's job from the start
                s.legs[job.carrier] = [Leg(Kind.PLACE, job.place, k)]
                s.next_job = k + 1
        return s

    @property
    def poses(self) -> tuple[int, ...]:
        return self.state.poses

    @property
    def num_robots(self) -> int:
        return len(self.legs)

    def key(self) -> tuple:
        """What the loop compares to see it is going round in circles."""
        return self.state.key(), tuple(map(tuple, self.legs)), self.next_job, tuple(self.Q)

    def shift_up(self, robot: int) -> None:
        """Move ``robot`` up one place in the priority queue ``Q``."""
        Q = self.Q
        k = Q.index(robot)
        if k > 0:
            Q[k - 1], Q[k] = Q[k], Q[k - 1]

    def snapshot(self) -> "LoopState":
        """A copy to go back to."""
        return LoopState(self.world, self.state, [list(legs) for legs in self.legs], self.jobs, self.next_job,
                         list(self.Q), list(self.steps))

    # ---- the world as the robots see it -----------------------------------------------------

    def walk(self, i: int, carrying: bool | None = None) -> Walk:
        """Robot ``i``'s walking graph on the current tiles (carrying as now, unless given)."""
        carrying = self.state.carrying[i] if carrying is None else carrying
        return walk_for(self.world.graphs[i], self.state.tiles, carrying)

    def cells_now(self, j: int) -> frozenset:
        """Robot ``j``'s feet and the tile it carries: cells every action of it touches."""
        return self.walk(j).cells(self.state.poses[j], self.world.graphs[j].wait)

    def occupied(self, but: int | None = None) -> set[int]:
        """Cells every action of the robots (except ``but``) touches this step."""
        out: set[int] = set()
        for j in range(len(self.legs)):
            if j != but:
                out |= self.cells_now(j)
        return out

    def waits(self) -> list[int]:
        return [self.world.graphs[i].wait for i in range(len(self.legs))]

    # ---- the work still to do ---------------------------------------------------------------

    def pending_picks(self) -> set[int]:
        """Cells of the picks still to do: the robots' legs and the jobs not handed out."""
        cells = {leg.cell for legs in self.legs for leg in legs if leg.kind == Kind.PICK}
        return cells | {j.pick for j in self.jobs[self.next_job:] if j.pick is not None}

    def pending_cells(self) -> set[int]:
        """Cells of the picks and places still to do."""
        cells = {leg.cell for legs in self.legs for leg in legs}
        return cells | {c for j in self.jobs[self.next_job:] for c in (j.pick, j.place) if c is not None}

    def pending_ops(self) -> list[Op]:
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

    def done(self, goal_tiles: np.ndarray, goal_cells) -> bool:
        """Every job done, no tile carried, the goal's tiles, every robot on its goal cell."""
        if self.next_job < len(self.jobs) or any(self.legs) or any(self.state.carrying):
            return False
        if not np.array_equal(self.state.tiles, goal_tiles):
            return False
        return all(c < 0 or self.world.graphs[i].feet[p, 0] == c
                   for i, (c, p) in enumerate(zip(goal_cells, self.state.poses)))

    # ---- the parts' decisions, applied --------------------------------------------------------

    def assign(self, robot: int, k: int) -> None:
        """Job ``k`` (the next one) goes to ``robot``: pick, then place."""
        job = self.jobs[k]
        self.legs[robot] = [Leg(Kind.PICK, job.pick, k), Leg(Kind.PLACE, job.place, k)]
        self.next_job = k + 1

    def transfer(self, t: Transfer) -> None:
        """A load transfer: a swap exchanges the two robots' drop-off cells; a relay has the
        giver drop its tile at ``t.cell`` and go on with the taker's job, and the taker pick it
        up there and carry it on."""
        i, j = t.giver, t.taker
        if t.kind == "swap":
            self.legs[i][0], self.legs[j][0] = self.legs[j][0], self.legs[i][0]
            return
        carried = self.legs[i][0]  # place x1 of job k1
        self.legs[i] = [Leg(Kind.PLACE, t.cell, carried.job, relay=True)] + self.legs[j]
        self.legs[j] = [Leg(Kind.PICK, t.cell, carried.job, relay=True), carried]

    def drop(self, robot: int, cell: int) -> None:
        """A temporary placement: ``robot`` puts its tile on ``cell``; the rest of its job (pick
        the tile up again, place it) becomes the next job to hand out."""
        leg = self.legs[robot][0]
        k = self.next_job
        self.jobs = self.jobs[:k] + [Job(cell, leg.cell)] + self.jobs[k:]
        self.legs[robot] = [Leg(Kind.PLACE, cell, leg.job)]

    def advance(self, joint: list[int], nxt: State, fixed: dict[int, int]) -> bool:
        """Take the step ``joint`` to ``nxt``: the robots of ``fixed`` whose manipulation was
        made end their leg. Returns whether one did."""
        done = False
        for i, a in fixed.items():
            if joint[i] == a:
                self.legs[i].pop(0)
                done = True
        self.steps.append(tuple(joint))
        self.state = nxt
        return done
