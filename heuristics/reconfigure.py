"""Reconfiguration by m robots: task allocation, the execution loop, load transfer (paper, Methods,
"Temporal A*" and "Load transfer").

The loop turns a reconfiguration sequence (:mod:`.sequence`) into a schedule, one time step at a
time. Each robot holds a list of *legs*: ``pick c`` (walk to a pose facing ``c``, pick the tile)
or ``place c`` (carry the tile to a pose facing ``c``, place it). Every step:

1. **Allocation.** The jobs of the sequence are handed out in order. The next job goes to the
   idle robot (no legs, no tile) nearest to its pick by pose-graph distance (walking to a pose
   facing the pick on the current structure; ties to the lower robot id); when no idle robot can
   reach it, allocation waits for the next step. A tile a robot holds at the start is that
   robot's delivery job.
2. **Load transfer** (``load_transfer=True``), equations (1)-(3) of the paper; see
   :meth:`Loop.transfers`.
3. **Goals.** A robot with legs is bound for the poses facing its next leg's cell, if that pick
   or place could happen now (step 4, robots aside); otherwise it has no goal for now, so that it
   gives way instead of holding a pose others need (a relay tile not dropped yet, a pick that
   must wait for another job); an idle robot
   for its goal cell if it has one; an idle robot standing on a tile that a pending job must
   pick for any pose whose feet are off those tiles; any other idle robot is free (it only keeps
   out of the way). Distance tables are cached per structure and goal.
4. **Manipulation.** A robot at a pose facing its leg's cell picks or places now when the
   rules allow it (a tile to pick, an empty cell to place on, no other robot on the cells) and
   the structure stays connected *and the rest of the sequence stays executable in order* from
   the tiles it leaves (so a pick that would disconnect, or that would strand a later place,
   waits until it would not). Robots are considered in the order of the priority queue ``Q``.
5. **Motion.** The other robots move with the motion planner: Temporal A* (the default;
   windows of ``H`` steps in the order of ``Q``, the manipulating robots' cells reserved first,
   a blocked robot moves up in ``Q``) or M* (a joint plan to the current goals, kept while the
   structure, the goals and the poses follow it, so paths are cached until goals change).
6. The joint action goes through the canonical rules (:func:`~bille.instances.rules.apply`).

The run ends when every job is done, no robot carries a tile and every robot with a goal cell
stands on it. It gives up with status ``unsolved`` (reason in ``stats["failure"]``) when no
sequence is found, at the step bound, when the motion planner finds no joint plan, or when the
robots are going round in circles after spending the budget of priority shifts; it stops with
``timeout`` at the time limit. Like Temporal A*, this loop is not complete.
"""
from __future__ import annotations

import random
import time

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.moveset import Kind
from bille.instances.rules import State, apply
from bille.instances.walking import Walk, walk_for

from .allocation import Allocation
from .joint import to_result
from .legs import Leg, Transfer, facing_feet
from .manipulation import Manipulation
from .motion import Motion
from .sequence import Job, NoSequence, sequence_of
from .temporal_astar import shift_up, timing
from .transfer import MAX_BACKTRACKS, LoadTransfer

MOTIONS = ("temporal-astar", "mstar", "lacam")
JOINT = {"mstar": "M*", "lacam": "LaCAM*"}  # the motion layers that follow a cached joint plan


def plan(instance: Instance, *, motion: str = "temporal-astar", load_transfer: bool = False, d_tr: int = 5,
         epsilon: float = 1.0, horizon: int = 5, time_limit: float | None = None, max_steps: int | None = None,
         max_shifts: int | None = None, priorities: list[int] | None = None, active: list[int] | None = None,
         method: str | None = None):
    """Run the reconfiguration loop (module docstring); returns a
    :class:`~bille.instances.result.Result` named ``method`` (default: ``motion``).

    ``motion``: ``temporal-astar`` or ``mstar``; ``load_transfer`` and ``d_tr``: equations
    (1)-(3); ``epsilon``, ``horizon``, ``priorities`` (the initial ``Q``): as for Temporal A*;
    ``max_steps``: the step bound (default: ten times the summed Manhattan carries plus ``W + H``
    per job, at least 200); ``max_shifts``: priority shifts allowed when going round in circles
    (default ``4 m^2 + 4 jobs``); ``active``: the robots that take jobs (default: all); the others
    only keep out of the way, and one that carries a tile at the start still delivers it.
    """
    try:
        loop = Loop(instance, motion=motion, load_transfer=load_transfer, d_tr=d_tr, epsilon=epsilon,
                    horizon=horizon, time_limit=time_limit, max_steps=max_steps, max_shifts=max_shifts,
                    priorities=priorities, active=active)
    except NoSequence as exc:  # the loop gives up before its first step
        return to_result(instance, method or motion, "unsolved", None, stats={"failure": str(exc)})
    return loop.run(method or motion)


class Loop(Allocation, LoadTransfer, Manipulation, Motion):
    """The state of one run; :meth:`run` drives it. Tests drive the parts (:meth:`transfers`)."""

    def __init__(self, instance: Instance, *, motion: str = "temporal-astar", load_transfer: bool = False,
                 d_tr: int = 5, epsilon: float = 1.0, horizon: int = 5, time_limit: float | None = None,
                 max_steps: int | None = None, max_shifts: int | None = None,
                 priorities: list[int] | None = None, active: list[int] | None = None) -> None:
        m = instance.num_robots
        if motion not in MOTIONS:
            raise OptionError(f"unknown motion planner '{motion}' (expected one of: {', '.join(MOTIONS)})")
        if epsilon < 1:
            raise OptionError(f"{motion}: epsilon must be >= 1, got {epsilon}")
        if horizon < 1:
            raise OptionError(f"{motion}: the horizon H must be >= 1, got {horizon}")
        if d_tr < 0:
            raise OptionError(f"{motion}: d_tr must be >= 0, got {d_tr}")
        self.Q = list(range(m)) if priorities is None else list(priorities)
        if sorted(self.Q) != list(range(m)):
            raise OptionError(f"{motion}: priorities must order the robot ids 0..{m - 1}, got {priorities}")
        if m == 0:
            raise OptionError(f"instance '{instance.name}' has no robots to move its tiles")
        if isinstance(active, int) and not isinstance(active, bool):
            active = [active]
        if active is not None and (not isinstance(active, (list, tuple)) or not active or not all(
                isinstance(i, int) and not isinstance(i, bool) and 0 <= i < m for i in active)):
            raise OptionError(f"{motion}: active must name some of the robot ids 0..{m - 1}, got {active!r}")
        self.active = list(range(m)) if active is None else sorted(set(active))
        self.instance, self.world = instance, instance.world
        self.motion, self.load_transfer, self.d_tr = motion, load_transfer, d_tr
        self.epsilon, self.horizon = epsilon, horizon
        self.start_time = time.perf_counter()
        self.deadline = None if time_limit is None else self.start_time + time_limit
        self.jobs: list[Job] = sequence_of(instance, deadline=self.deadline)
        self.state: State = instance.start_state
        self.legs: list[list[Leg]] = [[] for _ in range(m)]
        self.next_job = 0
        for k, job in enumerate(self.jobs):
            if job.pick is None:  # a delivery: the carrier's job from the start
                self.legs[job.carrier] = [Leg(Kind.PLACE, job.place, k)]
                self.next_job = k + 1
        w, h = instance.width, instance.height
        carries = sum(abs(j.place % w - j.pick % w) + abs(j.place // w - j.pick // w)
                      for j in self.jobs if j.pick is not None)
        # default step bound: ten times the carries plus a crossing of the grid per job
        self.max_steps = max(200, 10 * (carries + len(self.jobs) * (w + h))) if max_steps is None else max_steps
        self.max_shifts = 4 * m * m + 4 * len(self.jobs) if max_shifts is None else max_shifts
        self.max_drops = len(self.jobs)  # temporary placements (LaCAM* motion) per run
        self.goal_cells = instance.goal_cells
        self.steps: list[tuple[int, ...]] = []
        self.stats: dict = {"motion": motion, "load_transfer": load_transfer, "d_tr": d_tr, "horizon": horizon,
                            "epsilon": epsilon, "jobs": len(self.jobs), "steps": 0, "relays": 0, "swaps": 0,
                            "pairs_considered": 0, "deferred_manipulations": 0, "priority_shifts": 0,
                            "circle_shifts": 0, "cautious_steps": 0, "replans": 0, "expanded": 0, "backtracks": 0,
                            "goals_dropped": 0, "drops": 0,
                            "plan_ms_mean": 0.0, "plan_ms_max": 0.0}
        self._lists: dict = {}
        self._ready_key, self._ready = None, set()
        self._facing_feet = facing_feet(self.world)
        # check facing poses of the sequence's picks and places only if the sequence has them
        # in order (derived sequences do; a given task list may not)
        self._stands = True
        self._stands = self._executable(self.state.tiles, self._pending_ops())
        self.tabu: set[tuple] = set()  # transfers that led into a deadlock: never again
        self._checkpoints: list[tuple] = []  # the loop's state before each step with transfers
        self._joint: list | None = None  # the cached M* plan: remaining joint actions
        self._priority = [0.0] * m  # LaCAM* motion: the generator's priorities
        self._rng = random.Random(0)
        self._zeros: dict[int, list[int]] = {}  # distance lists of robots without a goal
        self._escape = False  # LaCAM* motion: follow a joint plan out of a circle
        self._turn = 0  # LaCAM* motion: whose goal a one-robot joint plan serves next
        self._joint_key = None  # the state, goals and manipulations the cached plan expects next

    # ---- the world as the robots see it -----------------------------------------------------

    def walk(self, i: int, carrying: bool | None = None) -> Walk:
        """Robot ``i``'s walking graph on the current tiles (carrying as now, unless given)."""
        carrying = self.state.carrying[i] if carrying is None else carrying
        return walk_for(self.world.graphs[i], self.state.tiles, carrying)
    # ---- the loop ---------------------------------------------------------------------------

    def done(self) -> bool:
        if self.next_job < len(self.jobs) or any(self.legs) or any(self.state.carrying):
            return False
        if not np.array_equal(self.state.tiles, self.instance.goal_tiles):
            return False
        return all(c < 0 or self.world.graphs[i].feet[p, 0] == c
                   for i, (c, p) in enumerate(zip(self.goal_cells, self.state.poses)))


    def run(self, method: str):
        seen: set = set()
        step_times: list[float] = []

        def stop(reason: str, status: str = "unsolved"):
            self.stats["failure"] = reason
            timing(self.stats, step_times)
            return to_result(self.instance, method, status, None, stats=self.stats)

        while not self.done():
            if len(self.steps) >= self.max_steps:
                return stop("step bound")
            if self.deadline is not None and time.perf_counter() > self.deadline:
                return stop("time limit", status="timeout")
            t0 = time.perf_counter()
            self.allocate()
            if self.load_transfer:
                snap = self._snapshot()
                if self.transfers():
                    self._checkpoints.append((snap, set(seen), self.chosen_keys))
            key = (self.state.key(), tuple(map(tuple, self.legs)), self.next_job, tuple(self.Q))
            if key in seen:  # going round in circles
                if self.stats["circle_shifts"] >= self.max_shifts:
                    if self._checkpoints and self.stats["backtracks"] < MAX_BACKTRACKS:
                        seen = self._backtrack()
                        continue
                    return stop("deadlock")
                busy = [i for i in self.Q if self.legs[i] or self.goal(i) is not None] or list(self.Q)
                shift_up(self.Q, busy[-1])
                self.stats["priority_shifts"] += 1
                self.stats["circle_shifts"] += 1
                if self.motion != "lacam" or self._escape:
                    continue
                self._escape = True  # LaCAM* motion: out of the circle along a joint plan, now
            seen.add(key)
            fixed, intents = self.manipulations()
            goals = [self.goal(i) for i in range(len(self.legs))]
            free_step = self.motion == "lacam" and not self._escape
            if free_step:
                joint = self._pibt(fixed, goals, intents)
                self._joint = None  # a joint plan, when needed again, starts from here
            elif self.motion in JOINT:
                joint = self._joint_step(fixed, goals, self.motion)
                if joint is None and self.motion == "lacam" and self.stats.get("joint_status") != "timeout":
                    dropped = self.drop()  # no plan gets a carrying robot on: it puts its tile down
                    if dropped:
                        fixed = dropped
                        joint = [self.world.graphs[i].wait for i in range(len(self.legs))]
                        for i, a in dropped.items():
                            joint[i] = a
                        self._joint = None
                if joint is None:
                    why = self.stats.get("joint_status")
                    return stop(f"{JOINT[self.motion]} found no joint plan ({why})",
                                status="timeout" if why == "timeout" else "unsolved")
            else:
                joint, blocked = self._temporal(fixed, goals, intents)
                for _ in range(len(self.Q)):  # a blocked robot moves up in Q (the paper's rule)
                    if blocked is None:
                        break
                    shift_up(self.Q, blocked)
                    self.stats["priority_shifts"] += 1
                    self.stats["replans"] += 1
                    joint, blocked = self._temporal(fixed, goals, intents)
                if blocked is not None:  # still blocked: every robot keeps off the lower ones
                    self.stats["cautious_steps"] += 1
                    joint, blocked = self._temporal(fixed, goals, intents, cautious=True)
                    if blocked is not None:  # the intents cannot be made room for now
                        joint, _ = self._temporal(fixed, goals, {}, cautious=True)
            step_times.append(time.perf_counter() - t0)
            nxt = apply(self.world, self.state, joint, step=len(self.steps) + 1)
            if not isinstance(nxt, State):  # the planners respect the rules; this is a bug
                return stop(f"internal: {nxt}", status="error")
            for i, a in fixed.items():
                if joint[i] == a:
                    self.legs[i].pop(0)
                    self._escape = False  # progress: LaCAM* motion takes free steps again
            self.steps.append(tuple(joint))
            self.state = nxt
            if self.motion in JOINT and not fixed and not free_step:  # the cached plan holds while it is followed
                self._joint_key = (nxt.key(), tuple(id(g) for g in goals), ())
            self.stats["steps"] = len(self.steps)
        timing(self.stats, step_times)
        self.stats["final_priorities"] = list(self.Q)
        return to_result(self.instance, method, "feasible", self.steps, stats=self.stats)





__all__ = ["Leg", "Loop", "MOTIONS", "Transfer", "plan"]
