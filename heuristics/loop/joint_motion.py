"""The joint motion layers of the reconfiguration loop: M* and LaCAM* (:mod:`.motion`).

Both follow a joint plan to the current goals (:class:`~.joint.JointProblem` towards the goals'
distance tables), planned again when the structure, the goals or the poses leave it; the robots
that manipulate make their pick or place where the plan has them wait and their cells are free.
M* keeps a manipulating robot where it is; LaCAM* lets it wait one step, then is free.

LaCAM* takes free steps of its configuration generator (:mod:`..lacam.pibt`) and plans only when the
loop goes round in circles, until the next pick or place; when no joint plan brings every robot
to its goal within :data:`LACAM_NODES` configurations, it plans for one robot at a time, and when
none is found at all, a carrying robot may put its tile down for a while (``drops``).
"""
from __future__ import annotations

import random

from bille.instances import Instance
from bille.instances.failure import Failure, stuck
from bille.instances.run import Budget
from bille.instances.walking import UNREACHABLE

from ..joint import JointProblem
from .loopstate import LoopState

MSTAR_EXPANSIONS = 100_000  # per M* replan: a joint plan that needs more ends the run
LACAM_NODES = 2_000  # per LaCAM* plan of a replan (a goal set that needs more is relaxed)
# blocked, or going round in circles, with the priority shifts spent (a motion layer, the loop)
DEADLOCK = stuck("deadlock")


def cut(budget: Budget) -> Failure:
    """A motion layer's plan for one step cut short by the run's budget (its time limit, or
    Ctrl-C: :meth:`Budget.why`)."""
    return Failure(budget.why().kind, "timeout")


def timed_out(failure: Failure | None) -> bool:
    """Whether a motion layer's failure is :func:`cut`'s."""
    return failure is not None and failure.kind in ("time-limit", "interrupted")


class _JointPlan:
    """A cached joint plan, followed while the state, the goals and the manipulations it was
    planned for come as expected."""

    label = ""
    parking = drops = False

    def start(self, instance: Instance, stats: dict, shifts: int | None = None) -> None:
        self.instance, self.stats = instance, stats
        self.failure: Failure | None = None
        self._plan: list | None = None  # the joint actions still to follow
        self._key = None  # the state, goals and manipulations the plan expects next

    def forget(self) -> None:
        self._plan, self._key = None, None

    def circle(self) -> bool:
        return True

    def stepped(self, s, fixed, goals, progress) -> None:
        if not fixed:  # the plan holds while it is followed
            self._key = (s.state.key(), tuple(None if g is None else g.key for g in goals), ())

    def _dists(self, s: LoopState, walks: list, fixed: dict[int, int], goals: list) -> list:
        raise NotImplementedError

    def _search(self, s: LoopState, problem: JointProblem, fixed: dict[int, int], budget: Budget):
        raise NotImplementedError

    def step(self, s, fixed, goals, intents, budget):
        """The next joint action of the plan (planned again when the structure, the goals or the
        poses left it); manipulations replace waits where they fit."""
        poses = s.poses
        key = (s.state.key(), tuple(None if g is None else g.key for g in goals), tuple(fixed))
        if self._key != key or not self._plan:
            walks = [s.walk(i) for i in range(len(poses))]
            dists = self._dists(s, walks, fixed, goals)
            # a goal out of reach for now (the structure is changing) does not hold the others up
            dists = [None if d is not None and d[p] >= UNREACHABLE else d for d, p in zip(dists, poses)]
            problem = JointProblem.towards(self.instance, walks, dists, poses)
            status, steps = self._search(s, problem, fixed, budget)
            self.stats["replans"] += 1
            if steps is None:
                self.stats["joint_status"] = status
                self.failure = cut(budget) if status == "timeout" else stuck(status)
                return None
            self._plan = list(steps) or [tuple(walks[i].wait for i in range(len(poses)))]
        joint = list(self._plan.pop(0))
        used: set[int] = set()
        for i, a in enumerate(joint):
            if i not in fixed:
                used |= s.walk(i).cells(poses[i], a)
        for i, a in fixed.items():
            cells = s.walk(i).cells(poses[i], a)
            if joint[i] == s.world.graphs[i].wait and cells.isdisjoint(used):
                joint[i] = a
            used |= s.walk(i).cells(poses[i], joint[i])
        return joint


class MStar(_JointPlan):
    """M* as the motion layer: a joint plan of at most ``max_expansions`` expansions per replan
    (a step that needs more ends the run)."""

    name, label = "mstar", "M*"

    def __init__(self, epsilon: float = 1.0, max_expansions: int = MSTAR_EXPANSIONS) -> None:
        self.epsilon, self.max_expansions = epsilon, max_expansions

    def _dists(self, s, walks, fixed, goals):
        return [(None if g is None else g.dist) if i not in fixed
                else walks[i].distances_to(("pose", s.poses[i]), lambda p=s.poses[i]: [p])
                for i, g in enumerate(goals)]

    def _search(self, s, problem, fixed, budget):
        from .. import mstar  # the planner, loaded when the loop runs with M*

        status, steps, stats = mstar.joint_plan(problem, epsilon=self.epsilon, budget=budget,
                                                max_expansions=self.max_expansions)
        self.stats["expanded"] += stats["expanded"]
        return status, steps


class LaCAM(_JointPlan):
    """LaCAM* as the motion layer (module docstring); ``seed`` for the generator's ties."""

    name, label, parking, drops = "lacam", "LaCAM*", True, True

    def __init__(self, max_nodes: int = LACAM_NODES, seed: int = 0) -> None:
        self.max_nodes, self.seed = max_nodes, seed

    def start(self, instance: Instance, stats: dict, shifts: int | None = None) -> None:
        super().start(instance, stats, shifts)
        self._priority = [0.0] * instance.num_robots  # the generator's priorities
        self._rng = random.Random(self.seed)
        self._zeros: dict[int, list[int]] = {}  # distance lists of robots without a goal
        self._escape = False  # follow a joint plan out of a circle
        self._free = False  # the last step was a free step
        self._turn = 0  # whose goal a one-robot joint plan serves next

    def circle(self) -> bool:
        if self._escape:
            return True
        self._escape = True  # out of the circle along a joint plan, now
        return False

    def step(self, s, fixed, goals, intents, budget):
        self._free = not self._escape
        if self._free:
            self._plan = None  # a joint plan, when needed again, starts from here
            return self._pibt(s, fixed, goals, intents)
        return super().step(s, fixed, goals, intents, budget)

    def stepped(self, s, fixed, goals, progress) -> None:
        if progress:
            self._escape = False  # free steps again
        if not self._free:
            super().stepped(s, fixed, goals, progress)

    def _pibt(self, s: LoopState, fixed: dict[int, int], goals: list, intents: dict[int, frozenset]) -> list[int]:
        """One step of LaCAM*'s configuration generator towards the current goals (no joint
        plan): robots in the order of their LaCAM priorities (a robot away from its goal gains
        one every step), a manipulating robot pinned to its manipulation's cells, a robot with
        an intent waiting while the robots on its manipulation's cells are pushed off."""
        from ..lacam import pibt  # the generator, loaded when the loop runs with LaCAM*

        poses = s.poses
        walks = [s.walk(i) for i in range(len(poses))]
        lists = []
        for i, g in enumerate(goals):
            dist = None if i in fixed or g is None else g.lists[0]
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

    def _dists(self, s, walks, fixed, goals):  # a manipulating robot waits one step, then is free
        return [None if i in fixed or g is None else g.dist for i, g in enumerate(goals)]

    def _search(self, s, problem, fixed, budget):
        """A plan that brings every robot to its goal at once; when none is found within
        ``max_nodes`` configurations (the goals may not all be held at once: one robot's goal
        pose stands where another must end), a plan for one robot alone while the others only
        make way (within 15 times as many), the robots taken in turn from ``Q`` (one further at
        every replan). ``goals_dropped`` counts the goals set aside for such plans."""
        from .. import lacam

        pinned = {i: s.walk(i).cells(problem.start[i], a) for i, a in fixed.items()}
        dists = [None if c < 0 else d for c, d in zip(problem.goals, problem.dists)]
        status, steps, stats = lacam.joint_plan(problem, budget=budget, max_nodes=self.max_nodes,
                                                pinned=pinned)
        self.stats["expanded"] += stats["nodes"]
        if steps is not None or status == "timeout":
            return status, steps
        movers = [i for i in s.Q if dists[i] is not None and dists[i][problem.start[i]] > 0]
        self._turn += 1
        for i in movers[self._turn % len(movers):] + movers[:self._turn % len(movers)] if movers else []:
            self.stats["goals_dropped"] += len(movers) - 1
            alone = [d if k == i else None for k, d in enumerate(dists)]
            one = JointProblem.towards(self.instance, problem.walks, alone, problem.start)
            status, steps, stats = lacam.joint_plan(one, budget=budget, max_nodes=15 * self.max_nodes,
                                                    pinned=pinned)
            self.stats["expanded"] += stats["nodes"]
            if steps is not None or status == "timeout":
                break
        return status, steps
