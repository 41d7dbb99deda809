"""The paper's Theorem 2 (``bille gen coop``): a gadget that two robots solve fastest only by
handing a tile over, alone and attached to Theorem 1's construction.

The paper's figure is missing; this is our gadget (``y`` down, ``gap = 2`` drawn)::

    t . t . t . A . . . . . . . B . t . t . t     t  task tile: a tile in the start only
    # # # # # # 1 # # # # # # # 2 # # # # # #     p  task position: a tile in the goal only
    p . p . p . : . . . . . . . : . p . p . p     A  the large task's tile, B its position
                                                  #  tiles of start and goal
                                                  1, 2  the robots' entries (attached: the
                                                        lines from below end at ``:``)

A line of tiles (the *bridge*) with three *small tasks* at each end: a tile above the line and a
position below it, two apart, which a robot standing between them solves in two steps (pick,
place). The *large task* moves tile ``A`` eight cells along the bridge to ``B``. Robot 1 starts
on the bridge below ``A``, robot 2 below ``B``; the small tasks begin ``gap`` cells beyond them,
on the far sides.

Tiles are identical, but every tile that ends on the right comes from the left and only a robot
carries one across, so some tile crosses the eight cells between ``A`` and ``B``. A robot that
carries it all the way pays eight steps on top of its side's small tasks and has to do those
first or walk back; the bridge has no cell to pass on, so the robots cannot trade sides cheaply.
Split, robot 1 carries the tile part of the way at once, sets it down above the bridge and walks
back to its tasks, while robot 2 solves a task first and then carries the tile on. A point robot
picks only next to it, so the hand-over costs two steps (robot 1 steps off, robot 2 steps on).

Measured (tests/test_coop.py, docs/generators.md), ``gap = 2``: the split schedule of
:func:`demonstration` takes 24 steps; the best schedule that carries every tile once, straight
from its start to its goal (the exact solvers' ``single_carry``), takes :data:`NO_SPLIT` = 28,
proved by CP-SAT. So every optimal schedule splits the large task.
"""
from __future__ import annotations

import networkx as nx

from ..errors import InstanceError
from ..instance import Instance, Robot, check_instance
from ..limits import check_size
from ..moveset import load_moveset
from .graphs import draw_graph, grid_graph, hamiltonian_path
from .hampath import HALF, T_G, Layout, bound, check_graph, tiles_grid

XY = tuple[int, int]
LARGE = 8                    # cells the large task moves its tile
SMALL = (0, 2, 4)            # the small tasks' columns, from a side's outer end
NO_SPLIT = 28                # the best single-carry schedule for gap = 2 (proved by CP-SAT, see the tests)
ROW = 4                      # the row of the connectors' horizontal runs (attached)


class Gadget:
    """The gadget's cells with its top left corner at ``(left, top)``; ``entries`` are the
    robots' cells on the bridge, below ``A`` and ``B``."""

    def __init__(self, gap: int = 2, left: int = 0, top: int = 0) -> None:
        if gap < 2:
            raise InstanceError(f"the gap must be at least 2 (the entries' connectors then touch no task), got {gap}")
        self.gap = gap
        self.width = 2 * (SMALL[-1] + gap) + LARGE + 1
        check_size([load_moveset("point")], left + self.width, top + 3, "the cooperative gadget")
        a = left + SMALL[-1] + gap
        self.entries = ((a, top + 1), (a + LARGE, top + 1))
        right = a + LARGE + gap                       # the right side's first small task
        columns = [left + k for k in SMALL] + [right + k for k in SMALL]
        self.base = {(x, top + 1) for x in range(left, left + self.width)}
        self.tiles_only = {(x, top) for x in columns} | {(a, top)}
        self.goal_only = {(x, top + 2) for x in columns} | {(a + LARGE, top)}


def demonstration(gap: int = 2) -> list[list[str]]:
    """The schedule that splits the large task (the paper's demonstration), one action list
    per robot. Robot 1 picks ``A``, carries it ``k`` cells east, sets it down above the bridge
    and walks back to its three small tasks; robot 2 solves its nearest small task, comes back,
    steps in when robot 1 has stepped away, picks the tile up, carries it the other ``8 - k``
    cells to ``B`` and solves its other two. ``k`` balances the two robots' steps (``k = 5``
    for ``gap = 2``: 24 steps each)."""
    task = ["pick-north", "place-south"]
    best = None
    for k in range(1, LARGE):
        one = (["pick-north"] + ["east"] * k + ["place-north"] + ["west"] * (k + gap)
               + task + ["west"] * 2 + task + ["west"] * 2 + task)
        # robot 1 steps off the pick-up stand with its step k + 3; robot 2 may step on one later
        come = ["west"] * (gap + LARGE - k)
        early = (k + 4) - (gap + len(task) + len(come))
        two = (["east"] * gap + task + come[:-1] + ["wait"] * max(0, early) + come[-1:]
               + ["pick-north"] + ["east"] * (LARGE - k) + ["place-north"] + ["east"] * (gap + 2)
               + task + ["east"] * 2 + task)
        steps = max(len(one), len(two))
        if best is None or steps < best[0]:
            best = (steps, [row + ["wait"] * (steps - len(row)) for row in (one, two)])
    return best[1]


def gadget(gap: int = 2, *, name: str | None = None) -> Instance:
    """Theorem 2's cooperative gadget alone, two ``point`` robots on its entries."""
    g = Gadget(gap)
    meta = {"generator": "coop", "theorem": "2 (the gadget alone)", "gap": gap, "large_task": LARGE,
            "small_tasks": 2 * len(SMALL), "split_makespan": len(demonstration(gap)[0]),
            "best_single_carry": NO_SPLIT if gap == 2 else None}
    return check_instance(Instance(
        name or f"coop-gap{gap}", load_moveset("point"), tiles_grid(g.width, 3, g.base | g.tiles_only),
        tuple(Robot(e) for e in g.entries), goal=tiles_grid(g.width, 3, g.base | g.goal_only), meta=meta))


def default_ends(g: nx.Graph, start: XY | None = None, end: XY | None = None) -> tuple[XY, XY]:
    """The start and end vertices of the Hamiltonian path asked for, where not given, in
    reading order (by ``y``, then ``x``): the end is the first vertex with no vertex above it
    (its upper arm leads to the gadget) and of degree 1, else the first with none above it; the
    start is the first other vertex of degree 1, else the first other vertex (any Hamiltonian
    path has the vertices of degree 1 at its ends)."""
    order = sorted(g.nodes, key=lambda v: (v[1], v[0]))
    if len(order) == 1:
        return order[0], order[0]
    if end is None:
        free = [v for v in order if _free_above(g, v) and v != start]
        if not free:
            raise InstanceError(f"no vertex other than the start {start} has the column above it free")
        end = min(free, key=lambda v: g.degree(v) != 1)
    if start is None:
        start = min((v for v in order if v != end), key=lambda v: g.degree(v) != 1)
    return start, end


def _free_above(g: nx.Graph, v: XY) -> bool:
    return not any(u[0] == v[0] and u[1] < v[1] for u in g.nodes)


def attached(g: nx.Graph, scale: int, *, start: XY | None = None, end: XY | None = None, gap: int = 2,
             name: str | None = None) -> Instance:
    """Theorem 2's instance: the gadget, robot 1 on Theorem 1's construction for ``g`` below
    it, robot 2 on a string of ``|V|`` gadgets (a path, solved in order), each joined to its
    entry by a line of tiles of the same length (see docs/generators.md).

    Both robots can stand on their entries at ``arrival`` (in the metadata) only if ``g`` has a
    Hamiltonian path from ``start`` to ``end``; they can then finish by ``bound`` = ``arrival``
    + the steps of :func:`demonstration`. ``end`` must have no vertex above it: its upper arm
    leads to the gadget. Raises :class:`InstanceError` for bad graphs, scales, vertices, gaps.
    """
    return _attached(g, scale, start, end, gap, name)[0]


def _attached(g: nx.Graph, scale: int, start: XY | None, end: XY | None, gap: int,
              name: str | None) -> tuple[Instance, _Parts]:
    check_graph(g, scale)
    for what, v in (("start", start), ("end", end)):
        if v is not None and tuple(v) not in g:
            raise InstanceError(f"the {what} vertex {tuple(v)} is not a vertex of the graph")
    start, end = default_ends(g, None if start is None else tuple(start), None if end is None else tuple(end))
    if not _free_above(g, end):
        raise InstanceError(f"the end vertex {end} has a vertex above it; its upper arm must lead out to the gadget")
    if start == end and g.number_of_nodes() > 1:
        raise InstanceError(f"the start and end vertices are both {start}")
    n = g.number_of_nodes()
    parts = _Parts(g, scale, end, gap)
    check_size([load_moveset("point")], parts.width, parts.height, "gen coop")
    meta = {"generator": "coop", "theorem": "2", "scale": scale, "gap": gap, "vertices": n,
            "edges": g.number_of_edges(), "start_vertex": list(start), "end_vertex": list(end),
            "graph": draw_graph(g), "t_g": T_G, "arrival": parts.arrival,
            "bound": parts.arrival + len(demonstration(gap)[0])}
    path = hamiltonian_path(g, start=start, end=end)
    meta["hamiltonian_path"] = None if path is None else [list(v) for v in path]
    robots = (Robot(parts.first.robot_cell(start)), Robot(parts.second.robot_cell((n - 1, 0))))
    w, h = parts.width, parts.height
    base = parts.base | parts.gadget.base
    return check_instance(Instance(
        name or f"coop-v{n}-s{scale}", load_moveset("point"),
        tiles_grid(w, h, base | parts.tiles_only | parts.gadget.tiles_only), robots,
        goal=tiles_grid(w, h, base | parts.goal_only | parts.gadget.goal_only), meta=meta)), parts


class _Parts:
    """Where everything goes: the gadget on rows 0-2; robot 1's copy of ``g`` from row
    ``ROW + 2`` down, its ``end`` vertex's upper arm joined to entry 1 by a line up to row
    ``ROW``, along it and up; robot 2's string of gadgets to the right, its left end joined to
    entry 2 the same way, by a line of the same length (the string is placed to make it so)."""

    def __init__(self, g: nx.Graph, scale: int, end: XY, gap: int) -> None:
        n, top = g.number_of_nodes(), ROW + 2
        self.first = Layout(g, scale, 0, top)
        a = max(self.first.width, SMALL[-1] + gap)    # entry 1's column: right of the copy
        self.gadget = Gadget(gap, left=a - SMALL[-1] - gap)
        (a, _), (b, _) = self.gadget.entries
        ex, ey = self.first.centre(end)
        length = (ey - HALF - 1) + (a - ex)          # from the upper arm's tip to entry 1
        string = grid_graph([(k, 0) for k in range(n)])
        # the string's left vertex is at x = b + length - (its tip's height - 1)
        sx = b + length - (top - 1)
        self.second = Layout(string, scale, sx - HALF, top)
        self.arrival = bound(n, scale) + HALF + length
        self.ways = (self.first.up_from(end, ROW) | {(x, ROW) for x in range(ex, a + 1)}
                     | {(a, y) for y in range(1, ROW)},
                     self.second.up_from((0, 0), ROW) | {(x, ROW) for x in range(b, sx + 1)}
                     | {(b, y) for y in range(1, ROW)})
        self.base = self.first.base | self.second.base | self.ways[0] | self.ways[1]
        self.tiles_only = self.first.tiles_only | self.second.tiles_only
        self.goal_only = self.first.goal_only | self.second.goal_only
        self.width = sx - HALF + self.second.width
        self.height = top + max(self.first.height, self.second.height)


def approaches(g: nx.Graph, scale: int, *, start: XY | None = None, end: XY | None = None,
               gap: int = 2) -> tuple[Instance, Instance]:
    """The two robots' ways to the gadget of :func:`attached`, each alone: robot 1's copy of
    ``g`` and robot 2's string, each with its line of tiles to its entry as the robot's goal
    cell. Their optimal makespans are the robots' earliest arrivals at the gadget."""
    inst, parts = _attached(g, scale, start, end, gap, None)
    w, h = parts.width, parts.height
    out = []
    for k, (layout, way) in enumerate(((parts.first, parts.ways[0]), (parts.second, parts.ways[1]))):
        base = layout.base | way
        out.append(check_instance(Instance(
            f"{inst.name}-way{k + 1}", inst.moveset, tiles_grid(w, h, base | layout.tiles_only),
            (inst.robots[k],), goal=tiles_grid(w, h, base | layout.goal_only),
            robot_goals=(parts.gadget.entries[k],), meta={"arrival": parts.arrival})))
    return out[0], out[1]
