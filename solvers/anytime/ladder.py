"""The widening ladder of anytime solving: the exact joint search (:mod:`bille.solvers.bfs`) over
classes of schedules that grow, from the class that keeps the structure towards the schedules
without scaffold, each searched below the best schedule known.

A *rung* is the class ``keep`` widened by a list of cells (``add_cells``); rung ``k`` adds the
first ``k * RUNG`` cells of :func:`candidates`. Each class holds the one below it, so its
optimum is at most the one below; a decided rung proves its class's optimum (the search below the
best schedule ``U`` exhausted: nothing shorter than ``U`` in that class; or a shorter schedule,
which is offered to the bracket and becomes ``U``). A rung stopped by the time or the state cap
proves a bound of its class only, and the ladder stops there: every rung above holds it.

The candidates are the cells where both the start and the goal have a tile (so a schedule
without scaffold may lift the tile and set it down again: a hole to hand a tile over through, a
row moved along by one), except those whose lifting disconnects the start structure. They come
nearest first to a cell that changes (steps over tiles), as a shorter schedule changes the
structure around the cells it must change; ties by position. The ladder is a search for shorter
schedules and a record of what each class proves, not a bound on every schedule.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from bille.instances import Instance
from bille.instances.grid import articulation_points, neighbour_table
from bille.instances.run import Budget, Run
from bille.instances.metrics import metrics
from bille.instances.schedule import Schedule, bind

RUNG = 2  # cells a rung adds to the one below


def candidates(instance: Instance) -> list[tuple[int, int]]:
    """The cells the ladder adds, in order (module docstring)."""
    w, h = instance.width, instance.height
    start, goal = instance.start.tiles, instance.goal_tiles
    both = start & goal
    cut = articulation_points(start, w, h)
    dist = np.full(w * h, -1, np.int64)
    queue = deque(int(c) for c in np.flatnonzero(start ^ goal))
    for c in queue:
        dist[c] = 0
    tiles = start | goal
    nbr = neighbour_table(w, h).tolist()
    while queue:
        c = queue.popleft()
        for n in nbr[c]:
            if n >= 0 and tiles[n] and dist[n] < 0:
                dist[n] = dist[c] + 1
                queue.append(n)
    cells = [int(c) for c in np.flatnonzero(both & ~cut & (dist > 0))]
    cells.sort(key=lambda c: (dist[c], c // w, c % w))
    return [(c % w, c // w) for c in cells]


def climb(instance: Instance, best, budget: Budget, offer, max_states: int) -> list[dict]:
    """Climb the ladder within ``budget``: each rung searched below ``best()`` (the bracket's best
    schedule, an :class:`~..incumbent.Incumbent`), a shorter schedule handed to ``offer``
    (a :class:`Schedule`). Returns what each rung proved: its cells added, its status, and its
    optimum (decided) or its bound (stopped)."""
    from ..bfs import Options, plan as bfs

    cells = candidates(instance)
    rows: list[dict] = []
    for k in range(RUNG, len(cells) + RUNG, RUNG):
        if budget.expired():
            break
        incumbent = best()
        added = [list(c) for c in cells[:k]]
        began = budget.now()
        schedule = Schedule.from_ids(instance, incumbent.ids, meta={"method": incumbent.method})
        got = bfs(instance, Options(cells="keep", add_cells=added, incumbent=schedule, max_states=max_states),
                  Run(budget.child()))
        decided = "stopped" not in got.stats  # exhausted below the incumbent, or a shorter schedule found
        row = {"add_cells": added, "status": got.status, "states": got.stats.get("states"),
               "s": round(budget.now() - began, 3)}
        makespan = None if got.schedule is None else metrics(instance, bind(instance, got.schedule)).makespan
        if got.status == "optimal":  # the class's optimum: a shorter schedule, or the incumbent (in the class)
            row["optimum"] = makespan
        else:  # nothing in the class below the incumbent (outside it), or the bound where it stopped
            row["lower_bound"] = incumbent.makespan if decided else got.stats["class"]["lower_bound"]
        rows.append(row)
        if got.status == "optimal" and makespan < incumbent.makespan:
            offer(got.schedule)
        if not decided:
            break
    return rows


__all__ = ["RUNG", "candidates", "climb"]
