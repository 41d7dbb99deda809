"""The ``crossings`` part of the static bound (:mod:`.static`): tiles that must cross a line, and
the trips of the robots that carry them across.

Draw a line between two columns (or two rows) of the grid: ``X`` the cells on one side, ``Y`` the
cells on the other. Write ``S`` and ``G`` for the cells with a tile at the start and in the goal,
and ``a = |S & X| - |G & X|``: the side ``X`` has ``a`` tiles more at the start than in the goal.

**Theorem.** Take ``a > 0`` and, for each robot ``r``: ``d_r``, the relaxed distance from its start
pose to a pose from which a pick targets a cell of ``X``; ``c_r``, the least relaxed distance from
such a pose to a pose from which a place targets a cell of ``Y``; ``b_r``, the least from the latter
back to the former; and ``T_r(k) = d_r + k (c_r + 2) + (k - 1) b_r`` for ``k >= 1``. Every schedule
has a makespan of at least the ``a``-th smallest of all the numbers ``T_r(k)`` (each robot ``r``
and each ``k = 1, 2, ...``).

**Proof.** A tile moves only while a robot carries it, from a pick to that robot's next place (a
*trip*: rules 1 and 3; a relay is a place and another robot's pick). Count the tiles on ``X``: a
trip from ``X`` to ``Y`` takes one away, a trip from ``Y`` to ``X`` or the place of a tile carried
since the start adds one, and no robot carries a tile at the end (the goal), so at least ``a``
trips go from ``X`` to ``Y``. Say robot ``r`` makes ``k_r`` of them. Its first pick on ``X`` is
made from a pose it reaches after at least ``d_r`` steps, and takes a step; a pick and a place
leave the robot where it stands, and every step is a step of the relaxed graph
(:mod:`bille.instances.distances`), so the place on ``Y`` comes at least ``c_r`` steps later and
takes a step; before its next pick on ``X`` the robot walks back, at least ``b_r`` steps. So its
``k``-th trip from ``X`` to ``Y`` ends after at least ``T_r(k)`` steps, and the makespan is at
least ``max T_r(k_r)`` over the robots with ``k_r >= 1``, where ``sum k_r >= a``. Each ``T_r``
increases with ``k``, so the least such maximum is the ``a``-th smallest of the numbers
``T_r(k)``. The part is the largest bound over the lines and both sides of each.

Within a class of schedules (:mod:`.classes`) the same holds with the poses, picks and places of
the class's ground (:class:`.ground.Ground`). There the part is strong where the tiles can only
be set down far apart: in a schedule that keeps the structure, a tile goes from one platform of
a load-transfer map to the other in one trip, and with more tiles than robots one robot makes
the trip, and the way back, twice.
"""
from __future__ import annotations

import heapq

import numpy as np

from bille.instances import Instance
from bille.instances.distances import INF
from bille.instances.moveset import Kind
from bille.instances.run import Budget

from .ground import Ground


def crossings_bound(instance: Instance, ground: Ground, budget: Budget | None = None) -> int | None:
    """The part of the module docstring: the largest bound over every line between two columns or
    two rows and both its sides (lines left out once ``budget`` expires); None where no line has
    tiles to move across that the robots can carry."""
    w, h = instance.width, instance.height
    start, goal = instance.start.tiles.reshape(h, w), instance.goal_tiles.reshape(h, w)
    xs, ys = np.meshgrid(np.arange(w), np.arange(h))
    sides = [xs <= x for x in range(w - 1)] + [ys <= y for y in range(h - 1)]
    events = {}  # per pose graph: its relaxed graph on the ground, and its (pose, cell) picks and places
    for graph in instance.world.graphs:
        if id(graph) not in events:
            events[id(graph)] = (ground.relaxed(graph), ground.targets(graph, Kind.PICK, w * h),
                                 ground.targets(graph, Kind.PLACE, w * h))
    best = None
    for side in sides:
        for X in (side, ~side):
            if budget is not None and budget.expired():
                return best
            a = int(start[X].sum()) - int(goal[X].sum())
            if a > 0:
                found = _across(instance, events, X.ravel(), a)
                if found is not None:
                    best = found if best is None else max(best, found)
    return best


def _across(instance: Instance, events: dict, X: np.ndarray, a: int) -> int | None:
    """The ``a``-th smallest of the numbers ``T_r(k)`` for the side ``X`` (module docstring), or
    None if the robots cannot make ``a`` trips; ``events`` per pose graph as
    :func:`crossings_bound` makes them."""
    world, poses = instance.world, instance.start_state.poses
    trips = []  # T_r(k) for every robot and k = 1..a
    legs: dict[int, tuple] = {}  # per pose graph: (distances to a pick on X, c, b)
    for i, graph in enumerate(world.graphs):
        if id(graph) not in legs:
            relaxed, (pick, picked), (place, placed) = events[id(graph)]
            pick, place = pick[X[picked]], place[~X[placed]]
            if len(pick) == 0 or len(place) == 0:
                legs[id(graph)] = None
                continue
            to_pick, to_place = relaxed.to_poses(pick), relaxed.to_poses(place)
            legs[id(graph)] = (to_pick, int(to_place[pick].min()), int(to_pick[place].min()))
        if legs[id(graph)] is None:
            continue
        to_pick, c, b = legs[id(graph)]
        d = int(to_pick[poses[i]])
        if d >= INF or c >= INF:
            continue
        trips.append(d + c + 2)
        if b < INF:
            trips.extend(d + k * (c + 2) + (k - 1) * b for k in range(2, a + 1))
    if len(trips) < a:
        return None
    return heapq.nsmallest(a, trips)[-1]
