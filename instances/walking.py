"""Walking on a fixed structure: the moves a robot can make and how far it is from a goal.

The planners of the paper (Methods, "Graph representation") search the pose graph of a robot on
the current structure: poses whose feet stand on tiles, joined by the moveset's walking actions
(``wait`` and the motions; no pick or place). :class:`Walk` holds that graph for one compiled
pose graph, one tile set and one carrying flag (a carried tile adds its cells to every collision
set and must not pass over an obstacle), and the breadth-first distance tables that the planners
use as their admissible, consistent heuristic (cached per goal): to a front-foot goal cell, to
the poses *facing* a cell (the poses from which a pick or place targets it), or to any set of
poses the caller names.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from .jit import loaded
from .lru import LRU
from .moveset import Kind
from .posegraph import PoseGraph

UNREACHABLE = np.iinfo(np.int32).max // 2  # distance of poses that cannot reach the goal
# up to SMALL_GRAPH poses, distances are found by a breadth-first search in Python (about 1 us a
# pose and move), so that a tiny instance's solve loads neither scipy (0.1 s) nor Numba (0.3 s);
# from LARGE_GRAPH poses, or once Numba is loaded, by the same search compiled
# (.walking_compiled: 30 us for 10,000 poses, where scipy's Dijkstra takes 330 us); between, by
# scipy's Dijkstra. All give the same distances (tests/test_motions.py)
SMALL_GRAPH, LARGE_GRAPH = 400, 5_000
NO_BLOCK = np.zeros(0, dtype=np.bool_)  # the compiled search's blocked poses: none


class Walk:
    """The walking graph of one robot type on one structure.

    ``succ[p, a]`` is the pose after action ``a`` from pose ``p``, or -1 where the action is not
    a walking action, leaves the workspace, or puts a foot off the tiles.
    """

    def __init__(self, graph: PoseGraph, tiles: np.ndarray, carrying: bool = False) -> None:
        self.graph = graph
        self.tiles = np.asarray(tiles, dtype=bool)
        self.carrying = carrying
        walking = np.isin(graph.kind, (int(Kind.WAIT), int(Kind.MOTION)))
        standing = graph.valid & self.tiles[np.maximum(graph.feet, 0)].all(axis=1)
        lands = self.tiles[np.maximum(graph.need, 0)].all(axis=2)
        ok = (graph.succ >= 0) & walking[None, :] & standing[:, None] & lands
        if carrying:
            ok &= graph.carry_ok
        self.succ = np.where(ok, graph.succ, -1).astype(np.int32)
        self.standing = standing
        self.wait = graph.wait
        manipulating = np.isin(graph.kind, (int(Kind.PICK), int(Kind.PLACE)))
        self._targets = np.where(manipulating[None, :] & standing[:, None], graph.target, -1)
        self._moves: dict[int, list[tuple[int, int, frozenset]]] = {}
        self._dist: LRU[np.ndarray] = LRU(256)
        self._forward: LRU[np.ndarray] = LRU(64)
        self._reverse = self._forward_graph = None  # scipy's sparse graphs of the moves (mid-sized graphs)
        self._adjacency: dict[bool, list[list[int]]] = {}  # reverse? -> the moves as lists (small graphs)
        self._arrays: dict[bool, tuple[np.ndarray, np.ndarray]] = {}  # reverse? -> the moves as CSR (large ones)
        self._components: np.ndarray | None = None

    # ---- moves --------------------------------------------------------------------------------

    def moves(self, pose: int) -> list[tuple[int, int, frozenset]]:
        """``(action, next pose, collision cells)`` of every walking action from ``pose``, wait
        first. Cached per pose: the planners' inner loops read Python tuples, not numpy rows."""
        out = self._moves.get(pose)
        if out is None:
            row = self.succ[pose].tolist()
            order = [self.wait] + [a for a in range(len(row)) if a != self.wait]
            g = self.graph
            coll = g.coll[pose].tolist()  # one row per pose: numpy is slow per element
            carry = g.carry[pose].tolist() if self.carrying else None
            out = []
            for a in order:
                if row[a] >= 0:
                    cells = coll[a] + carry[a] if carry is not None else coll[a]
                    out.append((a, row[a], frozenset(c for c in cells if c >= 0)))
            self._moves[pose] = out
        return out

    def cells(self, pose: int, action: int) -> frozenset:
        """The collision set of ``action`` from ``pose`` (with the carried tile's cells when
        this walk carries one); also for pick and place, which :meth:`moves` leaves out."""
        g = self.graph
        cells = g.coll[pose, action].tolist() + (g.carry[pose, action].tolist() if self.carrying else [])
        return frozenset(c for c in cells if c >= 0)

    # ---- distances ----------------------------------------------------------------------------

    def goal_poses(self, cell: int) -> np.ndarray:
        """Poses standing on the structure with the front foot on ``cell``."""
        return np.flatnonzero(self.standing & (self.graph.feet[:, 0] == cell))

    def facing_poses(self, cell: int) -> np.ndarray:
        """Poses standing on the structure from which a pick or place targets ``cell``."""
        return np.flatnonzero((self._targets == cell).any(axis=1))

    def facing_any(self, cells) -> np.ndarray:
        """Poses standing on the structure from which a pick or place targets one of ``cells``."""
        return np.flatnonzero(np.isin(self._targets, cells).any(axis=1))

    def manipulation(self, pose: int, cell: int, kind: Kind) -> int | None:
        """The pick (or place) action of ``pose`` that targets ``cell``, or None."""
        for a in np.flatnonzero(self._targets[pose] == cell).tolist():
            if int(self.graph.kind[a]) == kind:
                return a
        return None

    def distances(self, cell: int) -> np.ndarray:
        """``int32[P]``: fewest steps from each pose to a pose with its front foot on ``cell``
        (:data:`UNREACHABLE` where none). Cached per goal cell."""
        return self.distances_to(("front", cell), lambda: self.goal_poses(cell))

    def facing_distances(self, cell: int) -> np.ndarray:
        """``int32[P]``: fewest steps from each pose to a pose facing ``cell``. Cached."""
        return self.distances_to(("facing", cell), lambda: self.facing_poses(cell))

    def distances_to(self, key, sources) -> np.ndarray:
        """``int32[P]``: fewest steps from each pose to one of the poses ``sources()`` (called
        only on a cache miss; ``key`` names the set)."""
        def make() -> np.ndarray:
            found = np.asarray(sources(), dtype=np.int64)
            if len(found) == 0:
                return np.full(self.succ.shape[0], UNREACHABLE, dtype=np.int32)
            if self.succ.shape[0] <= SMALL_GRAPH:
                return self._breadth_first(found.tolist(), self._lists(reverse=True))
            if self._compiled():
                from .walking_compiled import breadth_first

                return breadth_first(*self._csr(reverse=True), found, UNREACHABLE, NO_BLOCK)
            from scipy.sparse.csgraph import dijkstra

            out = dijkstra(self._reverse_graph(), indices=found, unweighted=True, min_only=True)
            return np.where(np.isfinite(out), out, UNREACHABLE).astype(np.int32)

        return self._dist.get(key, make)

    def from_pose(self, pose: int) -> np.ndarray:
        """``int32[P]``: fewest steps from ``pose`` to each pose (forward search). Cached."""
        def make() -> np.ndarray:
            if self.succ.shape[0] <= SMALL_GRAPH:
                return self._breadth_first([pose], self._lists(reverse=False))
            if self._compiled():
                from .walking_compiled import breadth_first

                return breadth_first(*self._csr(reverse=False), np.array([pose], dtype=np.int64), UNREACHABLE,
                                     NO_BLOCK)
            from scipy.sparse.csgraph import dijkstra

            if self._forward_graph is None:
                self._forward_graph = self._reverse_graph().T.tocsr()
            out = dijkstra(self._forward_graph, indices=[pose], unweighted=True)[0]
            return np.where(np.isfinite(out), out, UNREACHABLE).astype(np.int32)

        return self._forward.get(pose, make)

    def components(self) -> np.ndarray:
        """``int[P]``: the strongly connected component of every pose: poses of one component
        reach each other (a quick answer for many reachability questions at once)."""
        if self._components is None:
            from scipy.sparse.csgraph import connected_components

            self._components = connected_components(self._reverse_graph(), directed=True, connection="strong")[1]
        return self._components

    def _lists(self, reverse: bool) -> list[list[int]]:
        """Each pose's successors (``reverse``: predecessors) by a move, waits left out."""
        out = self._adjacency.get(reverse)
        if out is None:
            out = self._adjacency[reverse] = [[] for _ in range(self.succ.shape[0])]
            for p, row in enumerate(self.succ.tolist()):
                for q in row:
                    if q >= 0 and q != p:
                        (out[q] if reverse else out[p]).append(p if reverse else q)
        return out

    @staticmethod
    def _breadth_first(sources: list[int], lists: list[list[int]]) -> np.ndarray:
        """``int32[P]``: fewest moves from the ``sources`` along ``lists`` (:data:`UNREACHABLE`
        where none leads)."""
        dist = [UNREACHABLE] * len(lists)
        queue = deque()
        for s in sources:
            if dist[s] == UNREACHABLE:
                dist[s] = 0
                queue.append(s)
        while queue:
            p = queue.popleft()
            d = dist[p] + 1
            for q in lists[p]:
                if dist[q] == UNREACHABLE:
                    dist[q] = d
                    queue.append(q)
        return np.asarray(dist, dtype=np.int32)

    def from_pose_avoiding(self, pose: int, avoid) -> np.ndarray:
        """``int32[P]``: fewest steps from ``pose`` to each pose without entering one of the
        poses ``avoid`` (the compiled search, whatever the graph's size; not cached)."""
        from .walking_compiled import breadth_first

        blocked = np.zeros(self.succ.shape[0], dtype=np.bool_)
        blocked[list(avoid)] = True
        return breadth_first(*self._csr(reverse=False), np.array([pose], dtype=np.int64), UNREACHABLE, blocked)

    def _compiled(self) -> bool:
        """Whether the compiled search finds the distances (module comment on SMALL_GRAPH)."""
        return self.succ.shape[0] >= LARGE_GRAPH or loaded()

    def _csr(self, reverse: bool) -> tuple[np.ndarray, np.ndarray]:
        """The moves (``reverse``: from the pose moved to to the pose moved from) as CSR arrays,
        waits left out."""
        out = self._arrays.get(reverse)
        if out is None:
            from .walking_compiled import csr

            p, a = np.nonzero(self.succ >= 0)
            q = self.succ[p, a]
            keep = q != p  # waiting adds nothing to distances
            p, q = p[keep], q[keep]
            n = self.succ.shape[0]
            out = self._arrays[reverse] = csr(q, p, n) if reverse else csr(p, q, n)
        return out

    def _reverse_graph(self):
        """The moves as a sparse matrix from the pose moved to to the pose moved from."""
        from scipy.sparse import csr_matrix

        if self._reverse is None:
            p, a = np.nonzero(self.succ >= 0)
            q = self.succ[p, a]
            keep = q != p  # waiting adds nothing to distances
            n = self.succ.shape[0]
            data = np.ones(int(keep.sum()), dtype=np.float32)
            self._reverse = csr_matrix((data, (q[keep], p[keep])), shape=(n, n))
        return self._reverse

    def policy(self, pose: int, cell: int) -> int:
        """A next pose on a shortest walk to ``cell`` (the pose itself when there, or stuck).

        Ties go to the lowest action id, so the policy is deterministic."""
        return self.towards(pose, self.distances(cell))

    def towards(self, pose: int, dist: np.ndarray) -> int:
        """A next pose that lowers the distance table ``dist`` the most (the pose itself at
        distance 0 or when stuck); ties go to the lowest action id."""
        if dist[pose] == 0 or dist[pose] >= UNREACHABLE:
            return pose
        row = self.succ[pose]
        best = min((int(dist[q]), a) for a, q in enumerate(row.tolist()) if q >= 0)
        return int(row[best[1]])


_CACHE: LRU[Walk] = LRU(64)


def walk_for(graph: PoseGraph, tiles: np.ndarray, carrying: bool = False) -> Walk:
    """The :class:`Walk` of ``graph`` on ``tiles``, cached by graph, tile set and carrying flag
    (a graph's id may be reused once it is gone: the cached walk must be of this graph)."""
    key = (id(graph), np.asarray(tiles, dtype=bool).tobytes(), carrying)
    return _CACHE.get(key, lambda: Walk(graph, tiles, carrying), valid=lambda walk: walk.graph is graph)


def runnable(tiles: np.ndarray, cut: np.ndarray, pick: int, place: int, nbr, graph, w: int, h: int) -> bool:
    """Whether the job can run now on ``tiles`` (``cut``: their articulation points, ``nbr``:
    :func:`~bille.instances.grid.neighbour_table`): it keeps the tiles connected, and a robot of
    ``graph`` can stand facing the pick and carry the tile to a pose facing the place."""
    if cut[pick] or tiles[place] or tiles.sum() <= 1:
        return False
    rest = tiles.copy()
    rest[pick] = False
    if not any(n >= 0 and rest[n] for n in nbr[place]):
        return False
    pick_poses = walk_for(graph, tiles).facing_poses(pick)
    carry = walk_for(graph, rest, carrying=True)
    to_place = carry.facing_distances(place)
    # the picking pose stands on the tiles that remain (a pose facing the pick never stands on it)
    return bool(len(pick_poses)) and bool((to_place[pick_poses] < UNREACHABLE).any())
