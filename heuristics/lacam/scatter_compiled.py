"""The SUO step's collision table and A* (:mod:`.scatter`) compiled with Numba: the same
algorithm, the same tie-breaking and so the same paths as :class:`.scatter.CollisionTable`,
about six times faster once loaded.

Loading it costs about a second in a new process (importing Numba, then its cached machine code;
the very first run on a machine compiles it, a few seconds more, and caches it beside this file
or in Numba's user cache), so :func:`.scatter.scatter` uses it only where the pure-Python table
would take longer (:data:`.scatter.COMPILED_FROM`), or once it is loaded. :func:`warm_up` loads
it ahead of a measurement.

The table is flat arrays: ``at[t * P + v]`` robots at cell ``v`` at step ``t``; ``moved[(t * P +
u) * D + j]`` the robots moving from ``u`` to its ``j``-th neighbour in step ``t -> t + 1`` (``D``
neighbours at most a cell; ``rev[v, j]`` is the place of ``v`` among the neighbours of its
``j``-th neighbour); ``end[v]`` the step the path ending on ``v`` ends. A path is an ``int64``
array of cells.
"""
from __future__ import annotations

import heapq

import numpy as np

from bille.instances.jit import jit

NEVER = 1 << 30  # no path ends on the cell
loaded = False  # whether a search has run in this process (the kernels are loaded)

@jit
def _slot(nbr, u, v):  # pragma: no cover - compiled
    """The place of ``v`` among the neighbours of ``u``."""
    for j in range(nbr.shape[1]):
        if nbr[u, j] == v:
            return j
    return -1


@jit
def _cost(at, moved, end, nbr, P, v, u, t):  # pragma: no cover - compiled
    """Collisions of a step from ``v`` at ``t`` to ``u`` at ``t + 1``."""
    n = at[(t + 1) * P + u] + moved[(t * P + u) * nbr.shape[1] + _slot(nbr, u, v)]
    if end[u] < t + 1:
        n += 1
    return n


@jit
def _after(at, P, v, last, horizon):  # pragma: no cover - compiled
    """Robots passing ``v`` after a path ended there at step ``last``."""
    n = 0
    for t in range(last + 1, horizon + 1):
        n += at[t * P + v]
    return n


@jit
def _enroll(at, moved, end, nbr, path, P, horizon):  # pragma: no cover - compiled
    """Add ``path``; returns (its collisions with the paths already in, the new horizon)."""
    n = 0
    D = nbr.shape[1]
    for t in range(len(path)):
        v = path[t]
        if t:
            u = path[t - 1]
            n += _cost(at, moved, end, nbr, P, u, v, t - 1)
            moved[((t - 1) * P + u) * D + _slot(nbr, u, v)] += 1
        at[t * P + v] += 1
    last = len(path) - 1
    end[path[last]] = last
    horizon = max(horizon, last)
    return n + _after(at, P, path[last], last, horizon), horizon


@jit
def _clear(at, moved, end, nbr, path, P, horizon):  # pragma: no cover - compiled
    """Take ``path`` out; returns its collisions with the paths left."""
    n = 0
    D = nbr.shape[1]
    for t in range(len(path)):
        v = path[t]
        at[t * P + v] -= 1
        if t:
            u = path[t - 1]
            moved[((t - 1) * P + u) * D + _slot(nbr, u, v)] -= 1
            n += _cost(at, moved, end, nbr, P, u, v, t - 1)
    last = len(path) - 1
    end[path[last]] = NEVER
    return n + _after(at, P, path[last], last, horizon)


@jit
def _meets(at, moved, end, nbr, path, P, horizon):  # pragma: no cover - compiled
    n = 0
    for t in range(1, len(path)):
        n += _cost(at, moved, end, nbr, P, path[t - 1], path[t], t - 1)
    last = len(path) - 1
    return n + _after(at, P, path[last], last, horizon)


@jit
def _search(nbr, rev, dist, start, goal, bound, at, moved, end, P, closed, parent, stamp):  # pragma: no cover
    """:func:`.scatter._path` (the same order of expansion): a heap entry is ``(order key,
    u * P + parent)`` with the order key ``(collisions * F + f) * F + F - 1 - g``."""
    F = bound + 2
    D = nbr.shape[1]
    heap = [(dist[start] * F + F - 1, start * P + start)]
    while heap:
        key, rest = heapq.heappop(heap)
        v, p = rest // P, rest % P
        if closed[v] == stamp:
            continue
        closed[v] = stamp
        parent[v] = p
        if v == goal:
            k, w = 1, v
            while w != start:
                w = parent[w]
                k += 1
            path = np.empty(k, np.int64)
            w = v
            for j in range(k - 1, -1, -1):
                path[j] = w
                w = parent[w]
            return path
        c, g = key // (F * F), F - 1 - key % F
        t = g + 1
        for j in range(D):
            u = nbr[v, j]
            if u < 0:
                break
            d = dist[u]
            if t + d > bound or closed[u] == stamp or u == start:
                continue
            # robots at u then, robots moving u -> v in step g -> t, a path ended on u by then
            n = c + at[t * P + u] + moved[(g * P + u) * D + rev[v, j]]
            if end[u] < t:
                n += 1
            heapq.heappush(heap, ((n * F + t + d) * F + F - 1 - t, u * P + v))
    return np.empty(0, np.int64)


class CompiledTable:
    """:class:`.scatter.CollisionTable`'s interface (``enroll``, ``clear``, ``meets``, ``path``,
    ``count``) on the compiled kernels; paths are ``int64`` arrays (:meth:`listed` makes them
    lists)."""

    def __init__(self, nbrs: list[list[int]], robots: int = 1 << 15) -> None:
        P = self.size = len(nbrs)
        width = max([len(row) for row in nbrs] + [1])
        self.nbr = np.full((P, width), -1, np.int64)
        self.rev = np.full((P, width), -1, np.int64)
        for v, row in enumerate(nbrs):
            self.nbr[v, :len(row)] = row
        for v, row in enumerate(nbrs):
            for j, u in enumerate(row):
                self.rev[v, j] = nbrs[u].index(v)  # the grid's moves go both ways
        self.at = np.zeros(0, np.int32)
        # at most ``robots`` move along one edge at once: two bytes a count where they fit
        self.moved = np.zeros(0, np.int16 if robots < 1 << 15 else np.int32)
        self.end = np.full(P, NEVER, np.int64)
        self.count = 0
        self.horizon = 0
        self.closed = np.zeros(P, np.int64)
        self.parent = np.zeros(P, np.int64)
        self.stamp = 0
        self.dists: dict[int, np.ndarray] = {}  # per robot: its distances as int64

    def reserve(self, steps: int) -> None:
        """Room in ``at`` and ``moved`` for steps ``0 .. steps`` (doubling)."""
        need = (steps + 1) * self.size
        if len(self.at) < need:
            grown = np.zeros(max(need, 2 * len(self.at)), np.int32)
            grown[:len(self.at)] = self.at
            self.at = grown
            moved = np.zeros(len(grown) * self.nbr.shape[1], self.moved.dtype)
            moved[:len(self.moved)] = self.moved
            self.moved = moved

    def enroll(self, i: int, path: np.ndarray) -> None:
        self.reserve(len(path))
        if self.end[path[-1]] != NEVER:
            raise ValueError(f"two paths end on cell {path[-1]}")
        n, self.horizon = _enroll(self.at, self.moved, self.end, self.nbr, path, self.size, self.horizon)
        self.count += n

    def clear(self, i: int, path: np.ndarray) -> None:
        self.count -= _clear(self.at, self.moved, self.end, self.nbr, path, self.size, self.horizon)

    def meets(self, path: np.ndarray) -> int:
        self.reserve(len(path))
        return _meets(self.at, self.moved, self.end, self.nbr, path, self.size, self.horizon)

    def path(self, i: int, dist, start: int, goal: int, bound: int) -> np.ndarray | None:
        """Robot ``i``'s path against the table (:func:`.scatter._path`); ``dist``: its
        distances to its goal, an array or a list."""
        self.reserve(bound + 1)
        self.stamp += 1
        if i not in self.dists:
            self.dists[i] = np.asarray(dist, dtype=np.int64)
        found = _search(self.nbr, self.rev, self.dists[i], start, goal, bound, self.at, self.moved,
                        self.end, self.size, self.closed, self.parent, self.stamp)
        global loaded
        loaded = True
        return found if len(found) else None

    @staticmethod
    def listed(path: np.ndarray) -> list[int]:
        return path.tolist()


def warm_up() -> None:
    """Load (or compile) the kernels now: one search on a two-cell corridor."""
    table = CompiledTable([[1], [0]], 1)
    path = table.path(0, [1, 0], 0, 1, 1)
    table.meets(path)
    table.enroll(0, path)
    table.clear(0, path)
