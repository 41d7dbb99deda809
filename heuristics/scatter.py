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
"""
from __future__ import annotations

import heapq
import random
import time


class CollisionTable:
    """Who stands where at which step, for paths without waits: ``at[t * P + v]`` lists the
    robots at ``v`` at step ``t``; ``ends[v]`` the steps at which paths end on ``v`` (their
    robot rests there from then on)."""

    def __init__(self, size: int) -> None:
        self.size = size
        self.at: dict[int, list[int]] = {}
        self.ends: dict[int, list[int]] = {}
        self.count = 0
        self.horizon = 0  # no path is longer

    def cost(self, v: int, u: int, t: int) -> int:
        """Collisions of a step from ``v`` at ``t`` to ``u`` at ``t + 1``: robots at ``u`` then,
        robots coming the other way, robots resting at ``u`` by then."""
        P, at = self.size, self.at
        n = 0
        there = at.get((t + 1) * P + u)
        if there:
            n += len(there)
        back = at.get((t + 1) * P + v)
        if back:
            came = at.get(t * P + u)
            if came:
                n += sum(1 for j in back if j in came)
        ends = self.ends.get(u)
        if ends:
            n += sum(1 for e in ends if e < t + 1)
        return n

    def enroll(self, i: int, path: list[int]) -> None:
        P, at = self.size, self.at
        for t, v in enumerate(path):
            if t:
                self.count += self.cost(path[t - 1], v, t - 1)
            at.setdefault(t * P + v, []).append(i)
        end = len(path) - 1
        self.horizon = max(self.horizon, end)
        goal = path[-1]
        self.ends.setdefault(goal, []).append(end)
        self.count += self._after(goal, end)

    def clear(self, i: int, path: list[int]) -> None:
        P, at = self.size, self.at
        for t, v in enumerate(path):
            at[t * P + v].remove(i)
            if t:
                self.count -= self.cost(path[t - 1], v, t - 1)
        end = len(path) - 1
        goal = path[-1]
        self.ends[goal].remove(end)
        self.count -= self._after(goal, end)

    def meets(self, path: list[int]) -> int:
        """Collisions of ``path`` with the paths in the table."""
        cost = self.cost
        n = sum(cost(path[t - 1], path[t], t - 1) for t in range(1, len(path)))
        return n + self._after(path[-1], len(path) - 1)

    def _after(self, v: int, end: int) -> int:
        """Robots passing ``v`` after a path ended there."""
        P, at = self.size, self.at
        return sum(len(at.get(t * P + v, ())) for t in range(end + 1, self.horizon + 1))


def scatter(nbrs: list[list[int]], dists: list[list[int]], starts: list[int], goals: list[int], *,
            margin: int = 10, deadline: float | None = None, seed: int = 0, rounds_max: int = 100) -> list[dict[int, int]]:
    """Per robot, the next cell of its SUO path from each cell of that path (module docstring);
    robots on ``nbrs`` (the cells next to each cell) from ``starts`` to ``goals``, ``dists[i]``
    robot ``i``'s distances to its goal. Stops at ``deadline`` with the paths of the last whole
    round (or none)."""
    rng = random.Random(seed)
    m = len(starts)
    table = CollisionTable(len(nbrs))
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
            if deadline is not None and time.perf_counter() > deadline:
                return _successors(kept)
            if paths[i] is not None:
                table.clear(i, paths[i])
                if table.meets(paths[i]) == 0:  # nothing to gain: keep it
                    table.enroll(i, paths[i])
                    continue
            found = _path(nbrs, dists[i], starts[i], goals[i], dists[i][starts[i]] + margin, table)
            if found is not None:
                paths[i] = found
            if paths[i] is not None:
                table.enroll(i, paths[i])
        kept = list(paths)
        if table.count == 0:
            break
    return _successors(kept)


def _successors(paths) -> list[dict[int, int]]:
    return [{} if p is None else dict(zip(p, p[1:])) for p in paths]


def _path(nbrs, dist, start: int, goal: int, bound: int, table: CollisionTable) -> list[int] | None:
    """A* from ``start`` to ``goal`` by (collisions, length, deeper first), paths of at most
    ``bound`` steps. A heap entry is one int: ``((collisions * F + f) * F + F - 1 - g) * P * P
    + u * P + parent`` (ints compare faster than tuples)."""
    P = table.size
    PP, F = P * P, bound + 2
    at, ends = table.at, table.ends
    parent: dict[int, int] = {}
    heap = [((dist[start] * F + F - 1) * P + start) * P + start]
    pop, push = heapq.heappop, heapq.heappush
    while heap:
        x = pop(heap)
        key, rest = divmod(x, PP)
        v, p = divmod(rest, P)
        if v in parent:
            continue
        parent[v] = p
        if v == goal:
            path = [v]
            while v != start:
                v = parent[v]
                path.append(v)
            return path[::-1]
        c, g = divmod(key, F * F)[0], F - 1 - key % F
        t = g + 1  # arriving at a neighbour
        back = at.get(t * P + v)
        for u in nbrs[v]:
            d = dist[u]
            if g + 1 + d > bound or u in parent or u == start:
                continue
            n = c
            there = at.get(t * P + u)
            if there:
                n += len(there)
            if back:
                came = at.get(g * P + u)
                if came:
                    n += sum(1 for j in back if j in came)
            if u in ends:
                n += sum(1 for e in ends[u] if e < t)
            push(heap, (((n * F + t + d) * F + F - 1 - t) * P + u) * P + v)
    return None
