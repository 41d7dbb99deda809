"""Walking on a fixed structure: the moves a robot can make and how far it is from a goal.

The planners of the paper (Methods, "Graph representation") search the pose graph of a robot on
the current structure: poses whose feet stand on tiles, joined by the moveset's walking actions
(``wait`` and the motions; no pick or place). :class:`Walk` holds that graph for one compiled
pose graph and one tile set, and the breadth-first distance tables to goal cells that the
planners use as their admissible, consistent heuristic (cached per goal).
"""
from __future__ import annotations

from collections import OrderedDict

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from bille.instances import PoseGraph
from bille.instances.moveset import Kind

UNREACHABLE = np.iinfo(np.int32).max // 2  # distance of poses that cannot reach the goal


class Walk:
    """The walking graph of one robot type on one structure.

    ``succ[p, a]`` is the pose after action ``a`` from pose ``p``, or -1 where the action is not
    a walking action, leaves the workspace, or puts a foot off the tiles.
    """

    def __init__(self, graph: PoseGraph, tiles: np.ndarray) -> None:
        self.graph = graph
        self.tiles = np.asarray(tiles, dtype=bool)
        walking = np.isin(graph.kind, (Kind.WAIT, Kind.MOTION))
        standing = graph.valid & self.tiles[np.maximum(graph.feet, 0)].all(axis=1)
        lands = self.tiles[np.maximum(graph.need, 0)].all(axis=2)
        ok = (graph.succ >= 0) & walking[None, :] & standing[:, None] & lands
        self.succ = np.where(ok, graph.succ, -1).astype(np.int32)
        self.standing = standing
        self.wait = graph.wait
        self._moves: dict[int, list[tuple[int, int, frozenset]]] = {}
        self._dist: OrderedDict[int, np.ndarray] = OrderedDict()
        self._reverse: csr_matrix | None = None

    # ---- moves --------------------------------------------------------------------------------

    def moves(self, pose: int) -> list[tuple[int, int, frozenset]]:
        """``(action, next pose, collision cells)`` of every walking action from ``pose``, wait
        first. Cached per pose: the planners' inner loops read Python tuples, not numpy rows."""
        out = self._moves.get(pose)
        if out is None:
            g, row = self.graph, self.succ[pose]
            order = [self.wait] + [a for a in range(len(row)) if a != self.wait]
            out = [(a, int(row[a]), frozenset(c for c in g.coll[pose, a].tolist() if c >= 0))
                   for a in order if row[a] >= 0]
            self._moves[pose] = out
        return out

    # ---- distances ----------------------------------------------------------------------------

    def goal_poses(self, cell: int) -> np.ndarray:
        """Poses standing on the structure with the front foot on ``cell``."""
        return np.flatnonzero(self.standing & (self.graph.feet[:, 0] == cell))

    def distances(self, cell: int) -> np.ndarray:
        """``int32[P]``: fewest steps from each pose to a pose with its front foot on ``cell``
        (:data:`UNREACHABLE` where none). Cached per goal cell."""
        if cell in self._dist:
            self._dist.move_to_end(cell)
            return self._dist[cell]
        sources = self.goal_poses(cell)
        n = self.succ.shape[0]
        if len(sources) == 0:
            dist = np.full(n, UNREACHABLE, dtype=np.int32)
        else:
            found = dijkstra(self._reverse_graph(), indices=sources, unweighted=True, min_only=True)
            dist = np.where(np.isfinite(found), found, UNREACHABLE).astype(np.int32)
        self._dist[cell] = dist
        while len(self._dist) > 256:
            self._dist.popitem(last=False)
        return dist

    def _reverse_graph(self) -> csr_matrix:
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
        dist = self.distances(cell)
        if dist[pose] == 0 or dist[pose] >= UNREACHABLE:
            return pose
        row = self.succ[pose]
        best = min((int(dist[q]), a) for a, q in enumerate(row.tolist()) if q >= 0)
        return int(row[best[1]])


_CACHE: OrderedDict = OrderedDict()


def walk_for(graph: PoseGraph, tiles: np.ndarray) -> Walk:
    """The :class:`Walk` of ``graph`` on ``tiles``, cached by graph and tile set."""
    key = (id(graph), np.asarray(tiles, dtype=bool).tobytes())
    walk = _CACHE.get(key)
    if walk is None or walk.graph is not graph:
        walk = Walk(graph, tiles)
        _CACHE[key] = walk
        while len(_CACHE) > 32:
            _CACHE.popitem(last=False)
    else:
        _CACHE.move_to_end(key)
    return walk
