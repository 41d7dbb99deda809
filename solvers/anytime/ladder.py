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
row moved along by one), except those whose lifting disconnects the start structure, and except
the cells that change. First come the cells *in line with a passage*: a passage is a straight
run of two or more cut cells of the start (cells whose lifting disconnects it, as on a bridge);
the cells that go on from its end in the same direction, over tiles, are in line with it, the
nearest first, ties by position. Through them the robots on the two sides hand tiles over: on
lt-1 the first rung ((3, 3), (12, 3)) holds a 56-step schedule and the second (and (2, 3),
(13, 3)) a 54-step one, where the structure kept gives 57. The other candidates follow,
nearest first to a cell that changes (steps over tiles), as a shorter schedule changes the
structure around the cells it must change; ties by position. The ladder is a search for shorter
schedules and a record of what each class proves, not a bound on every schedule.

Where the abstraction of the class without scaffold fits (:mod:`bille.solvers.joint.abstraction`),
that class, the ladder's top, is searched first, within two thirds of the ladder's time: its
search deepens from the abstraction's bound to the best schedule, which decides it on lt-1 (54)
and lt-3 (53) in seconds. Decided, it holds
every rung's class, so no rung can give a shorter schedule and the ladder ends there.
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
# the top's share of the ladder's time at most (where its abstraction is not built in time, the
# search of the top goes on unguided and decides little: the rungs get the rest)
TOP_SHARE = 2 / 3


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
    line = _in_line(cut, tiles, w, h)
    cells.sort(key=lambda c: (line.get(c, w + h), dist[c], c // w, c % w))
    return [(c % w, c // w) for c in cells]


def _in_line(cut: np.ndarray, tiles: np.ndarray, w: int, h: int) -> dict[int, int]:
    """The cells in line with a passage (module docstring) and their steps from its end."""
    line: dict[int, int] = {}
    for a in np.flatnonzero(cut):
        x, y = int(a) % w, int(a) // w
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            bx, by = x - dx, y - dy  # the passage goes on behind a
            if not (0 <= bx < w and 0 <= by < h and cut[by * w + bx]):
                continue
            k, cx, cy = 1, x + dx, y + dy
            while 0 <= cx < w and 0 <= cy < h and tiles[cy * w + cx]:
                c = cy * w + cx
                if not cut[c]:
                    line[c] = min(line.get(c, k), k)
                k, cx, cy = k + 1, cx + dx, cy + dy
    return line


def climb(instance: Instance, best, budget: Budget, offer, max_states: int, closed=lambda: False,
          top: bool = True) -> list[dict]:
    """Climb the ladder within ``budget``: each rung searched below ``best()`` (the bracket's best
    schedule, an :class:`~..incumbent.Incumbent`), a shorter schedule handed to ``offer``
    (a :class:`Schedule`), until ``closed()`` (the best schedule proved optimal); ``top``: its
    top first where it fits (module docstring). Returns what each rung proved: its cells added
    (``cells``: ``no-scaffold`` for the top), its status, and its optimum (decided) or its bound
    (stopped)."""
    from ..bfs import Options, plan as bfs

    cells = candidates(instance)
    rows: list[dict] = []
    row = _top(instance, best, budget, offer, max_states) if top and not closed() else None
    if row is not None:
        rows.append(row)
        if row["decided"]:  # every rung's class is within it: none holds a shorter schedule
            return rows
    for k in range(RUNG, len(cells) + RUNG, RUNG):
        if budget.expired() or closed():
            break
        incumbent = best()
        added = [list(c) for c in cells[:k]]
        began = budget.now()
        schedule = Schedule.from_ids(instance, incumbent.ids, meta={"method": incumbent.method})
        got = bfs(instance, Options(cells="keep", add_cells=added, incumbent=schedule, max_states=max_states),
                  Run(budget.child()))
        row = _row(instance, got, incumbent, budget.now() - began, offer, add_cells=added)
        rows.append(row)
        if not row["decided"]:
            break
    return rows


def _row(instance: Instance, got, incumbent, seconds: float, offer, **names) -> dict:
    """What a rung's search proved (``names``: its class), a shorter schedule handed to ``offer``."""
    decided = "stopped" not in got.stats  # exhausted below the incumbent, or a shorter schedule found
    row = {**names, "status": got.status, "decided": decided, "states": got.stats.get("states"), "s": round(seconds, 3)}
    makespan = None if got.schedule is None else metrics(instance, bind(instance, got.schedule)).makespan
    if got.status == "optimal":  # the class's optimum: a shorter schedule, or the incumbent (in the class)
        row["optimum"] = makespan
    else:  # nothing in the class below the incumbent (outside it), or the bound where it stopped
        row["lower_bound"] = incumbent.makespan if decided else got.stats["class"]["lower_bound"]
    if got.status == "optimal" and makespan < incumbent.makespan:
        offer(got.schedule)
    return row


def _top(instance: Instance, best, budget: Budget, offer, max_states: int) -> dict | None:
    """The top of the ladder first, where the abstraction of its class fits
    (:mod:`bille.solvers.joint.abstraction`): the schedules without scaffold, searched below the
    best schedule. What it proved, as a rung's row (``cells``: ``no-scaffold``), or None."""
    from bille.instances.limits import address_room, memory_budget

    from ..bfs import Options, plan as bfs
    from ..joint.abstraction import MAX_SIZE, size_of
    from ..joint.cells import cells_of

    room = min(memory_budget(), address_room())
    if budget.expired() or size_of(instance, cells_of(instance, "no-scaffold")) > min(MAX_SIZE, room // 2):
        return None
    incumbent = best()
    began = budget.now()
    schedule = Schedule.from_ids(instance, incumbent.ids, meta={"method": incumbent.method})
    got = bfs(instance, Options(cells="no-scaffold", incumbent=schedule, max_states=max_states),
              Run(budget.share(TOP_SHARE)))
    if "abstraction" not in got.stats:  # not built in the time or the memory left: nothing searched to speak of
        return None
    return _row(instance, got, incumbent, budget.now() - began, offer, cells="no-scaffold")


def top_class(rows: list[dict]) -> dict:
    """What the top's row proved of the class without scaffold: ``{"class_optima": optimum}``,
    or ``{"class_lower_bounds": bound}``, or nothing (no top searched)."""
    for row in rows:
        if row.get("cells") == "no-scaffold":
            if "optimum" in row:
                return {"class_optima": row["optimum"]}
            return {} if row.get("lower_bound") is None else {"class_lower_bounds": row["lower_bound"]}
    return {}


__all__ = ["RUNG", "candidates", "climb", "top_class"]
