"""The flat tables the compiled search reads (:mod:`.kernel`): the pose graphs stacked by
moveset, the cells allowed to change as bits, the packing of a joint state into words, each
robot's distance bound, and the groups of interchangeable robots."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.limits import check_budget
from bille.instances.rules import State

from . import kernel
from .cells import Cells

FAR = 1 << 20
# the tile bound's tables (reach, fetch) where the cells allowed to change are at most this many
# and its tables small (cells^2 x poses: the fetch table's intermediate)
TRANSPORT_CELLS, TRANSPORT_SIZE = 64, 5_000_000  # the intermediate: 8 bytes each, 40 MB
MASK_CELLS = 512  # grids up to this many cells test rule 3 by bit masks (at most 8 words an action)  # the distance bound of a pose from which no goal pose can be reached


@dataclass(frozen=True, eq=False)
class Tables:
    """An instance compiled for the joint search within one class of schedules (module docstring).

    ``rbits`` bits per robot value (``pose * 2 + carrying``), ``rpw`` robots per word, ``nR``
    words of robots and ``nT`` of tiles (63 bits each) per state."""

    m: int
    rbits: int
    rpw: int
    nR: int
    nT: int
    width: int
    height: int
    classic: bool
    gid: np.ndarray
    succ: np.ndarray
    coll: np.ndarray
    carry: np.ndarray
    carry_ok: np.ndarray
    need: np.ndarray
    target: np.ndarray
    kind: np.ndarray
    bit_of: np.ndarray
    cell_of: np.ndarray
    fixed: np.ndarray
    fixed_count: int
    anchor: int
    goal_words: np.ndarray
    dist: np.ndarray
    sym_start: np.ndarray
    sym_idx: np.ndarray
    masks: np.ndarray
    W: int
    reach: np.ndarray
    fetch: np.ndarray
    # the abstraction's distances and index (.abstraction.Abstraction; empty: none)
    pdb_local: np.ndarray = dataclasses.field(default_factory=lambda: np.full((1, 1), -1, np.int64))
    pdb_order: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(1, np.int64))
    pdb_blocks: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 3), np.int64))
    pdb_binom: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((1, 1), np.int64))
    pdb_gmask: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((1, 1), np.int64))
    pdb_size: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int64))
    pdb_dist: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.uint8))

    @property
    def L(self) -> int:
        return self.nR + self.nT

    def args(self) -> tuple:
        """The tables in the order :func:`.kernel.expand` takes them."""
        return (self.m, self.rbits, self.rpw, self.nR, self.nT, self.width, self.height, self.classic, self.gid,
                self.succ, self.coll, self.carry, self.carry_ok, self.need, self.target, self.kind, self.bit_of,
                self.cell_of, self.fixed, self.fixed_count, self.anchor, self.goal_words, self.dist,
                self.sym_start, self.sym_idx, self.masks, self.W, self.reach, self.fetch, self.pdb_local, self.pdb_order,
                self.pdb_blocks, self.pdb_binom, self.pdb_gmask, self.pdb_size, self.pdb_dist)

    def pack(self, state: State, canonical: bool = True) -> np.ndarray:
        """A state as a row of words; ``canonical``: the robots of each symmetry group sorted."""
        vals = [2 * int(p) + int(c) for p, c in zip(state.poses, state.carrying)]
        if canonical:
            for s in range(len(self.sym_start) - 1):
                idx = self.sym_idx[self.sym_start[s]:self.sym_start[s + 1]]
                for i, v in zip(idx, sorted(vals[i] for i in idx)):
                    vals[i] = v
        row = np.zeros(self.L, dtype=np.int64)
        for i, v in enumerate(vals):
            row[i // self.rpw] |= np.int64(v) << np.int64((i % self.rpw) * self.rbits)
        for b, cell in enumerate(self.cell_of):
            if state.tiles[cell]:
                row[self.nR + b // kernel.TILE_BITS] |= np.int64(1) << np.int64(b % kernel.TILE_BITS)
        return row

    def is_goal(self, row: np.ndarray) -> bool:
        if not np.array_equal(row[self.nR:], self.goal_words):
            return False
        mask = (1 << self.rbits) - 1
        for i in range(self.m):
            v = (int(row[i // self.rpw]) >> ((i % self.rpw) * self.rbits)) & mask
            if v & 1 or self.dist[i, v >> 1] != 0:
                return False
        return True


def compile_tables(instance: Instance, cells: Cells, distances: bool = True) -> Tables:
    """The tables of ``instance`` within the class ``cells``. ``distances``: each robot's walk to
    its goal cell as its bound (:func:`_distances`, a search per goal: for the pruning below an
    incumbent); without, the bound is 1 off the goal cell and 0 on it (what the goal test reads)."""
    world = instance.world
    m, n = instance.num_robots, instance.width * instance.height
    graphs, gid = distinct_graphs(world.graphs)
    P = max([g.num_poses for g in graphs] + [1])
    succ, coll, carry, carry_ok, need, target, kind = _stacked(graphs, P)

    mask = cells.mask
    cell_of = np.flatnonzero(mask).astype(np.int64)
    bit_of = np.full(n, -1, np.int64)
    bit_of[cell_of] = np.arange(len(cell_of))
    fixed = (instance.start.tiles & ~mask).astype(np.uint8)
    fixed_count = int(fixed.sum())
    anchor = int(np.flatnonzero(fixed)[0]) if fixed_count else 0
    nT = -(-len(cell_of) // kernel.TILE_BITS)
    goal_words = np.zeros(nT, np.int64)
    for b, cell in enumerate(cell_of):
        if instance.goal_tiles[cell]:
            goal_words[b // kernel.TILE_BITS] |= np.int64(1) << np.int64(b % kernel.TILE_BITS)

    rbits = max(1, (2 * P - 1).bit_length())
    rpw = max(1, 62 // rbits)
    nR = max(1, -(-m // rpw))
    possible = instance.start.tiles | mask  # the cells that may hold a tile at some step
    check_budget(8 * m * P, lambda size: f"the joint search: {m} robots' distance tables on {P} poses need {size}",
                 OptionError)
    dist = _goal_distances(instance, graphs, gid, possible, P, distances)
    sym = interchangeable(instance, gid)
    sym_start = np.cumsum([0] + [len(idx) for idx in sym]).astype(np.int64)
    sym_idx = np.array([i for idx in sym for i in idx], dtype=np.int64)
    classic = instance.collisions == "classic"
    W = -(-n // 64) if not classic and n <= MASK_CELLS else 0
    masks = _masks(coll, carry, W) if W else np.zeros((1, 1, 1, 2, 1), np.int64)
    reach = fetch = np.zeros((0, 1, 1), np.int32)
    size = len(cell_of) ** 2 * max(len(graphs), 1) * P  # the transport tables' entries
    if distances and 0 < len(cell_of) <= TRANSPORT_CELLS and size <= TRANSPORT_SIZE:
        reach, fetch = _transport(graphs, cell_of, possible, P)
    return Tables(m, rbits, rpw, nR, nT, instance.width, instance.height, classic, gid, succ, coll, carry, carry_ok,
                  need, target, kind, bit_of, cell_of, fixed, fixed_count, anchor, goal_words, dist, sym_start,
                  sym_idx, masks, W, reach, fetch)


def interchangeable(instance: Instance, gid: np.ndarray) -> list[list[int]]:
    """The groups of two or more interchangeable robots (one pose graph ``gid``, no goal cell),
    each in increasing order: the search's symmetry groups."""
    groups: dict = {}
    for i, goal in enumerate(instance.goal_cells):
        if goal < 0:
            groups.setdefault(int(gid[i]), []).append(i)
    return [idx for idx in groups.values() if len(idx) > 1]


def distinct_graphs(robot_graphs) -> tuple[list, np.ndarray]:
    """The distinct pose graphs (robots of one moveset share one) and each robot's index among them."""
    graphs: list = []
    gid = np.zeros(len(robot_graphs), dtype=np.int64)
    for i, g in enumerate(robot_graphs):
        for k, h in enumerate(graphs):
            if h is g:
                gid[i] = k
                break
        else:
            gid[i] = len(graphs)
            graphs.append(g)
    return graphs, gid


def _stacked(graphs: list, P: int) -> tuple:
    """The graphs' tables stacked into arrays of one shape (padded with -1, False or 0): the
    successors, collision cells, carried cells, carry flags, needed cells, targets and kinds."""
    A = max([g.num_actions for g in graphs] + [1])
    K = max([g.coll.shape[2] for g in graphs] + [1])
    Kc = max([g.carry.shape[2] for g in graphs] + [1])
    G = max(len(graphs), 1)
    succ = np.full((G, P, A), -1, np.int32)
    coll = np.full((G, P, A, K), -1, np.int32)
    carry = np.full((G, P, A, Kc), -1, np.int32)
    carry_ok = np.zeros((G, P, A), np.bool_)
    need = np.zeros((G, P, A, 2), np.int32)
    target = np.full((G, P, A), -1, np.int32)
    kind = np.zeros((G, A), np.int8)
    for k, g in enumerate(graphs):
        p, a = g.num_poses, g.num_actions
        succ[k, :p, :a] = g.succ
        coll[k, :p, :a, :g.coll.shape[2]] = g.coll
        carry[k, :p, :a, :g.carry.shape[2]] = g.carry
        carry_ok[k, :p, :a] = g.carry_ok
        need[k, :p, :a] = np.maximum(g.need, 0)  # read only where succ >= 0, where need is a cell
        target[k, :p, :a] = g.target
        kind[k, :a] = g.kind
    return succ, coll, carry, carry_ok, need, target, kind


def _goal_distances(instance: Instance, graphs: list, gid: np.ndarray, possible: np.ndarray, P: int,
                    distances: bool) -> np.ndarray:
    """``dist[i, p]``: robot ``i``'s bound from pose ``p`` (:func:`compile_tables`), 0 for a robot
    without a goal cell; computed once per graph and goal."""
    dist = np.zeros((instance.num_robots, P), np.int32)
    cache: dict = {}
    for i, goal in enumerate(instance.goal_cells):
        if goal >= 0:
            key = (int(gid[i]), goal)
            if key not in cache:
                g = graphs[gid[i]]
                cache[key] = _distances(g, goal, possible, P) if distances else \
                    np.pad((g.feet[:, 0] != goal).astype(np.int32), (0, P - g.num_poses), constant_values=1)
            dist[i] = cache[key]
    return dist


def _transport(graphs, cell_of: np.ndarray, possible: np.ndarray, P: int) -> tuple[np.ndarray, np.ndarray]:
    """The tile bound's tables (:mod:`.search`): ``reach[b, g, p]``, the motions from pose ``p``
    to a pose whose pick or place targets the cell of bit ``b``; ``fetch[b, g, p]``, the steps
    from ``p`` to a place on that cell for a robot that holds no tile: reach a pick on some cell
    allowed to change, pick, carry it to a pose targeting ``b`` (the fewest motions between the
    two, loads not minded), place."""
    k = len(cell_of)
    reach = np.full((k, len(graphs), P), FAR, np.int32)
    fetch = np.full((k, len(graphs), P), FAR, np.int32)
    for g, graph in enumerate(graphs):
        manipulating = (graph.kind == kernel.PICK) | (graph.kind == kernel.PLACE)
        for b, cell in enumerate(cell_of):
            aims = np.flatnonzero(graph.valid & (graph.target[:, manipulating] == cell).any(axis=1)
                                  & possible[np.maximum(graph.feet[:, 0], 0)] & possible[np.maximum(graph.feet[:, 1], 0)])
            reach[b, g] = _distances(graph, -1, possible, P, sources=aims)
        q = graph.num_poses
        # between[e, b]: the fewest motions from a pose targeting e to one targeting b
        between = np.full((k, k), FAR, np.int64)
        for e in range(k):
            aims = reach[e, g, :q] == 0
            if aims.any():
                between[e] = reach[:, g, :q][:, aims].min(axis=1)
        total = reach[:, g, :].astype(np.int64)[:, None, :] + between[:, :, None] + 2  # [e, b, p]
        fetch[:, g, :] = np.minimum(total.min(axis=0), FAR).astype(np.int32)
    return reach, fetch


def reversible(t: Tables) -> bool:
    """Whether :func:`reverse_tables` reads the steps backwards exactly: no pick or place has
    carried-tile cells (the shipped movesets have none; a moveset file may give some, and their
    cells count with the load before the step, which the step backwards does not hold)."""
    manipulating = (t.kind == kernel.PICK) | (t.kind == kernel.PLACE)  # [G, A]
    return not any((t.carry[g][:, manipulating[g]] >= 0).any() for g in range(t.kind.shape[0]))


def reverse_tables(instance: Instance, forward: Tables) -> Tables:
    """The tables of the steps taken backwards, for the search from the goal (:mod:`.bidirectional`).

    A step back over action ``a`` from pose ``q`` comes from the pose ``p`` with ``succ[p, a] = q``
    (each action's successor is one-to-one: a translation and a turn). It is valid exactly when the
    step forward from ``p`` is, from a valid state: so its collision set, carried cells and target
    are ``p``'s, the feet it needs on tiles are ``p``'s (the state before a step is valid), and
    undoing a pick puts the tile back (the kernel's place: the robot carries, the target is
    empty), undoing a place takes it (the kernel's pick). Connectivity is then checked on the
    tiles before the step, which a valid state has too; the tiles after the step were checked
    when the state was stored. No state is a goal of this side (``dist`` is 1 everywhere): the
    sides meet instead."""
    graphs, _ = distinct_graphs(instance.world.graphs)
    G, P, A = forward.succ.shape
    rsucc = np.full((G, P, A), -1, np.int32)
    rcoll = np.full_like(forward.coll, -1)
    rcarry = np.full_like(forward.carry, -1)
    rcarry_ok = np.zeros_like(forward.carry_ok)
    rneed = np.zeros_like(forward.need)
    rtarget = np.full_like(forward.target, -1)
    kind = forward.kind.copy()
    kind[forward.kind == kernel.PICK] = kernel.PLACE
    kind[forward.kind == kernel.PLACE] = kernel.PICK
    for k, g in enumerate(graphs):
        p, a = np.nonzero(forward.succ[k] >= 0)
        q = forward.succ[k, p, a]
        rsucc[k, q, a] = p
        rcoll[k, q, a] = forward.coll[k, p, a]
        rcarry[k, q, a] = forward.carry[k, p, a]
        rcarry_ok[k, q, a] = forward.carry_ok[k, p, a]
        rneed[k, q, a] = np.maximum(g.feet[p], 0)
        rtarget[k, q, a] = forward.target[k, p, a]
    masks = _masks(rcoll, rcarry, forward.W) if forward.W else forward.masks
    return dataclasses.replace(forward, succ=rsucc, coll=rcoll, carry=rcarry, carry_ok=rcarry_ok, need=rneed,
                               target=rtarget, kind=kind, masks=masks, dist=np.ones_like(forward.dist),
                               reach=np.zeros((0, 1, 1), np.int32), fetch=np.zeros((0, 1, 1), np.int32))


def _masks(coll: np.ndarray, carry: np.ndarray, W: int) -> np.ndarray:
    """Each action's collision set as bits of ``W`` words, ``[g, p, a, carrying, w]``: rule 3 is
    then that the masks of the robots' actions share no bit (their sets, with the carried tile's
    cells when carrying, are pairwise disjoint)."""
    G, P, A, _ = coll.shape
    masks = np.zeros((G, P, A, 2, W), np.uint64)

    def add(cells, which):
        for k in range(cells.shape[3]):
            cell = cells[..., k].astype(np.int64)
            has = cell >= 0
            word = np.where(has, cell // 64, 0)
            bit = np.where(has, np.left_shift(np.uint64(1), (np.maximum(cell, 0) % 64).astype(np.uint64)), np.uint64(0))
            for w in range(W):
                for c in which:
                    masks[:, :, :, c, w] |= np.where(word == w, bit, np.uint64(0))

    add(coll, (0, 1))
    add(carry, (1,))
    return masks.view(np.int64)


def _distances(graph, goal: int, possible: np.ndarray, P: int, sources: np.ndarray | None = None) -> np.ndarray:
    """Each pose's least number of motions to a pose with its front foot on ``goal``, over the
    moves whose new feet are on ``possible`` cells (:data:`FAR` where there is none). A lower
    bound on the steps a robot needs: every pose a schedule of the class takes has its feet on
    tiles (rule 4), so on cells of ``possible``."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import shortest_path

    walks = (graph.kind == kernel.WAIT) | (graph.kind == kernel.MOTION)
    ok = (graph.succ >= 0) & walks[None, :]
    ok &= possible[np.maximum(graph.need[..., 0], 0)] & possible[np.maximum(graph.need[..., 1], 0)]
    p, a = np.nonzero(ok)
    s = graph.succ[p, a]
    keep = s != p
    q = graph.num_poses
    # reversed edges (successor -> pose) plus a source q joined to every goal pose
    goals = np.flatnonzero(graph.valid & (graph.feet[:, 0] == goal)) if sources is None else sources
    rows = np.concatenate([s[keep], np.full(len(goals), q)])
    cols = np.concatenate([p[keep], goals])
    matrix = csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(q + 1, q + 1))
    d = shortest_path(matrix, unweighted=True, indices=q, directed=True)[:q] - 1
    out = np.full(P, FAR, np.int32)
    finite = np.isfinite(d)
    out[:q][finite] = d[finite].astype(np.int32)
    return out
