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
number of dead ends). The pairs are chosen one at a time rather than by a minimum-cost matching
fixed in advance, because the pairs of such a matching often cannot all run in any order.

When that finds nothing, a second search allows *temporary placements*: a job may take any tile
whose pick keeps the structure connected (one that stays too) and put it on any empty cell
next to the structure (one that must stay empty too), to be moved on or back by a later job.
It is a best-first search over tile sets, each visited once, on the jobs so far plus the cells
still to empty; within a tile set, the jobs from the cells to empty to the cells to fill come
first (in the order above), then the others (tiles that cut a robot off from other work first,
then the shortest carries). It is complete over sequences of one-robot
jobs: when it has visited every tile set those jobs reach, none ends in the goal, and the
loop says ``unsolved`` with that reason; otherwise it stops at its cap of tile sets or when
the run's budget expires.

Deliveries go first, each to the nearest fill cell (from the carrier's front foot) that touches
the structure.
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, InstanceError
from bille.instances.grid import articulation_points, is_connected, neighbour_table
from bille.instances.run import Budget
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


def sequence_of(instance: Instance, *, budget: Budget | None = None) -> list[Job]:
    """The instance's ``tasks`` (checked) with deliveries first, or a derived sequence (searched
    within ``budget``; None: no limit)."""
    if instance.tasks is None:
        return derive(instance, budget=budget)
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


def derive(instance: Instance, *, dead_ends: int = 200, max_sets: int | None = None,
           budget: Budget | None = None) -> list[Job]:
    """A valid sequence for ``instance`` (see the module docstring), or :class:`NoSequence`:
    ``dead_ends`` for the first search, ``max_sets`` tile sets for the one with temporary
    placements (default :func:`max_tile_sets`), both within ``budget`` (None: no limit)."""
    w, h = instance.width, instance.height
    max_sets = max_tile_sets(w * h) if max_sets is None else max_sets
    start, goal = instance.start.tiles, instance.goal_tiles
    jobs = _deliveries(instance, start & goal, goal & ~start)
    tiles = start.copy()
    for job in jobs:
        tiles[job.place] = True
    empty = sorted(np.flatnonzero(tiles & ~goal).tolist())
    fill = sorted(np.flatnonzero(goal & ~tiles).tolist())
    graph = instance.world.graphs[0]
    order = _order(tiles, empty, fill, graph, w, h, dead_ends, budget)
    if order is None:
        graphs = [g for g, _ in instance.world.groups]  # any robot type may serve a job
        search = _Setting(tiles, goal, instance.start.obstacles, graphs, w, h, max_sets, budget)
        order = search.run()
        if order is None:
            raise NoSequence(search.why() + "; a task list given with the instance is used as it is")
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


def _critical(tiles: np.ndarray, empty: list[int], fill: list[int], graph,
              candidates: list[int] | None = None) -> dict[int, int]:
    """For each cell still to empty (or each of ``candidates``): how many cells to empty or fill
    it would leave with no pose facing them if it were picked now (poses on the tiles plus every
    cell to fill, the most a later pick or place can stand on)."""
    future = tiles.copy()
    future[fill] = True
    walk = walk_for(graph, future)
    out = dict.fromkeys(empty if candidates is None else candidates, 0)
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
           dead_ends: int, budget: Budget | None = None) -> list | None:
    """Depth first over (pick, place) pairs, the shortest runnable carry first; gives up after
    ``dead_ends``, or once ``budget`` expires."""
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
            if dead >= dead_ends or (budget is not None and budget.expired()):
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


def max_tile_sets(cells: int) -> int:
    """How many tile sets the search with temporary placements may visit on a grid of ``cells``
    cells: 20,000 (each one a few hundred bytes with its place in the queue), fewer on grids over
    1,000 cells, down to 2,000. 20,000 reach a sequence on random 10x8 maps with ten moved tiles
    (``bille gen random --moved 10``, seeds 1 and 2, three and four robots), where 2,000 reach
    none (the test suite derives seed 2)."""
    return min(20_000, max(2_000, 20_000_000 // max(1, cells)))


class _Setting:
    """The search with temporary placements (module docstring): best first over tile sets."""

    def __init__(self, tiles, goal, obstacles, graphs, w: int, h: int, max_sets: int,
                 budget: Budget | None) -> None:
        self.start, self.goal, self.obstacles, self.w, self.h = tiles.copy(), goal, obstacles, w, h
        self.graphs, self.graph = graphs, graphs[0]  # critical picks: by the first robot's moveset
        self.max_sets, self.budget = max_sets, budget
        self.nbr = neighbour_table(w, h)
        self.seen: set[bytes] = set()
        self.stopped: str | None = None

    def why(self) -> str:
        if self.stopped == "time":
            return (f"no sequence of tile moves found before the time limit ({len(self.seen)} tile sets "
                    "searched, temporary placements included)")
        if self.stopped == "budget":
            return (f"no sequence of tile moves found within {self.max_sets} tile sets (temporary "
                    "placements included)")
        return (f"no sequence of one-robot tile moves reaches the goal: all {len(self.seen)} tile sets they "
                "reach were searched, temporary placements included")

    def run(self) -> list | None:
        """Best first on ``jobs so far + cells still to empty`` (each job empties at most one),
        taking one job of a tile set at a time: a tile set whose jobs are not all tried goes
        back with its key, so the direct jobs are followed depth first and a temporary placement
        is tried only when every shorter sequence is out."""
        start = self.start
        self.seen.add(start.tobytes())
        count = 0
        heap = [(self._h(start), 0, start, self._moves(start), [])]
        while heap:
            if self.budget is not None and self.budget.expired():
                self.stopped = "time"
                return None
            f, order, tiles, moves, path = heapq.heappop(heap)
            move = next(moves, None)
            if move is None:
                continue
            heapq.heappush(heap, (f, order, tiles, moves, path))
            p, q = move
            nxt = tiles.copy()
            nxt[p], nxt[q] = False, True
            key = nxt.tobytes()
            if key in self.seen:
                continue
            if np.array_equal(nxt, self.goal):
                return path + [(p, q)]
            if len(self.seen) >= self.max_sets:
                self.stopped = "budget"
                return None
            self.seen.add(key)
            count += 1
            heapq.heappush(heap, (len(path) + 1 + self._h(nxt), -count, nxt, self._moves(nxt), path + [(p, q)]))
        return None

    def _h(self, tiles) -> int:
        return int((tiles & ~self.goal).sum())

    def _runnable(self, tiles, cut, p: int, q: int) -> bool:
        return any(runnable(tiles, cut, p, q, self.nbr, g, self.w, self.h) for g in self.graphs)

    def _moves(self, tiles):
        """The runnable jobs on ``tiles``, lazily: from cells to empty to cells to fill first
        (critical picks last, then the shortest carry), then every other pick and place (critical
        picks first, then the shortest carry)."""
        goal, w, h = self.goal, self.w, self.h
        cut = articulation_points(tiles, w, h)
        empty = np.flatnonzero(tiles & ~goal).tolist()
        fill = np.flatnonzero(goal & ~tiles).tolist()
        critical = _critical(tiles, empty, fill, self.graph)
        direct = sorted((critical[p], _carry(p, q, w), p, q) for p in empty for q in fill if not cut[p])
        for *_, p, q in direct:
            if self._runnable(tiles, cut, p, q):
                yield p, q
        pickable = np.flatnonzero(tiles & ~cut).tolist()
        blocking = _critical(tiles, empty, fill, self.graph, candidates=pickable)
        edge = [c for c in range(w * h) if not tiles[c] and not self.obstacles[c]
                and any(n >= 0 and tiles[n] for n in self.nbr[c])]
        to_empty, to_fill = set(empty), set(fill)  # their pairs came first
        others = sorted((-blocking[p], _carry(p, q, w), p, q) for p in pickable for q in edge
                        if not (p in to_empty and q in to_fill))
        for *_, p, q in others:
            if self._runnable(tiles, cut, p, q):
                yield p, q


__all__ = ["Job", "NoSequence", "SequenceError", "apply_move", "check", "derive", "sequence_of"]
