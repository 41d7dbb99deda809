"""Motion, step 5 of the reconfiguration loop (paper, Methods, "Temporal A*"): the motion layers.

A motion layer plans the next joint action of the robots that do not manipulate this step,
towards their goals (:mod:`.goals`), within the loop's budget. Every layer has the shape of
:class:`Motion`, and :data:`MOTIONS` makes one by name:

- ``temporal-astar`` (:class:`TemporalAStar`, the paper's): windows of ``H`` steps planned in
  the order of ``Q`` (:func:`.spacetime.reservation_step`), the manipulating robots' cells
  reserved first; a blocked robot moves up in ``Q``. On path planning this layer and the loop
  are the method ``temporal-astar`` itself, with the paper's rules when stuck.
- ``mstar`` and ``lacam`` (:mod:`.joint_motion`): a joint plan to the current goals, followed
  while the structure, the goals and the poses follow it.
"""
from __future__ import annotations

from functools import cache
from typing import Callable, Protocol

from bille.instances import Instance
from bille.instances.failure import Failure
from bille.instances.run import Budget

from ..spacetime import reservation_step
from .goals import Goal
from .joint_motion import DEADLOCK, LaCAM, MStar, cut
from .loopstate import LoopState


class Motion(Protocol):
    """A motion layer: one object per run of the loop.

    ``name`` is the method's name and ``label`` the planner's in messages. ``parking``: idle
    robots head for poses out of the way of the work (:class:`.Goals`). ``drops``: when the
    layer finds no joint action, a carrying robot may put its tile down for a while.
    """

    name: str
    label: str
    parking: bool
    drops: bool
    failure: Failure | None  # why the last :meth:`step` found no joint action (:func:`cut`, ...)

    def start(self, instance: Instance, stats: dict, shifts: int | None = None) -> None:
        """Begin a run on ``instance``, counting into ``stats``. ``shifts``: path planning, the
        paper's rules: priority shifts allowed in the run (``stats["priority_shifts"]`` counts
        them); None: the loop's own rules."""

    def step(self, s: LoopState, fixed: dict[int, int], goals: list[Goal | None],
             intents: dict[int, frozenset], budget: Budget) -> list[int] | None:
        """The next joint action from state ``s``: the robots of ``fixed`` make their
        manipulation (or wait), the others head for ``goals`` (None: free), a robot with an
        intent waits while its manipulation's cells are made room for; planned within ``budget``
        (the loop's). None when there is none (:attr:`failure` says why)."""

    def circle(self) -> bool:
        """The loop came back to a state it was in (``Q`` has just changed): True to plan the
        step again at once, False to take it."""

    def stepped(self, s: LoopState, fixed: dict[int, int], goals: list[Goal | None], progress: bool) -> None:
        """The step was taken (``s`` is the state after it); ``progress``: a pick or place was made."""

    def forget(self) -> None:
        """Drop any plan held: the loop's state changed other than by following it."""


class TemporalAStar:
    """Temporal A* windows for the robots not in ``fixed`` (module docstring). The manipulating
    robots' cells are reserved for the whole window; a robot with an intent waits, and the cells
    of its manipulation are reserved from the second step on, so that the robot standing there
    must leave. A blocked robot moves up in ``Q`` (the paper's rule) and the step is planned
    again; if one is still blocked, every robot keeps off the lower robots' cells for the whole
    window (*cautious*), and if even then, without the intents. With the paper's rules (path
    planning), a blocked robot moves up and the step is planned again while the run's budget of
    shifts lasts, and no further (``deadlock``)."""

    name, label, parking, drops = "temporal-astar", "Temporal A*", False, False

    def __init__(self, horizon: int = 5, epsilon: float = 1.0) -> None:
        self.horizon, self.epsilon = horizon, epsilon
        self.failure: Failure | None = None

    def start(self, instance: Instance, stats: dict, shifts: int | None = None) -> None:
        self.stats, self.shifts = stats, shifts

    def step(self, s, fixed, goals, intents, budget):
        self.failure = None
        # what the replans of this step share: the state does not change between them, Q does
        self._walk, self._here = cache(s.walk), cache(s.cells_now)
        joint, blocked = self._window(s, fixed, goals, intents)
        if self.shifts is not None:
            return self._paper(s, fixed, goals, intents, budget, joint, blocked)
        for _ in range(len(s.Q)):
            if blocked is None:
                break
            if budget.expired():  # between replans too
                self.failure = cut(budget)
                return None
            joint, blocked = self._replan(s, blocked, fixed, goals, intents)
        if blocked is not None:
            self.stats["cautious_steps"] += 1
            joint, blocked = self._window(s, fixed, goals, intents, cautious=True)
            if blocked is not None:  # the intents cannot be made room for now
                joint, _ = self._window(s, fixed, goals, {}, cautious=True)
        return joint

    def _paper(self, s, fixed, goals, intents, budget, joint, blocked):
        """The paper's rule for a blocked robot (class docstring)."""
        while blocked is not None:
            if self.stats["priority_shifts"] >= self.shifts:
                self.failure = DEADLOCK
                return None
            if budget.expired():  # many robots: many replans
                self.failure = cut(budget)
                return None
            joint, blocked = self._replan(s, blocked, fixed, goals, intents)
        return joint

    def _replan(self, s, blocked: int, fixed, goals, intents):
        """The blocked robot moves up in ``Q``; the step is planned again."""
        s.shift_up(blocked)
        self.stats["priority_shifts"] += 1
        self.stats["replans"] += 1
        return self._window(s, fixed, goals, intents)

    def _window(self, s: LoopState, fixed: dict[int, int], goals: list[Goal | None],
                intents: dict[int, frozenset], cautious: bool = False) -> tuple[list[int] | None, int | None]:
        """``(joint action, None)`` or ``(None, blocked robot)``. ``cautious``: a robot keeps off
        the lower-priority robots' cells for the whole window, not only the first step (with no
        intents, then no robot is ever blocked: waiting is always left)."""
        H, poses = self.horizon, s.poses
        reserved: list[set[int]] = [set() for _ in range(H + 1)]
        joint = [0] * len(poses)
        for i, a in fixed.items():
            cells = self._walk(i).cells(poses[i], a)
            for t in range(1, H + 1):
                reserved[t] |= cells
            joint[i] = a
        for i, cells in intents.items():
            here = self._here(i)
            reserved[1] |= here
            for t in range(2, H + 1):
                reserved[t] |= here | cells
            joint[i] = s.world.graphs[i].wait
        order = [i for i in s.Q if i not in fixed and i not in intents]
        walks = {i: self._walk(i) for i in order}
        targets = {i: (None, None) if goals[i] is None else goals[i].lists for i in order}
        first, blocked = reservation_step(order, walks, targets, poses, H, reserved, self._here,
                                          self.epsilon, self.stats, cautious)
        if first is None:
            return None, blocked
        for i, a in first.items():
            joint[i] = a
        return joint, None

    def circle(self) -> bool:
        return True

    def stepped(self, s, fixed, goals, progress) -> None:
        pass

    def forget(self) -> None:
        pass


MOTIONS: dict[str, Callable[..., Motion]] = {
    "temporal-astar": lambda o: TemporalAStar(horizon=o.horizon, epsilon=o.epsilon),
    "mstar": lambda o: MStar(epsilon=o.epsilon),
    "lacam": lambda o: LaCAM(),
}
"""Motion layer by name: ``MOTIONS[name](options)`` makes one for a run from the method's options
(:class:`.loop_options.LoopOptions` or a record holding it; each takes what it has: ``horizon``
is Temporal A*'s, ``epsilon`` Temporal A*'s and M*'s)."""


__all__ = ["MOTIONS", "LaCAM", "MStar", "Motion", "TemporalAStar"]
