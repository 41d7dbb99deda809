"""A schedule replayed for drawing: the state after every step, in coordinates.

Both the rerun recording and the pictures draw from a :class:`Trace`, so they show the same
thing. Frame ``t`` is the state after step ``t`` (frame 0 the start). The collision set shown at
frame ``t`` is the one of step ``t``, the motion that led there. When the schedule breaks a rule
at step ``k``, frames ``0 .. k - 1`` are the states reached, frame ``k`` repeats the last one with
the collision sets step ``k`` would sweep, and :attr:`Trace.violation` says what it would break (a
goal failure is reported at the last frame).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, Kind, State, Violation
from bille.instances.rules import goal_violation, run
from bille.instances.metrics import action_kinds
from bille.instances.schedule import Schedule, bind

XY = tuple[int, int]


@dataclass(frozen=True, eq=False)
class Trace:
    """Frames ``0 .. steps`` of one schedule on one instance.

    ``tiles[t]`` is the flat tile mask, ``front[t, i]`` / ``back[t, i]`` robot ``i``'s feet as
    ``(x, y)`` (a point robot's back foot is its front foot), ``carrying[t, i]`` its load;
    ``swept[t][i]`` the collision set of step ``t`` (``swept[0]`` is empty), ``actions[t][i]`` its
    action name (``actions[0]`` is empty); ``traveled[t]`` the tiles traveled up to step ``t``
    and ``waiting[t]`` the robots that wait at step ``t``.
    """

    instance: Instance
    label: str
    tiles: np.ndarray
    front: np.ndarray
    back: np.ndarray
    carrying: np.ndarray
    swept: tuple[tuple[tuple[XY, ...], ...], ...]
    actions: tuple[tuple[str, ...], ...]
    traveled: np.ndarray
    waiting: np.ndarray
    violation: Violation | None = None

    @property
    def steps(self) -> int:
        """The last frame's number."""
        return len(self.tiles) - 1

    def load_cell(self, t: int, i: int) -> XY | None:
        """Where robot ``i``'s carried tile is drawn at frame ``t``: the cell ahead of its front
        foot (a point robot carries it on its own cell); None if it carries nothing."""
        if not self.carrying[t, i]:
            return None
        (fx, fy), (bx, by) = self.front[t, i], self.back[t, i]
        return int(2 * fx - bx), int(2 * fy - by)

    def changes(self) -> list[int]:
        """Frames where the tile set differs from the frame before (always frame 0)."""
        diff = (self.tiles[1:] != self.tiles[:-1]).any(axis=1)
        return [0] + (np.flatnonzero(diff) + 1).tolist()


def trace(instance: Instance, schedule: Schedule | None = None, label: str = "schedule") -> Trace:
    """Replay ``schedule`` (None: the start state alone) on ``instance`` under the rules.

    Raises :class:`~bille.instances.ScheduleError` when the schedule does not fit the instance
    (robot count, action names); rule violations end the trace and are kept in ``violation``.

    >>> from bille.instances.bundled import bundled_path
    >>> from bille.instances import load_instance
    >>> from bille.solvers import load_schedule
    >>> inst = load_instance(bundled_path("corridor-2"))
    >>> tr = trace(inst, load_schedule(bundled_path("corridor-2.schedule")))
    >>> tr.steps, tr.violation is None
    (13, True)
    """
    ids = bind(instance, schedule) if schedule is not None else np.zeros((instance.num_robots, 0), np.int64)
    world = instance.world
    states: list[State] = [instance.start_state]
    violation = None
    for nxt in run(world, states[0], ids):
        if isinstance(nxt, Violation):
            violation = nxt
            break
        states.append(nxt)
    done = len(states) - 1
    if violation is None and schedule is not None:
        violation = goal_violation(world, states[-1], instance.goal_tiles, instance.goal_cells, done)
    elif violation is not None:
        states.append(states[-1])  # frame k: the state the failing step starts from

    m = instance.num_robots
    movesets = instance.movesets
    poses = np.array([s.poses for s in states], dtype=np.int64).reshape(len(states), m)
    feet = np.zeros((len(states), m, 2), dtype=np.int64)  # cells
    kinds = action_kinds(instance, ids[:, :done])
    for i, g in enumerate(world.graphs):
        feet[:, i] = g.feet[poses[:, i]]
    w = instance.width
    front = np.stack([feet[..., 0] % w, feet[..., 0] // w], axis=-1)
    back = np.stack([feet[..., 1] % w, feet[..., 1] // w], axis=-1)

    swept: list[tuple[tuple[XY, ...], ...]] = [tuple(() for _ in range(m))]
    actions: list[tuple[str, ...]] = [tuple("" for _ in range(m))]
    graphs = world.graphs
    for t in range(1, done + 1):
        before = states[t - 1]
        swept.append(tuple(_collision(graphs[i], before.poses[i], int(ids[i, t - 1]), before.carrying[i], w)
                           for i in range(m)))
        actions.append(tuple(movesets[i].actions[ids[i, t - 1]].name for i in range(m)))
    if violation is not None and violation.rule != "goal":  # the failing step, attempted
        last = states[-1]
        swept.append(tuple(_collision(graphs[i], last.poses[i], int(ids[i, done]), last.carrying[i], w)
                           for i in range(m)))
        actions.append(tuple(movesets[i].actions[ids[i, done]].name for i in range(m)))

    pad = len(states) - 1 - done
    traveled = np.concatenate([[0], np.cumsum((kinds == int(Kind.MOTION)).sum(axis=0)), np.zeros(pad, np.int64)])
    if pad:
        traveled[-pad:] = traveled[done]
    waiting = np.concatenate([[0], (kinds == int(Kind.WAIT)).sum(axis=0), np.zeros(pad, np.int64)])
    return Trace(instance, label, np.array([s.tiles for s in states]), front, back,
                 np.array([s.carrying for s in states], dtype=bool).reshape(len(states), m),
                 tuple(swept), tuple(actions), traveled.astype(np.int64), waiting.astype(np.int64), violation)


def _collision(graph, pose: int, action: int, carrying: bool, width: int) -> tuple[XY, ...]:
    cells = graph.coll[pose, action].tolist() + (graph.carry[pose, action].tolist() if carrying else [])
    return tuple((c % width, c // width) for c in dict.fromkeys(cells) if c >= 0)
