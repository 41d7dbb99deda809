"""Single-robot A* over (pose, time) with a reservation table (paper, Methods, "Temporal A*").

Time is part of the vertex, so waiting is a move like any other. The search plans one robot's
next ``H`` steps on the current structure, avoiding the cells that other robots have reserved
at each step (their collision cells) and, on the first step only, cells that are blocked (the
current feet of lower-priority robots). A step costs 1 unless the robot is at its goal before
and after it; ``f = g + epsilon * h`` with ``h`` the breadth-first distance to the goal.
"""
from __future__ import annotations

import heapq
import itertools

from bille.instances.walking import Walk


def window(walk: Walk, dist: list[int] | None, home: list[bool] | None, pose: int, H: int,
           reserved: list[set[int]], blocked_first: set[int], epsilon: float = 1.0,
           stats: dict | None = None) -> list[tuple[int, int]] | None:
    """The best ``H``-step walk from ``pose``: ``[(action, pose after)] * H``, or None if no walk
    avoids the reservations (``reserved[t]``: cells taken at step ``t``, ``t = 1 .. H``; index 0
    unused) and, at step 1, ``blocked_first``.

    ``dist[p]`` is the distance from pose ``p`` to the goal and ``home[p]`` whether ``p`` has
    the front foot on it (plain lists: this is the inner loop of Temporal A*). With ``dist``
    None (no goal) every step is free and the robot only keeps out of the way.
    """
    if dist is None:
        def at_goal(p: int) -> bool:
            return True

        def h(p: int) -> float:
            return 0.0
    else:
        def at_goal(p: int) -> bool:
            return home[p]

        def h(p: int) -> float:
            return epsilon * dist[p]

    counter = itertools.count()
    g = {(pose, 0): 0}
    parent: dict = {(pose, 0): None}
    frontier = [(h(pose), 0, next(counter), pose, 0)]
    expanded = 0
    while frontier:
        _, _, _, p, t = heapq.heappop(frontier)
        if t == H:
            if stats is not None:
                stats["expanded"] = stats.get("expanded", 0) + expanded
            return _unwind(parent, (p, t))
        expanded += 1
        gp = g[(p, t)]
        taken = reserved[t + 1]
        here = at_goal(p)
        for a, q, cells in walk.moves(p):
            if not taken.isdisjoint(cells) or (t == 0 and not blocked_first.isdisjoint(cells)):
                continue
            node = (q, t + 1)
            cost = gp + (0 if here and at_goal(q) else 1)
            if cost < g.get(node, 1 << 60):
                g[node] = cost
                parent[node] = ((p, t), a)
                # deeper nodes first on ties: reach the end of the window sooner
                heapq.heappush(frontier, (cost + h(q), -(t + 1), next(counter), q, t + 1))
    if stats is not None:
        stats["expanded"] = stats.get("expanded", 0) + expanded
    return None


def _unwind(parent: dict, node) -> list[tuple[int, int]]:
    path = []
    while parent[node] is not None:
        prev, a = parent[node]
        path.append((a, node[0]))
        node = prev
    return path[::-1]


def reservation_step(order: list[int], walks: list[Walk], goals: list, poses, H: int,
                     reserved: list[set[int]], here, epsilon: float = 1.0, stats: dict | None = None,
                     cautious: bool = False) -> tuple[dict[int, int] | None, int | None]:
    """One step of prioritized planning: the robots of ``order`` (highest priority first) plan
    their windows one after another, each avoiding the cells reserved by those before it and, at
    the first step, the cells ``here(j)`` of every robot ``j`` below it. ``goals[i]`` is robot
    ``i``'s ``(dist, home)`` pair for :func:`window`; ``reserved`` is updated in place.
    ``cautious``: a robot keeps off the lower robots' cells for the whole window.

    Returns ``({robot: first action}, None)``, or ``(None, robot)`` for the first robot that
    finds no walk. Temporal A* and the reconfiguration loop share it.
    """
    below: list[set[int]] = [set() for _ in range(len(order) + 1)]
    for rank in range(len(order) - 1, -1, -1):
        below[rank] = below[rank + 1] | set(here(order[rank]))
    first: dict[int, int] = {}
    for rank, i in enumerate(order):
        walk = walks[i]
        dist, home = goals[i]
        avoid = [r | below[rank + 1] for r in reserved] if cautious else reserved
        path = window(walk, dist, home, poses[i], H, avoid, below[rank + 1], epsilon, stats)
        if path is None:
            return None, i
        p = poses[i]
        for t, (a, q) in enumerate(path, start=1):
            reserved[t].update(walk.cells(p, a))
            p = q
        first[i] = path[0][0]
    return first, None
