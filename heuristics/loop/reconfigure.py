"""Reconfiguration by m robots: task allocation, the execution loop, load transfer (paper, Methods,
"Temporal A*" and "Load transfer").

The loop turns a reconfiguration sequence (:mod:`.sequence`) into a schedule, one time step at a
time. Each robot holds a list of *legs*: ``pick c`` (walk to a pose facing ``c``, pick the tile)
or ``place c`` (carry the tile to a pose facing ``c``, place it). The loop's state is one
:class:`~.loopstate.LoopState`; each step asks its parts for their decisions and applies them:

1. **Allocation** (:class:`~.allocation.Allocation`). The jobs of the sequence are handed out in
   order, each to the idle robot nearest to its pick; a tile a robot holds at the start is that
   robot's delivery job.
2. **Load transfer** (:class:`~.transfer.LoadTransfer`, ``load_transfer=True``), equations
   (1)-(3) of the paper: relays and swaps between robots within ``d_tr`` of each other.
3. **Goals** (:class:`~.goals.Goals`). A robot with legs is bound for the poses facing its next
   leg's cell if that pick or place could happen now, an idle robot for its goal cell, or out of
   the way; otherwise it is free.
4. **Manipulation** (:class:`~.manipulation.Manipulation`). A robot at a pose facing its leg's
   cell picks or places now when the rules allow it and the structure stays connected *and the
   rest of the sequence stays executable in order*; robots in the order of the priority queue
   ``Q``.
5. **Motion** (a motion layer of :mod:`.motion`: Temporal A* by default, M* or LaCAM*). The
   other robots move towards their goals.
6. The joint action goes through the canonical rules (:func:`~bille.instances.rules.apply`).

When the loop comes back to a state it was in (the same tiles, poses, legs, jobs and ``Q``), it
is going round in circles: the lowest robot of ``Q`` that has work moves up one place, and the
motion layer is told (LaCAM* then follows a joint plan out of the circle). After a budget of
such shifts, the latest step that made load transfers is undone and its transfers are never
made again (at most ``MAX_BACKTRACKS`` times).

**Path planning** (an instance whose tiles stay: no jobs) is this loop with the paper's
Temporal A* rules when the robots are stuck: in a circle, the lowest robot of ``Q`` not at its
goal moves up one place; a blocked robot moves up and the step is planned again; every such
shift counts against one budget (``max_shifts``), and when it is spent the run gives up
(``deadlock``); with ``shift_priorities=False`` the first block or circle ends it. The loop's
own ways out (cautious windows, evictions) are for making room for picks and places: measured
on crowded path-planning instances, they give up more often than the paper's rules
(docs/decisions.md). A robot that cannot reach its goal ends the run at once (``unreachable``),
and the step bound defaults to four times the robots' summed distances to their goals, at
least 100.

The run ends when every job is done, no robot carries a tile and every robot with a goal cell
stands on it. It gives up with status ``unsolved`` (reason in the result's ``failure``) when no
sequence is found, at the step bound, when the motion layer finds no joint action, or when the
robots are going round in circles after spending the budget of priority shifts; it stops with
``timeout`` at the time limit. Like Temporal A*, this loop is not complete.
"""
from __future__ import annotations

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.failure import CANNOT_REACH, Failure, cap, stuck
from bille.instances.rules import State, apply
from bille.instances.run import Budget, Run
from bille.instances.walking import UNREACHABLE

from ..joint import check_tables, to_result
from .allocation import Allocation
from .goals import Goals
from .joint_motion import DEADLOCK, timed_out
from .legs import Leg, Transfer
from .loop_options import LoopOptions
from .loopstate import LoopState
from .manipulation import Manipulation
from .motion import MOTIONS, Motion
from .sequence import NoSequence, sequence_of
from .transfer import LoadTransfer

RESTORED = ("circle_shifts", "relays", "swaps")  # counts that a backtrack sets back
PROGRESS_STEPS = 16  # the loop tells its progress every so many steps

WALKING = ("horizon", "epsilon", "steps", "priority_shifts", "replans", "expanded", "plan_ms_mean",
           "plan_ms_max")  # the counts of path planning (no jobs)


def plan(instance: Instance, options: LoopOptions | None = None, run: Run | None = None, *,
         motion: str | Motion = "temporal-astar", method: str | None = None):
    """Run the reconfiguration loop (module docstring); returns a
    :class:`~bille.instances.result.Result` named ``method`` (default: the motion layer's name).

    ``options``: the method's record (:class:`.loop_options.LoopOptions`, or Temporal A*'s, M*'s
    or LaCAM*'s, which hold it), checked for the instance by ``solve()`` or the caller
    (``options.check_instance``), not again here. ``motion``: a name of :data:`.motion.MOTIONS`
    (``temporal-astar``, ``mstar``, ``lacam``), made from ``options``, or a motion layer
    (:class:`.motion.Motion`) with its own options. ``run``: the run context (when its budget
    expires, status ``timeout``; default: no limit).
    """
    name = motion if isinstance(motion, str) else motion.name
    run = run or Run()
    budget = run.budget
    try:
        loop = Loop(instance, options, motion=motion, budget=budget, method=method)
    except NoSequence as exc:  # the loop gives up before its first step
        status = "timeout" if budget.expired() else "unsolved"
        kind = budget.why().kind if budget.expired() else "stuck"
        return to_result(instance, method or name, status, None, stats={}, failure=Failure(kind, str(exc)))
    loop.progress = run.events.on_progress
    result = loop.run(method or name)
    if result.schedule is not None:
        run.events.schedule(result.schedule)
    return result


class Stop(Exception):
    """The loop ends without a schedule: ``reason`` (the result's ``failure``) and its
    ``status`` (``unsolved``, ``timeout``, ``error``)."""

    def __init__(self, reason: Failure, status: str = "unsolved") -> None:
        super().__init__(reason.text)
        self.reason, self.status = reason, status


class Loop:
    """One run: the state :attr:`s`, the parts (:attr:`allocation`, :attr:`transfer` (None
    without load transfer), :attr:`manipulation`, :attr:`goals`, :attr:`motion`) and the
    counts :attr:`stats`; :meth:`run` drives them (options as for :func:`plan`)."""

    def __init__(self, instance: Instance, options: LoopOptions | None = None, *,
                 motion: str | Motion = "temporal-astar", budget: Budget | None = None,
                 method: str | None = None) -> None:
        o = options or LoopOptions()
        m = instance.num_robots
        name = method or (motion if isinstance(motion, str) else motion.name)
        if isinstance(motion, str) and motion not in MOTIONS:
            raise OptionError(f"unknown motion planner '{motion}' (expected one of: {', '.join(MOTIONS)})")
        Q = list(range(m)) if o.priorities is None else list(o.priorities)
        active = list(range(m)) if o.active is None else sorted(set(o.active))
        max_steps = o.max_steps
        self.instance = instance
        self.budget = budget or Budget()
        self.progress = None  # the run's progress receiver: told the steps planned every PROGRESS_STEPS
        self.path_planning = not instance.is_reconfiguration  # no jobs: the paper's rules when stuck
        if self.path_planning:
            check_tables(instance, name)
        elif m == 0:
            raise OptionError(f"instance '{instance.name}' has no robots to move its tiles")
        self.shift_priorities = o.shift_priorities
        jobs = [] if self.path_planning else sequence_of(instance, budget=self.budget)
        self.s = LoopState.start(instance, jobs, Q)
        jobs = self.s.jobs
        w, h = instance.width, instance.height
        carries = sum(abs(j.place % w - j.pick % w) + abs(j.place // w - j.pick // w)
                      for j in jobs if j.pick is not None)
        # default step bound: ten times the carries plus a crossing of the grid per job
        self.max_steps = max(200, 10 * (carries + len(jobs) * (w + h))) if max_steps is None else max_steps
        self.max_shifts = 4 * m * m + 4 * len(jobs) if o.max_shifts is None else o.max_shifts
        self.max_drops = len(jobs)  # temporary placements per run
        self.stats: dict = {"motion": name, "load_transfer": o.load_transfer, "d_tr": o.d_tr, "horizon": o.horizon,
                            "epsilon": o.epsilon, "jobs": len(jobs), "steps": 0, "relays": 0, "swaps": 0,
                            "pairs_considered": 0, "deferred_manipulations": 0, "priority_shifts": 0,
                            "circle_shifts": 0, "cautious_steps": 0, "replans": 0, "expanded": 0, "backtracks": 0,
                            "goals_dropped": 0, "drops": 0, "evictions": 0,
                            "plan_ms_mean": 0.0, "plan_ms_max": 0.0}
        if self.path_planning:  # the counts of walking alone
            self.stats = {k: self.stats[k] for k in WALKING}
        self.motion: Motion = MOTIONS[motion](o) if isinstance(motion, str) else motion
        # the paper's rules: the motion layer's replans spend the same budget (none with Q fixed)
        shifts = (self.max_shifts if o.shift_priorities else 0) if self.path_planning else None
        self.motion.start(instance, self.stats, shifts)
        self.allocation = Allocation(active)
        self.transfer = LoadTransfer(instance, o.d_tr, self.stats) if o.load_transfer else None
        self.manipulation = Manipulation(instance, self.s, self.stats)
        self.goals = Goals(instance, self.manipulation, parking=self.motion.parking, size=2 * m)
        if self.path_planning and max_steps is None:
            far = self._distances()
            self.max_steps = max(100, 4 * int(far[far < UNREACHABLE].sum()))

    def _distances(self) -> np.ndarray:
        """Each robot's steps to its goal from where it stands (0 without a goal cell); read from
        the goals' plain lists, which the motion layer reads every step (made here, before it)."""
        goals = self.goals.all(self.s)
        return np.array([0 if g is None else g.lists[0][p] for g, p in zip(goals, self.s.poses)], dtype=np.int64)

    def done(self) -> bool:
        return self.s.done(self.instance.goal_tiles, self.goals.cells)

    def _transfers(self, seen: set) -> None:
        """Step 2: the load transfers of this step, applied, and the state before them kept."""
        chosen = self.transfer.decide(self.s)
        if chosen:
            self.transfer.remember(self.s, seen, {k: self.stats[k] for k in RESTORED}, chosen)
            for t in chosen:
                self.s.transfer(t)
                self.stats["swaps" if t.kind == "swap" else "relays"] += 1

    def _backtrack(self) -> set:
        """Go back to before the latest step that made load transfers; the states seen then."""
        self.s, seen, counts = self.transfer.backtrack()
        self.stats.update(counts)
        self.motion.forget()
        return seen

    def _drop(self) -> dict[int, int]:
        """A temporary placement, applied: ``{robot: place action}``, or nothing."""
        if self.stats["drops"] >= self.max_drops:
            return {}
        found = self.manipulation.drop(self.s)
        if found is None:
            return {}
        robot, cell, action = found
        self.s.drop(robot, cell)
        self.stats["drops"] += 1
        return {robot: action}

    def run(self, method: str):
        """Step until the structure and the robots are at their goals (the paper's loop: jobs,
        transfers, circles, manipulations, motion), or until a :class:`Stop`; the result."""
        stats = self.stats
        step_times: list[float] = []
        try:
            if self.path_planning:
                unreachable = np.flatnonzero(self._distances() >= UNREACHABLE).tolist()
                if unreachable:
                    stats["unreachable"] = unreachable
                    raise Stop(CANNOT_REACH)
            self._steps(step_times)
        except Stop as stop:
            timing(stats, step_times)
            return to_result(self.instance, method, stop.status, None, stats=stats, failure=stop.reason)
        timing(stats, step_times)
        stats["final_priorities"] = list(self.s.Q)
        return to_result(self.instance, method, "feasible", self.s.steps, stats=stats)

    def _steps(self, step_times: list[float]) -> None:
        seen: set = set()
        told = -1
        while not self.done():
            s = self.s
            if self.progress is not None and len(s.steps) // PROGRESS_STEPS != told:
                told = len(s.steps) // PROGRESS_STEPS
                self.progress({"lower": None, "best": None, "elapsed": self.budget.elapsed(), "steps": len(s.steps)})
            if len(s.steps) >= self.max_steps:
                raise Stop(cap("step bound"))
            if self.budget.expired():
                raise Stop(self.budget.why(), "timeout")
            t0 = self.budget.now()
            for robot, k in self.allocation.decide(s):
                s.assign(robot, k)
            if self.transfer is not None:
                self._transfers(seen)
            key = s.key()
            if key in seen:
                seen, again = self._circling(s, seen)
                if again:
                    continue
            seen.add(key)
            self._step(s, t0, step_times)

    def _circling(self, s: LoopState, seen: set) -> tuple[set, bool]:
        """The state was met before: the robots go round in circles. Shift a priority (the paper's
        rule; in the loop, after the budget of shifts, back before the last load transfer, or
        idle robots evicted), or :class:`Stop` with a deadlock. ``(seen, again)``: the states
        seen from now on, and whether the step starts over (False: it is planned from here)."""
        stats = self.stats
        if self.path_planning:
            if not self.shift_priorities or stats["priority_shifts"] >= self.max_shifts:
                raise Stop(DEADLOCK)
            behind = [i for i in s.Q if not self._at_goal(i)]
            s.shift_up(behind[-1])
            stats["priority_shifts"] += 1
            return seen, True
        if stats["circle_shifts"] >= self.max_shifts:
            if self.transfer is not None and self.transfer.can_backtrack():
                return self._backtrack(), True
            if self.goals.evict(s):  # idle robots leave the poses the others need
                stats["evictions"] += 1
                stats["circle_shifts"] = 0
                self.motion.forget()
                return set(), True
            raise Stop(DEADLOCK)
        busy = [i for i in s.Q if s.legs[i] or self.goals.of(s, i) is not None] or list(s.Q)
        s.shift_up(busy[-1])
        stats["priority_shifts"] += 1
        stats["circle_shifts"] += 1
        return seen, self.motion.circle()

    def _step(self, s: LoopState, t0: float, step_times: list[float]) -> None:
        """Steps 3 and 4: the manipulations and the goals decided, the motion planned (or a
        tile put down where no plan gets a carrying robot on), and the joint action applied."""
        motion = self.motion
        fixed, intents = self.manipulation.decide(s)
        goals = self.goals.all(s)
        joint = motion.step(s, fixed, goals, intents, self.budget)
        if joint is None and motion.drops and not timed_out(motion.failure):
            fixed = self._drop()  # no plan gets a carrying robot on: it puts its tile down
            if fixed:
                joint = s.waits()
                for i, a in fixed.items():
                    joint[i] = a
                motion.forget()
        if joint is None:
            status = "timeout" if timed_out(motion.failure) else "unsolved"
            if self.path_planning:
                step_times.append(self.budget.now() - t0)
                raise Stop(self.budget.why() if status == "timeout" else motion.failure, status)
            raise Stop(stuck(f"{motion.label} found no joint plan ({motion.failure.text})"), status)
        step_times.append(self.budget.now() - t0)
        nxt = apply(s.world, s.state, joint, step=len(s.steps) + 1)
        if not isinstance(nxt, State):  # the planners respect the rules; this is a bug
            raise Stop(Failure("error", f"internal: {nxt}"), "error")
        progress = s.advance(joint, nxt, fixed)
        if progress:
            self.goals.evicted.clear()  # the work has moved on: evicted robots are idle again
        motion.stepped(s, fixed, goals, progress)
        self.stats["steps"] = len(s.steps)

    def _at_goal(self, i: int) -> bool:
        """Robot ``i`` stands on its goal cell, or has none."""
        cell = self.goals.cells[i]
        return cell < 0 or self.instance.world.graphs[i].feet[self.s.poses[i], 0] == cell


def timing(stats: dict, step_times: list[float]) -> None:
    """Mean and largest planning time per step, in ms, into ``stats``."""
    if step_times:
        stats["plan_ms_mean"] = round(1000 * float(np.mean(step_times)), 3)
        stats["plan_ms_max"] = round(1000 * float(np.max(step_times)), 3)


__all__ = ["Leg", "Loop", "LoopState", "MOTIONS", "Transfer", "plan"]
