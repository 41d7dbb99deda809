"""A bound on the steps left from any joint state of a class: the exact distances of a coarser
world, searched backwards once from its goals (a pattern database).

**The abstract world.** Its state keeps each robot's pose and load as they are, and of the tiles
only how many lie on each *group* of cells. The cells the class allows to change, less its
pinned cells (:func:`bille.solvers.bounds.classes.pinned`: cells that hold a tile at every step
of every schedule of the class), are split into those where the start and the goal differ and
the others, and the groups are the 4-connected pieces of each. Its steps are the joint actions
of the robots under the rules with three of them relaxed:

- support: a robot may stand on any cell that may hold a tile in the class (the cells allowed
  to change, and the start's tiles), whether it holds one or not (no other cell ever does);
- a pick from a group needs a tile on it, a place an empty cell of it: a step picks at most
  ``count`` tiles from a group and places at most ``size - count`` on it; no pick or place
  targets a pinned cell or a cell the class does not allow to change;
- connectivity is not asked for.

The preconditions on the loads, the workspace and the collision sets (rules 1-3) are the exact
rules', read from the same tables (:mod:`.tables`).

**Why it is a bound.** Map a state of the class to the abstract state with the same poses and
loads and each group's count of tiles. A step of the class maps to an abstract step: its robots'
actions are the same, their collision sets the same, every new foot stands on a tile, so on a
cell that may hold one; a pick takes a tile from a cell of a group (a pinned cell is never
picked, nor placed on since it always holds a tile; a cell the class keeps never changes), so
the group held at least as many tiles as the step picks from it, and a place sets a tile on an
empty cell, one of at most ``size - count``. A goal state maps to an abstract goal (the goal's
counts, no load, each robot with a goal cell on it). So a schedule of ``k`` steps from a state
maps to an abstract path of ``k`` steps from its image, and the abstract distance (the fewest
steps to an abstract goal; infinite where none is reached) is at most the steps left from the
state: an admissible bound, and consistent, since a step changes the image by one abstract step.

The distances are computed by a breadth-first search backwards from every abstract goal, stored
one byte a state of the whole abstract space, where it is small enough (:data:`MAX_SIZE`).

**Interchangeable robots** (one moveset, no goal cell: the search's symmetry groups) are alike in
the abstract world too, so a state's distance is that of the state with their values sorted;
only sorted states are stored and looked up (the search backwards from a sorted state reaches
every state one step before it or before any of its permutations, up to sorting), each group's
sorted values ranked as a multiset, so the table of three such robots is about a sixth of
their values cubed.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bille.instances import Instance

from . import kernel
from .backwards import goals, layer
from .compiled import UNREACHED, abstract_distance, sort_groups
from .cells import Cells
from .tables import Tables, distinct_graphs, interchangeable

MAX_SIZE = 2_000_000_000  # abstract states (a byte each)
# a call of the compiled layer looks at about this many joint steps backwards (its states times the
# joint actions of a state at most), so the budget is polled within a second or so
WORK = 1 << 25
OUT = 1 << 22  # states listed per buffer


@dataclass(frozen=True, eq=False)
class Abstraction:
    """The abstract distances (module docstring) and how a packed state maps to its index.

    ``local[g, p]`` is pose ``p``'s index among the poses of graph ``g`` whose feet may stand
    (-1 elsewhere); a robot's local value is twice that plus its load. The robots' part of an
    index runs over ``blocks`` (rows ``start, robots, values``): each group of interchangeable
    robots is one block, its robots' sorted local values ranked as a multiset, and every other
    robot a block of its own; ``order[start:start + robots]`` lists a block's robots and
    ``binom`` the binomial coefficients the ranks read. ``gmask[k, w]`` has the bits of group
    ``k`` in tile word ``w``, ``size[k]`` its cells; ``dist`` one byte per index:
    :data:`UNREACHED` where no abstract goal is reached when ``complete``, else where none is
    reached in 254 steps (a bound all the same)."""

    local: np.ndarray
    order: np.ndarray
    blocks: np.ndarray
    binom: np.ndarray
    gmask: np.ndarray
    size: np.ndarray
    dist: np.ndarray
    complete: bool = True  # every abstract state that reaches a goal has its distance (none beyond 254)

    def at(self, t: Tables, row: np.ndarray) -> int:
        """The bound of a packed state (:data:`UNREACHED` where no abstract goal is reached)."""
        rmask = (1 << t.rbits) - 1
        vals = np.array([(int(row[i // t.rpw]) >> ((i % t.rpw) * t.rbits)) & rmask for i in range(t.m)], np.int64)
        sort_groups(vals, t.sym_start, t.sym_idx)  # interchangeable robots sorted, as stored
        return int(abstract_distance(vals, row, t.nR, t.gid, self.local, self.order, self.blocks, self.binom,
                                     self.gmask, self.size, self.dist))


def groups(instance: Instance, cells: Cells) -> tuple[np.ndarray, int]:
    """Each cell's group (-1 for none) and the number of groups (module docstring)."""
    from bille.instances.grid import components
    from bille.solvers.bounds.classes import pinned

    possible = instance.start.tiles | cells.mask
    free = cells.mask & ~pinned(instance, possible)
    differ = instance.start.tiles ^ instance.goal_tiles
    out = np.full(free.shape, -1, np.int64)
    k = 0
    for part in (free & differ, free & ~differ):
        labels, n = components(part, instance.width, instance.height)
        out[part] = labels[part] - 1 + k
        k += int(n)
    return out, k


def size_of(instance: Instance, cells: Cells) -> int:
    """The number of abstract states (its distances take a byte each)."""
    from math import comb

    possible = instance.start.tiles | cells.mask
    group, k = groups(instance, cells)
    sizes = np.bincount(group[group >= 0], minlength=k)
    total = int(np.prod(sizes + 1, dtype=np.float64))
    _, gid = distinct_graphs(instance.world.graphs)
    sym = interchangeable(instance, gid)  # each group: a multiset of values
    alone = set(range(instance.num_robots)) - {i for idx in sym for i in idx}
    values = [2 * int(_standing(graph, possible).sum()) for graph in instance.world.graphs]
    for idx in sym + [[i] for i in sorted(alone)]:
        total *= comb(values[idx[0]] + len(idx) - 1, len(idx))
    return total


def _blocks(t: Tables, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``order``, ``blocks`` and ``binom`` of :class:`Abstraction` for robots with ``values``
    local values each: the search's symmetry groups, then every other robot alone."""
    from math import comb

    rows, order = [], []
    grouped = set(int(i) for i in t.sym_idx)
    parts = [[int(i) for i in t.sym_idx[t.sym_start[s]:t.sym_start[s + 1]]] for s in range(len(t.sym_start) - 1)]
    parts += [[i] for i in range(t.m) if i not in grouped]
    for robots in parts:
        v = int(values[robots[0]])
        rows.append((len(order), len(robots), comb(v + len(robots) - 1, len(robots))))
        order += robots
    top = int(values.max(initial=1)) + t.m + 1
    binom = np.array([[comb(n, k) for k in range(t.m + 2)] for n in range(top)], np.int64)
    return np.array(order, np.int64), np.array(rows, np.int64).reshape(-1, 3), binom


def _standing(graph, possible: np.ndarray) -> np.ndarray:
    feet = graph.feet
    ok = graph.valid & possible[np.maximum(feet[:, 0], 0)]
    both = feet[:, 1] >= 0
    ok[both] &= possible[np.maximum(feet[both, 1], 0)]
    return ok


def build(instance: Instance, cells: Cells, t: Tables, budget=None) -> Abstraction | None:
    """The abstraction of ``cells`` on ``instance`` (module docstring), or None where the rules'
    collision sets are not bit masks (classic collisions, large grids), a pick or place carries
    cells, or the space exceeds :data:`MAX_SIZE`. ``budget`` polled every :data:`WORK` joint
    steps backwards or so: None if it runs out first."""
    from .tables import reversible

    if t.W == 0 or t.classic or not reversible(t) or size_of(instance, cells) > MAX_SIZE:
        return None
    possible = instance.start.tiles | cells.mask
    group, k = groups(instance, cells)
    G, P, A = t.succ.shape
    graphs, _ = distinct_graphs(instance.world.graphs)
    local = np.full((G, P), -1, np.int64)
    glob = np.full((G, P), -1, np.int64)
    count = np.zeros(G, np.int64)
    for g, graph in enumerate(graphs):
        ids = np.flatnonzero(_standing(graph, possible))
        local[g, ids] = np.arange(len(ids))
        glob[g, :len(ids)] = ids
        count[g] = len(ids)
    V = np.array([2 * count[t.gid[i]] for i in range(t.m)], np.int64)
    order, blocks, binom = _blocks(t, V)
    sizes = np.bincount(group[group >= 0], minlength=k).astype(np.int64)
    gmask = np.zeros((max(k, 1), t.nT), np.int64)
    for b, cell in enumerate(t.cell_of):
        if group[cell] >= 0:
            gmask[group[cell], b // kernel.TILE_BITS] |= np.int64(1) << np.int64(b % kernel.TILE_BITS)
    goal_counts = np.array([int(instance.goal_tiles[group == j].sum()) for j in range(k)], np.int64)
    goal_cell = np.array(instance.goal_cells, np.int64)
    front = np.full((G, P), -1, np.int64)
    for g, graph in enumerate(graphs):
        front[g, :graph.num_poses] = graph.feet[:, 0]
    # each local pose's steps backwards: the (pose, action) pairs whose step forward reaches it
    rstart = np.zeros((G, P + 1), np.int64)
    rp_list, ra_list = [], []
    for g in range(G):
        p, a = np.nonzero((t.succ[g] >= 0) & (local[g] >= 0)[:, None])
        q = t.succ[g, p, a]
        keep = local[g, q] >= 0
        p, a, q = p[keep], a[keep], q[keep]
        by = np.argsort(local[g, q], kind="stable")
        p, a, q = p[by], a[by], local[g, q[by]]
        rstart[g, 1:] = np.cumsum(np.bincount(q, minlength=P))[:P]
        rstart[g] += sum(len(x) for x in rp_list)
        rp_list.append(p)
        ra_list.append(a)
    rp = np.concatenate(rp_list).astype(np.int64) if rp_list else np.zeros(0, np.int64)
    ra = np.concatenate(ra_list).astype(np.int64) if ra_list else np.zeros(0, np.int64)
    total = int(np.prod(blocks[:, 2])) * int(np.prod(sizes + 1))
    dist = np.full(total, UNREACHED, np.uint8)
    mult = np.ones(max(k, 1), np.int64)
    for j in range(k - 2, -1, -1):
        mult[j] = mult[j + 1] * (sizes[j + 1] + 1)
    goals(dist, t.m, V, t.gid, glob, front, goal_cell, int(np.dot(goal_counts, mult[:k])) if k else 0,
           int(np.prod(sizes + 1)), order, blocks, binom, t.sym_start, t.sym_idx)
    frontier = np.flatnonzero(dist == 0)
    out = np.empty(max(OUT, t.kind.shape[1] ** t.m), np.int64)
    chunk = max(1, WORK // t.kind.shape[1] ** t.m)
    for level in range(UNREACHED - 1):
        parts, pos, nout = [], 0, 0
        while pos < len(frontier):
            if budget is not None and budget.expired():
                return None
            hi = min(pos + chunk, len(frontier))
            pos, nout = layer(dist, level, frontier, pos, hi, out, nout, t.m, t.gid, local, rstart, rp, ra, t.kind,
                               t.target, t.carry_ok, t.masks, t.W, group, sizes, mult, k, t.sym_start, t.sym_idx, order,
                               blocks, binom)
            if pos < hi:  # out is full (it holds the steps backwards of any one state)
                parts.append(out[:nout].copy())
                nout = 0
        frontier = np.concatenate(parts + [out[:nout]])
        if len(frontier) == 0:
            return Abstraction(local, order, blocks, binom, gmask, sizes, dist)
    return Abstraction(local, order, blocks, binom, gmask, sizes, dist, complete=False)


def attach(instance: Instance, cells: Cells, t: Tables, budget, room: float) -> tuple[Tables, dict | None]:
    """``t`` with the abstraction's distances, where they serve: a class that keeps some cells
    (``keep`` and ``no-scaffold``, widened or not; over every cell one group holds all tiles
    and the bound is weak: bridge-2's is 8 where its optimum is 23), an abstract space of at
    most :data:`MAX_SIZE` states and half of ``room`` bytes, built within ``budget``. Also what
    was built (its states, the start's bound, whether it proves that the class has no schedule:
    no abstract goal reached from the start, seconds), or None."""
    if cells.unconditional:
        return t, None
    size = size_of(instance, cells)
    if size > min(MAX_SIZE, room // 2):
        return t, None
    began = budget.now()
    a = build(instance, cells, t, budget)
    if a is None:
        return t, None
    t = dataclasses.replace(t, pdb_local=a.local, pdb_order=a.order, pdb_blocks=a.blocks, pdb_binom=a.binom,
                            pdb_gmask=a.gmask, pdb_size=a.size, pdb_dist=a.dist)
    start = a.at(t, t.pack(instance.start_state))
    return t, {"states": size, "start": start, "none": start == UNREACHED and a.complete,
               "s": round(budget.now() - began, 3)}
