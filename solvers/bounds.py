"""Lower bounds on the makespan, and what no schedule can do.

Distances here are taken in the *relaxed* pose graph: a robot may walk anywhere that is not an
obstacle, as if every cell held a tile. Tiles can appear and vanish during a reconfiguration, so
only these distances bound every schedule; on a fixed structure they may be shorter than the
walking distances the planners use.

- Each robot needs at least its distance to its goal cell.
- Every tile that must move needs a pick and a place (a biped also a step in between: its
  target is the cell ahead of its front foot), spread over at most ``m`` robots per step; the
  first such move needs some robot to reach a pick pose, pick, reach a place pose and place.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from bille.instances import Instance, PoseGraph
from bille.instances.moveset import Kind

INF = np.iinfo(np.int32).max // 2


@dataclass(frozen=True, eq=False)
class Relaxed:
    """The pose graph of one robot type with tiles ignored: walking on every non-obstacle cell."""

    graph: PoseGraph

    @cached_property
    def edges(self) -> csr_matrix:
        g = self.graph
        walking = np.isin(g.kind, (Kind.WAIT, Kind.MOTION))
        p, a = np.nonzero((g.succ >= 0) & walking[None, :])
        q = g.succ[p, a]
        keep = p != q
        n = g.num_poses
        return csr_matrix((np.ones(int(keep.sum()), np.float32), (p[keep], q[keep])), shape=(n, n))

    def _run(self, sources, reverse: bool) -> np.ndarray:
        sources = np.asarray(sources, dtype=np.int64)
        if len(sources) == 0:
            return np.full(self.graph.num_poses, INF, dtype=np.int64)
        graph = self.edges.T.tocsr() if reverse else self.edges
        d = dijkstra(graph, indices=sources, unweighted=True, min_only=True)
        return np.where(np.isfinite(d), d, INF).astype(np.int64)

    def from_pose(self, pose: int) -> np.ndarray:
        """Steps from ``pose`` to every pose."""
        return self._run([pose], reverse=False)

    def to_poses(self, poses) -> np.ndarray:
        """Steps from every pose to the nearest of ``poses``."""
        return self._run(poses, reverse=True)

    def to_front(self, cell: int) -> np.ndarray:
        """Steps from every pose to a pose with the front foot on ``cell``."""
        g = self.graph
        return self.to_poses(np.flatnonzero(g.valid & (g.feet[:, 0] == cell)))


def facing(graph: PoseGraph, kind: Kind, cells: np.ndarray) -> np.ndarray:
    """Poses from which an action of ``kind`` targets one of the flat ``cells`` mask."""
    acts = np.flatnonzero(graph.kind == kind)
    if len(acts) == 0:
        return np.zeros(0, dtype=np.int64)
    t = graph.target[:, acts]
    hit = (t >= 0) & cells[np.maximum(t, 0)] & (graph.succ[:, acts] >= 0)
    return np.flatnonzero(hit.any(axis=1))


@dataclass
class Bounds:
    """Lower bound on the makespan, its parts, and reasons why no schedule exists (if any)."""

    lower: int
    parts: dict
    impossible: list[str]


def lower_bound(instance: Instance) -> Bounds:
    """The makespan lower bound of the module docstring, and static proofs of infeasibility."""
    world = instance.world
    state = instance.start_state
    start, goal = instance.start.tiles, instance.goal_tiles
    remove, fill = start & ~goal, goal & ~start
    relaxed = [Relaxed(g) for g in world.graphs]
    from_start = [r.from_pose(p) for r, p in zip(relaxed, state.poses)]
    parts, impossible = {}, []

    goal_steps = 0
    for i, cell in enumerate(instance.goal_cells):
        if cell < 0:
            continue
        d = int(relaxed[i].to_front(cell)[state.poses[i]])
        if d >= INF:
            impossible.append(f"robot {i} can never reach its goal cell {world.xy(cell)}")
        goal_steps = max(goal_steps, d)
    parts["robot goals"] = goal_steps

    k_remove, carried = int(remove.sum()), sum(state.carrying)
    if k_remove or carried:
        bipeds_only = all(g.footprint == "biped" for g in world.graphs)
        actions = 2 * k_remove + carried + (k_remove if bipeds_only else 0)
        parts["actions for the tiles that move"] = -(-actions // max(1, instance.num_robots))
        first = INF
        for i, (r, g) in enumerate(zip(relaxed, world.graphs)):
            place_poses = facing(g, Kind.PLACE, fill)
            to_place = r.to_poses(place_poses)
            if state.carrying[i]:
                first = min(first, int(to_place[state.poses[i]]) + 1)
            if k_remove:
                pick_poses = facing(g, Kind.PICK, remove)
                if len(pick_poses):
                    via = from_start[i][pick_poses] + 1 + to_place[pick_poses] + 1
                    first = min(first, int(via.min()))
        if first >= INF:
            impossible.append("no robot can ever pick a tile that must move and place it on a cell that must be filled")
        parts["first tile moved"] = first if first < INF else None
        carry = _transport(world, relaxed, remove, fill)
        if carry is not None:
            work = carry + 2 * k_remove + carried
            parts["carrying the tiles (matching)"] = -(-work // max(1, instance.num_robots))
    lower = max([v for v in parts.values() if v is not None] + [0])
    return Bounds(lower, parts, impossible)


def _transport(world, relaxed, remove, fill) -> int | None:
    """Least total walking while carrying the tiles that must move.

    One *hop* carries a tile from cell ``u`` to cell ``v``: at least the distance from a pose
    that picks at ``u`` to a pose that places at ``v`` (the best robot type). A tile may travel
    in several hops, handed over between robots (a relay), so the cost of getting a tile from
    ``u`` to ``v`` is the shortest path over hops (the metric closure). Tiles have no identity,
    so the tiles from the cells that must empty reach the cells that must fill at no less than a
    minimum-cost matching under that closure. Tiles carried at the start are left out (they may
    be placed at once). None if some required pair can never be joined.
    """
    from scipy.optimize import linear_sum_assignment
    from scipy.sparse.csgraph import csgraph_from_dense, floyd_warshall

    rm, fl = np.flatnonzero(remove), np.flatnonzero(fill)
    if len(rm) == 0:
        return 0
    if len(fl) < len(rm):
        return None
    cells = np.flatnonzero(~world.obstacles)
    index = {int(c): k for k, c in enumerate(cells)}
    hop = np.full((len(cells), len(cells)), np.inf)
    for g, r in zip(world.graphs, relaxed):
        picks_at = _facing_each(g, Kind.PICK, cells)
        places_at = _facing_each(g, Kind.PLACE, cells)
        for v, place_poses in enumerate(places_at):
            if not len(place_poses):
                continue
            to_v = r.to_poses(place_poses)
            for u, pick_poses in enumerate(picks_at):
                if len(pick_poses):
                    d = to_v[pick_poses].min()
                    if d < INF:
                        hop[u, v] = min(hop[u, v], d)
    # from_dense with null_value=inf keeps zero-cost hops (a dense zero would mean "no edge")
    closure = floyd_warshall(csgraph_from_dense(hop, null_value=np.inf), directed=True)
    cost = closure[np.ix_([index[int(c)] for c in rm], [index[int(c)] for c in fl])]
    if not np.isfinite(cost).any(axis=1).all():
        return None
    cost = np.where(np.isfinite(cost), cost, 1e9)
    rows, cols = linear_sum_assignment(cost)
    total = cost[rows, cols].sum()
    return None if total >= 1e9 else int(total)


def _facing_each(graph: PoseGraph, kind: Kind, cells: np.ndarray) -> list[np.ndarray]:
    """For each cell, the poses from which an action of ``kind`` targets it."""
    acts = np.flatnonzero(graph.kind == kind)
    out = [[] for _ in cells]
    if not len(acts):
        return [np.zeros(0, np.int64) for _ in cells]
    where = {int(c): k for k, c in enumerate(cells)}
    p, a = np.nonzero((graph.target[:, acts] >= 0) & (graph.succ[:, acts] >= 0))
    for pose, cell in zip(p.tolist(), graph.target[p, acts[a]].tolist()):
        k = where.get(cell)
        if k is not None:
            out[k].append(pose)
    return [np.array(x, dtype=np.int64) for x in out]
