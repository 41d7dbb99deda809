"""Relaxed walking distances: a robot walking on every cell that is not an obstacle.

Tiles appear and vanish during a reconfiguration, so the only distances that bound *every*
schedule are those of the pose graph with tiles ignored: every walking action whose collision
cells stay inside the grid and off obstacles (docs/rules.md, rule 2 without a load). A real step of a
robot is a step of this graph (rules 1 and 4 only remove steps), and a pick or place leaves the
pose unchanged, so the number of steps between two poses of any schedule is at least their
distance here. Bounds (``bille.solvers.bounds``) and the encodings' pruning read these tables.

Within a class of schedules that never has a tile on some cells (``ground``: the cells that may
ever hold one, :mod:`bille.solvers.bounds.classes`), a robot's feet stand only on ground cells (rule 4),
so its steps are those of the relaxed graph whose poses have both feet on the ground: the
distances of that graph bound every schedule of the class.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from .lru import LRU
from .moveset import Kind
from .posegraph import PoseGraph

INF = np.iinfo(np.int32).max // 2  # the distance of what cannot be reached


@dataclass(frozen=True, eq=False)
class Relaxed:
    """The pose graph of one robot type with tiles ignored (see the module docstring); with
    ``ground`` (a mask of cells), only its poses with both feet on the ground."""

    graph: PoseGraph
    ground: np.ndarray | None = None

    @cached_property
    def poses(self) -> np.ndarray:
        """Mask of the poses of this graph: valid, and with both feet on the ground."""
        g = self.graph
        if self.ground is None:
            return g.valid
        return g.valid & self.ground[g.feet[:, 0]] & self.ground[g.feet[:, 1]]

    @cached_property
    def edges(self) -> csr_matrix:
        """Walking steps ``p -> q`` (``p != q``) between poses of this graph, unit weight."""
        g = self.graph
        walking = np.isin(g.kind, (int(Kind.WAIT), int(Kind.MOTION)))
        p, a = np.nonzero((g.succ >= 0) & walking[None, :] & self.poses[:, None])
        q = g.succ[p, a]
        keep = (p != q) & self.poses[q]
        n = g.num_poses
        return csr_matrix((np.ones(int(keep.sum()), np.float64), (p[keep], q[keep])), shape=(n, n))

    @cached_property
    def _reverse(self) -> csr_matrix:
        return self.edges.T.tocsr()

    def _run(self, sources, reverse: bool) -> np.ndarray:
        sources = np.asarray(sources, dtype=np.int64)
        if len(sources) == 0:
            return np.full(self.graph.num_poses, INF, dtype=np.int64)
        graph = self._reverse if reverse else self.edges
        d = dijkstra(graph, indices=sources, unweighted=True, min_only=True)
        return np.where(np.isfinite(d), d, INF).astype(np.int64)

    def from_pose(self, pose: int) -> np.ndarray:
        """Steps from ``pose`` to every pose."""
        return self._run([pose], reverse=False)

    def from_poses(self, poses) -> np.ndarray:
        """Steps from the nearest of ``poses`` to every pose."""
        return self._run(poses, reverse=False)

    def to_poses(self, poses) -> np.ndarray:
        """Steps from every pose to the nearest of ``poses``."""
        return self._run(poses, reverse=True)

    def to_front(self, cell: int) -> np.ndarray:
        """Steps from every pose to a pose with the front foot on ``cell``."""
        g = self.graph
        return self.to_poses(np.flatnonzero(self.poses & (g.feet[:, 0] == cell)))

    def from_offsets(self, offsets: np.ndarray) -> np.ndarray:
        """Earliest arrival at every pose when pose ``p`` is available from time ``offsets[p]``
        (``INF``: not a start): ``min_q offsets[q] + dist(q, p)``."""
        start = np.flatnonzero(offsets < INF)
        n = self.graph.num_poses
        if not len(start):
            return np.full(n, INF, dtype=np.int64)
        # a super source joined to each start by an edge of weight offset + 1 (>= 1: csgraph
        # reads a stored zero as a missing edge), the 1 taken off again below
        e = self.edges.tocoo()
        rows = np.concatenate([e.row, np.full(len(start), n)])
        cols = np.concatenate([e.col, start])
        w = np.concatenate([e.data, offsets[start].astype(np.float64) + 1])
        graph = csr_matrix((w, (rows, cols)), shape=(n + 1, n + 1))
        d = dijkstra(graph, indices=n)[:n] - 1
        return np.where(np.isfinite(d), d, INF).astype(np.int64)


_CACHE: LRU[Relaxed] = LRU(16)


def relaxed_for(graph: PoseGraph, ground: np.ndarray | None = None) -> Relaxed:
    """The :class:`Relaxed` graph of ``graph`` (on ``ground``), one per pose graph and ground:
    robots of one moveset, the bounds and every horizon's model share its edges (a graph's id
    may be reused once it is gone: the cached one must be of this graph)."""
    key = id(graph) if ground is None else (id(graph), np.packbits(ground).tobytes())
    return _CACHE.get(key, lambda: Relaxed(graph, ground), valid=lambda r: r.graph is graph)


def manipulates_ahead(graph: PoseGraph) -> bool:
    """Whether every pick and place from a pose targets one and the same cell (a Bill-E's cell
    ahead of its front foot): then a carried tile can land elsewhere than where it was picked
    only after the robot moved."""
    acts = np.flatnonzero(np.isin(graph.kind, (int(Kind.PICK), int(Kind.PLACE))))
    if not len(acts):
        return True
    t = np.where(graph.succ[:, acts] >= 0, graph.target[:, acts], -1)
    hi = t.max(axis=1)
    lo = np.where(t >= 0, t, np.iinfo(np.int32).max).min(axis=1)
    return bool(((hi < 0) | (lo == hi)).all())
