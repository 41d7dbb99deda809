"""Space utilization optimization (SUO; Han and Yu, ICRA 2022), as LaCAM* uses it in lacam3
(Okumura, "Engineering LaCAM*", AAMAS 2024): before the search, every robot gets a path of at
most ``margin`` steps more than its shortest one that meets the other robots' paths as little as
possible; the configuration generator then prefers a robot's next cell on that path, so that
robots spread over the map instead of all taking the same shortest corridors.

Classic collisions (point robots, a pose is a cell). Paths are planned one robot at a time, in a
random order, against a *collision table* of the others' paths (who is where at which step, and
where each path ends); a robot's search is A* over cells, ordered by the collisions met first,
then by length, without waiting (a cell is closed once reached, so the search stays as small as
a single-robot one). Rounds repeat while the total of collisions falls.

Two tables give the same paths: :class:`CollisionTable` in plain Python, and on large problems
(:data:`COMPILED_FROM`) :class:`~.scatter_compiled.CompiledTable`, the same algorithm compiled
with Numba.
"""
from __future__ import annotations

import heapq
import random
import sys

from bille.instances.run import Budget

NEVER = 1 << 30  # no path ends on the cell

# robots x cells from which the compiled table is used: below it the Python table finishes in
# well under the second that loading Numba's compiled code takes in a new process (measured on
# the shipped MovingAI maps: 200 robots on random-32-32-10, 184,000, 0.17 s in Python; 400
# robots, 369,000, 1.6 s in Python and 0.3 s compiled; the warehouse with 200 robots, 1.1
# million, 1.0 s and 0.16 s)
COMPILED_FROM = 300_000


class CollisionTable:
    """Who stands where at which step, for paths without waits: ``at[t * P + v]`` counts the
    robots at ``v`` at step ``t`` (a flat list, grown as longer paths come); ``moved`` counts the
    robots moving ``u -> v`` in step ``t -> t + 1`` (key ``(t * P + u) * P + v``); ``end[v]`` is
    the step at which the path ending on ``v`` ends (its robot rests there from then on; goals
    are distinct)."""

    def __init__(self, nbrs: list[list[int]]) -> None:
        self.nbrs = nbrs  # the cells next to each cell
        size = self.size = len(nbrs)
        self.at: list[int] = []
        self.moved: dict[int, int] = {}
        self.end = [NEVER] * size
        self.count = 0
        self.horizon = 0  # no path is longer
        self.closed = [0] * size  # the searches' closed cells: ``closed[v] == stamp``
        self.parent = [0] * size
        self.stamp = 0

    def reserve(self, steps: int) -> None:
        """Room in ``at`` for steps ``0 .. steps``."""
        need = (steps + 1) * self.size
        if len(self.at) < need:
            self.at.extend([0] * (need - len(self.at)))

    def cost(self, v: int, u: int, t: int) -> int:
        """Collisions of a step from ``v`` at ``t`` to ``u`` at ``t + 1``: robots at ``u`` then,
        robots coming the other way, robots resting at ``u`` by then."""
        P = self.size
        return self.at[(t + 1) * P + u] + self.moved.get((t * P + u) * P + v, 0) + (self.end[u] < t + 1)

    def enroll(self, i: int, path: list[int]) -> None:
        P, moved = self.size, self.moved
        self.reserve(len(path))
        at = self.at
        for t, v in enumerate(path):
            if t:
                u = path[t - 1]
                self.count += self.cost(u, v, t - 1)
                key = ((t - 1) * P + u) * P + v
                moved[key] = moved.get(key, 0) + 1
            at[t * P + v] += 1
        end, goal = len(path) - 1, path[-1]
        if self.end[goal] != NEVER:
            raise ValueError(f"two paths end on cell {goal}")
        self.horizon = max(self.horizon, end)
        self.end[goal] = end
        self.count += self._after(goal, end)

    def clear(self, i: int, path: list[int]) -> None:
        P, at, moved = self.size, self.at, self.moved
        for t, v in enumerate(path):
            at[t * P + v] -= 1
            if t:
                u = path[t - 1]
                key = ((t - 1) * P + u) * P + v
                moved[key] -= 1
                if not moved[key]:
                    del moved[key]
                self.count -= self.cost(u, v, t - 1)
        end, goal = len(path) - 1, path[-1]
        self.end[goal] = NEVER
        self.count -= self._after(goal, end)

    def meets(self, path: list[int]) -> int:
        """Collisions of ``path`` with the paths in the table."""
        self.reserve(len(path))
        cost = self.cost
        n = sum(cost(path[t - 1], path[t], t - 1) for t in range(1, len(path)))
        return n + self._after(path[-1], len(path) - 1)

    def path(self, i: int, dist: list[int], start: int, goal: int, bound: int) -> list[int] | None:
        """Robot ``i``'s path against the table (:func:`_path`); ``dist``: its distances to its
        goal."""
        return _path(self.nbrs, dist, start, goal, bound, self)

    @staticmethod
    def listed(path: list[int]) -> list[int]:
        return path

    def _after(self, v: int, end: int) -> int:
        """Robots passing ``v`` after a path ended there."""
        P, at = self.size, self.at
        return sum(at[t * P + v] for t in range(end + 1, self.horizon + 1))


def scatter(nbrs: list[list[int]], dists: list, starts: list[int], goals: list[int], *,
            margin: int = 10, budget: Budget | None = None, seed: int = 0, rounds_max: int = 100,
            compiled: bool | None = None, arrays: list | None = None) -> list[dict[int, int]]:
    """Per robot, the next cell of its SUO path from each cell of that path (module docstring);
    robots on ``nbrs`` (the cells next to each cell) from ``starts`` to ``goals``, ``dists[i]``
    robot ``i``'s distances to its goal (lists; ``arrays``: the same as numpy arrays, if at hand,
    for the compiled table). Stops when ``budget`` expires with the paths of the last whole round
    (or none). ``compiled``: which table (None: the compiled one from :data:`COMPILED_FROM`, or
    once it is loaded in this process)."""
    rng = random.Random(seed)
    m = len(starts)
    if compiled is None:
        compiled = m * len(nbrs) >= COMPILED_FROM or _loaded()
    if compiled:
        from .scatter_compiled import CompiledTable
        table = CompiledTable(nbrs, m)
        dists = dists if arrays is None else arrays
    else:
        table = CollisionTable(nbrs)
    paths: list[list[int] | None] = [None] * m
    kept: list[list[int] | None] = [None] * m
    last = None
    rounds = 0
    while rounds < min(2, rounds_max) or (table.count < last and rounds < rounds_max):
        rounds += 1
        last = table.count
        order = list(range(m))
        rng.shuffle(order)
        for i in order:
            if budget is not None and budget.expired():
                return _successors(kept, table)
            if paths[i] is not None:
                table.clear(i, paths[i])
                if table.meets(paths[i]) == 0:  # nothing to gain: keep it
                    table.enroll(i, paths[i])
                    continue
            found = table.path(i, dists[i], starts[i], goals[i], int(dists[i][starts[i]]) + margin)
            if found is not None:
                paths[i] = found
            if paths[i] is not None:
                table.enroll(i, paths[i])
        kept = list(paths)
        if table.count == 0:
            break
    return _successors(kept, table)


def _loaded() -> bool:
    """Whether this process has the compiled table loaded already (it costs nothing more then)."""
    module = sys.modules.get(f"{__package__}.scatter_compiled")
    return bool(module is not None and module.loaded)


def _successors(paths, table) -> list[dict[int, int]]:
    lists = [None if p is None else table.listed(p) for p in paths]
    return [{} if p is None else dict(zip(p, p[1:])) for p in lists]


def _path(nbrs, dist, start: int, goal: int, bound: int, table: CollisionTable) -> list[int] | None:
    """A* from ``start`` to ``goal`` by (collisions, length, deeper first), paths of at most
    ``bound`` steps. A heap entry is one int: ``((collisions * F + f) * F + F - 1 - g) * P * P
    + u * P + parent`` (ints compare faster than tuples)."""
    P = table.size
    PP, F = P * P, bound + 2
    table.reserve(bound + 1)
    at, moved, end = table.at, table.moved, table.end
    closed, parent = table.closed, table.parent
    table.stamp += 1
    stamp = table.stamp
    heap = [((dist[start] * F + F - 1) * P + start) * P + start]
    pop, push = heapq.heappop, heapq.heappush
    while heap:
        x = pop(heap)
        key, rest = divmod(x, PP)
        v, p = divmod(rest, P)
        if closed[v] == stamp:
            continue
        closed[v] = stamp
        parent[v] = p
        if v == goal:
            path = [v]
            while v != start:
                v = parent[v]
                path.append(v)
            return path[::-1]
        c, g = key // (F * F), F - 1 - key % F
        t = g + 1  # arriving at a neighbour
        row = t * P
        swaps = (g * P * P + v) if moved else -1  # + u * P: robots moving u -> v in step g -> t
        for u in nbrs[v]:
            d = dist[u]
            if t + d > bound or closed[u] == stamp or u == start:
                continue
            n = c + at[row + u]
            if swaps >= 0:
                n += moved.get(swaps + u * P, 0)
            if end[u] < t:
                n += 1
            push(heap, (((n * F + t + d) * F + F - 1 - t) * P + u) * P + v)
    return None
