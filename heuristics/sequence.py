"""Reconfiguration sequences: which tile goes where, in which order (paper, Methods, "Load transfer").

A *reconfiguration sequence* is an ordered list of jobs ``(pick, place)``: take the tile at
``pick`` and put it on ``place``. A tile that a robot carries at the start has a job with no
pick (a *delivery*). The sequence is *valid* when executing it one job at a time from the start
tiles keeps the structure non-empty and 4-connected after every pick and every place, every
pick finds a tile, every place an empty cell, and the end is the goal's tile set.

An instance's ``tasks`` are used as given (checked: a bad task is bad input, named by its index).
Otherwise :func:`derive` builds one:

the cells that must be emptied (start tiles not in the goal) are matched to the cells that must
be filled (goal tiles not in the start) one job at a time: the next job is the pair that can
*run* now with the shortest carry (Manhattan distance, ties by cell index), where a pick that
would leave another cell to empty or to fill with no pose facing it (on the tiles plus all cells
to fill) comes last. A job can run when
the pick is not an articulation point of the current tiles, the place touches what remains, and
a robot can stand facing the pick and carry the tile to a pose facing the place on the current
structure. A choice that leads to a state where nothing can run is undone (depth first, with a
budget of dead ends); a fixed minimum-cost matching was tried first and dropped, since the
pairs it fixes often cannot all run in any order.

Deliveries go first, each to the nearest fill cell (from the carrier's front foot) that touches
the structure.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, InstanceError
from bille.instances.grid import articulation_points, is_connected, neighbour_table
from bille.instances.walking import runnable, walk_for


@dataclass(frozen=True)
class Job:
    """Pick the tile at cell ``pick`` (None: the tile robot ``carrier`` holds at the start) and
    place it on cell ``place``. Cells are flat indices ``y * width + x``."""

    pick: int | None
    place: int
    carrier: int | None = None

    def describe(self, width: int) -> str:
        def xy(c):
            return f"({c % width}, {c // width})"
        head = f"robot {self.carrier}'s tile" if self.pick is None else f"pick {xy(self.pick)}"
        return f"{head} -> place {xy(self.place)}"


class SequenceError(InstanceError):
    """A given reconfiguration sequence that cannot be executed (names the job): bad input."""


class NoSequence(Exception):
    """The derivation found no sequence within its search: the method gives up (status
    ``unsolved``); not a proof that none exists, and not bad input."""


def sequence_of(instance: Instance) -> list[Job]:
    """The instance's ``tasks`` (checked) with deliveries first, or a derived sequence."""
    if instance.tasks is None:
        return derive(instance)
    w = instance.width
    tasks = [Job(t.pick[1] * w + t.pick[0], t.place[1] * w + t.place[0]) for t in instance.tasks]
    after = instance.start.tiles.copy()  # the tasks' end, ignoring errors (check() names them)
    for job in tasks:
        after[job.pick], after[job.place] = False, True
    jobs = _deliveries(instance, instance.start.tiles & after, instance.goal_tiles & ~after) + tasks
    check(instance, jobs, given=True)
    return jobs


def apply_move(tiles: np.ndarray, pick: bool, cell: int, width: int, height: int) -> str | None:
    """Pick (or place) the tile at ``cell`` in ``tiles``, in place, one move of a sequence run in
    order. Returns the rule it breaks (``precondition``: no tile to pick, or a tile where to
    place; ``connectivity``: the tiles after it are not one piece), or None."""
    if tiles[cell] != pick:
        return "precondition"
    tiles[cell] = not pick
    return None if is_connected(tiles, width, height) else "connectivity"


def check(instance: Instance, jobs: list[Job], *, given: bool = False) -> None:
    """Raise :class:`SequenceError` naming the first job that breaks sequential execution, or
    that the jobs end away from the goal's tiles."""
    w, h = instance.width, instance.height
    tiles = instance.start.tiles.copy()
    obstacles = instance.start.obstacles
    offset = sum(1 for j in jobs if j.pick is None) if given else 0

    def fail(k: int, what: str):
        job = jobs[k]
        label = f"tasks[{k - offset}]" if given and job.pick is not None else f"job {k}"
        raise SequenceError(f"{instance.name}: {label} ({job.describe(w)}): {what}")

    # (pick?, what the cell holds when the move cannot run, what breaks the structure)
    moves = ((True, "pick", "holds no tile", "picking this tile disconnects the structure"),
             (False, "place", "already holds a tile", "the placed tile does not touch the structure"))
    for k, job in enumerate(jobs):
        for pick, name, held, cut in moves:
            cell = job.pick if pick else job.place
            if cell is None:
                continue
            if obstacles[cell]:
                fail(k, f"the {name} cell is an obstacle")
            broken = apply_move(tiles, pick, cell, w, h)
            if broken:
                fail(k, f"the {name} cell {held} when the task runs" if broken == "precondition" else cut)
    goal = instance.goal_tiles
    if not np.array_equal(tiles, goal):
        extra = [instance.world.xy(c) for c in np.flatnonzero(tiles & ~goal)[:3]]
        missing = [instance.world.xy(c) for c in np.flatnonzero(goal & ~tiles)[:3]]
        where = "tasks" if given else "the sequence"
        raise SequenceError(f"{instance.name}: {where} do not reach the goal tiles "
                            f"(extra tiles at {extra}, missing at {missing})")


def derive(instance: Instance, *, budget: int = 200) -> list[Job]:
    """A valid sequence for ``instance`` (see the module docstring), or :class:`NoSequence`."""
    w, h = instance.width, instance.height
    start, goal = instance.start.tiles, instance.goal_tiles
    jobs = _deliveries(instance, start & goal, goal & ~start)
    tiles = start.copy()
    for job in jobs:
        tiles[job.place] = True
    empty = sorted(np.flatnonzero(tiles & ~goal).tolist())
    fill = sorted(np.flatnonzero(goal & ~tiles).tolist())
    graph = instance.world.graphs[0]
    order = _order(tiles, empty, fill, graph, w, h, budget)
    if order is None:
        raise NoSequence(f"no order of the tile moves found that keeps the structure connected "
                         f"and lets a robot reach every pick and place ({budget} dead ends searched); "
                         "a task list given with the instance is used as it is")
    jobs += [Job(p, q) for p, q in order]
    check(instance, jobs)
    return jobs


def _deliveries(instance: Instance, fixed: np.ndarray, free: np.ndarray) -> list[Job]:
    """One delivery per robot carrying at the start: the nearest cell of ``free`` that touches
    the structure (``fixed``: tiles that stay)."""
    w, h = instance.width, instance.height
    nbr = neighbour_table(w, h)
    tiles = fixed.copy()
    free = free.copy()
    jobs = []
    for i, robot in enumerate(instance.robots):
        if not robot.carrying:
            continue
        fx, fy = robot.front
        touching = [c for c in np.flatnonzero(free).tolist() if any(n >= 0 and tiles[n] for n in nbr[c])]
        options = touching or np.flatnonzero(free).tolist()
        if not options:
            raise SequenceError(f"{instance.name}: robots[{i}] carries a tile but no goal cell is left to fill")
        cell = min(options, key=lambda c: (abs(c % w - fx) + abs(c // w - fy), c))
        jobs.append(Job(None, cell, carrier=i))
        free[cell], tiles[cell] = False, True
    return jobs


def _critical(tiles: np.ndarray, empty: list[int], fill: list[int], graph) -> dict[int, int]:
    """For each cell still to empty: how many other cells to empty or fill it would leave with no
    pose facing them if it were picked now (poses on the tiles plus every cell to fill, the
    most a later pick or place can stand on)."""
    future = tiles.copy()
    future[fill] = True
    walk = walk_for(graph, future)
    out = dict.fromkeys(empty, 0)
    for c in empty + fill:
        feet = graph.feet[walk.facing_poses(c)]
        if len(feet) == 0:
            continue
        for p in set(feet[0].tolist()) & out.keys():  # p is under every pose facing c
            if p != c and (feet == p).any(axis=1).all():
                out[p] += 1
    return out


def _carry(p: int, q: int, w: int) -> int:
    return abs(p % w - q % w) + abs(p // w - q // w)


def _order(tiles: np.ndarray, empty: list[int], fill: list[int], graph, w: int, h: int,
           budget: int) -> list | None:
    """Depth first over (pick, place) pairs, the shortest runnable carry first; gives up after
    ``budget`` dead ends."""
    nbr = neighbour_table(w, h)
    dead = 0

    def go(tiles, empty, fill):
        nonlocal dead
        if not empty:
            return []
        cut = articulation_points(tiles, w, h)
        critical = _critical(tiles, empty, fill, graph)
        pairs = sorted((critical[p], _carry(p, q, w), p, q) for p in empty for q in fill if not cut[p])
        for *_, p, q in pairs:
            if dead >= budget:
                return None
            if not runnable(tiles, cut, p, q, nbr, graph, w, h):
                continue
            nxt = tiles.copy()
            nxt[p], nxt[q] = False, True
            rest = go(nxt, [e for e in empty if e != p], [f for f in fill if f != q])
            if rest is not None:
                return [(p, q)] + rest
        dead += 1
        return None

    return go(tiles.copy(), list(empty), list(fill))


__all__ = ["Job", "NoSequence", "SequenceError", "apply_move", "check", "derive", "sequence_of"]
