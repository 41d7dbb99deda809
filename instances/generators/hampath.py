"""The paper's NP-hardness construction: Theorem 1 (``bille gen hampath``) and Corollary 1
(``--robots m``).

A grid graph ``G`` becomes a reconfiguration instance for one ``point`` robot whose optimal
makespan is ``(s + 7)(|V| - 1) + t_g |V|`` exactly when ``G`` has a Hamiltonian path starting at
the robot's vertex, and larger otherwise. The paper's figure is missing; this is our gadget.
Around every vertex tile ``V`` (offsets ``dx, dy`` from it, ``y`` down)::

    . p . # . t .       #  gadget tile (the 7x7 cross and a 5x5 ring)
    t # # # # # p       V  the vertex tile
    . # . # . # .       t  task tile: a tile in the start only
    # # # V # # #       p  task position: a tile in the goal only
    . # . # . # .
    p # # # # # t
    . t . # . p .

Each corner of the ring has a task tile on one outer side and a task position on the other: a
robot standing on the corner picks the one and places it on the other, two steps. A task cell's
only tile neighbour is its corner, so every corner must be visited. The four corners are 4
apart on the ring; the cross's arms leave the ring at the middle of its sides, 2 from the two
nearest corners. So a robot that enters by one arm and leaves by any other walks 2 + 4 + 4 + 4 + 2
between the ring's sides instead of the 4 of a straight pass, ``t_g = 12 + 8 = 20`` steps more
than walking through; one that enters and stops (the path's last vertex) walks 2 + 12 and its 8
manipulations, 20 more than reaching ``V``; and the robot starts on a corner of its vertex's ring,
from which the other three corners and any arm cost the same 20. Adjacent vertex tiles are
``s + 7`` apart, joined along the arms by ``s`` edge tiles, so a Hamiltonian path costs exactly
``(s + 7)(|V| - 1) + 20 |V|``; a walk that has to come back through a vertex walks an edge
twice, ``s + 7`` more, and saves only part of it in the gadgets it cuts short (three vertices in
a row started in the middle: the bound plus ``s + 3``). The numbers are checked by exhaustive
search in the tests (docs/generators.md).

The robot's start vertex is part of the instance: the bound is met exactly when a Hamiltonian
path *from that vertex* exists. By default it is a vertex of degree 1 if there is one (every
Hamiltonian path then has it at one end), else the first vertex; see docs/decisions.md.

Corollary 1: ``robots`` copies side by side, so far apart (the bound plus one) that no robot can
reach another copy before its own is done, joined by one line of tiles above them; one robot
each.
"""
from __future__ import annotations

import networkx as nx
import numpy as np

from ..errors import InstanceError
from ..grid import Grid, neighbour_table
from ..instance import Instance, Robot, check_instance
from ..limits import check_size
from ..moveset import Kind, load_moveset
from ..rules import State, apply
from ..schedule import Schedule
from ..walking import Walk
from .graphs import check_grid_graph, draw_graph, hamiltonian_path

XY = tuple[int, int]
HALF = 3                     # a gadget spans -3..3 around its vertex tile
T_G = 20                     # steps to solve one gadget beyond walking through it (see above)
CROSS = frozenset({(0, 0)} | {(d * k, 0) for d in (1, -1) for k in (1, 2, 3)}
                  | {(0, d * k) for d in (1, -1) for k in (1, 2, 3)})
RING = frozenset((x, y) for x in range(-2, 3) for y in range(-2, 3) if max(abs(x), abs(y)) == 2)
# (corner, task tile, task position), a quarter turn apart
CORNERS = (((2, 2), (3, 2), (2, 3)), ((-2, 2), (-2, 3), (-3, 2)),
           ((-2, -2), (-3, -2), (-2, -3)), ((2, -2), (2, -3), (3, -2)))
ROBOT_CORNER = CORNERS[0][0]


def bound(vertices: int, scale: int) -> int:
    """Theorem 1's makespan, ``(s + 7)(|V| - 1) + t_g |V|``."""
    return (scale + 2 * HALF + 1) * (vertices - 1) + T_G * vertices


def check_graph(g: nx.Graph, scale: int) -> None:
    """Raise :class:`InstanceError` for a graph that is not a grid graph, an empty or
    disconnected one, or a scale below 1."""
    check_grid_graph(g)
    if g.number_of_nodes() == 0:
        raise InstanceError("the graph has no vertices")
    if not nx.is_connected(g):
        raise InstanceError(f"the graph is not connected ({nx.number_connected_components(g)} parts)")
    if scale < 1:
        raise InstanceError(f"the scale must be at least 1, got {scale}")


def default_start(g: nx.Graph) -> XY:
    """A vertex of degree 1 if there is one (every Hamiltonian path ends there), else the first
    vertex, both in reading order (by ``y``, then ``x``)."""
    order = sorted(g.nodes, key=lambda v: (v[1], v[0]))
    return next((v for v in order if g.degree(v) == 1), order[0])


def reduction(g: nx.Graph, scale: int, *, start: XY | None = None, robots: int = 1, moveset: str = "point",
              name: str | None = None) -> Instance:
    """Theorem 1's instance for grid graph ``g`` (Corollary 1's with ``robots > 1``).

    Raises :class:`InstanceError` for an empty or disconnected graph, a scale below 1, fewer
    than one robot, or a start that is not a vertex.
    """
    check_graph(g, scale)
    if robots < 1:
        raise InstanceError(f"at least 1 robot, got {robots}")
    start = default_start(g) if start is None else tuple(start)
    if start not in g:
        raise InstanceError(f"the start vertex {start} is not a vertex of the graph")
    ms = load_moveset(moveset)
    n = g.number_of_nodes()
    best = bound(n, scale)
    one = Layout(g, scale)
    gap = best + 1 if robots > 1 else 0
    top = 2 if robots > 1 else 0                 # the line joining the copies runs along row 0
    width, height = robots * one.width + (robots - 1) * gap, top + one.height
    check_size([ms], width, height, "gen hampath")
    anchor = min(g.nodes, key=lambda v: (v[1], v[0]))
    base, tiles_only, goal_only, placed = set(), set(), set(), []
    copies = [Layout(g, scale, k * (one.width + gap), top) for k in range(robots)]
    for copy in copies:
        base |= copy.base
        tiles_only |= copy.tiles_only
        goal_only |= copy.goal_only
        front = copy.robot_cell(start)
        placed.append(Robot(front) if ms.footprint == "point" else Robot(front, (front[0] - 1, front[1])))
        if robots > 1:   # down from the joining line to the upper arm of a top vertex (free: none above)
            base |= copy.up_from(anchor, 0)
    if robots > 1:
        base |= {(x, 0) for x in range(copies[0].centre(anchor)[0], copies[-1].centre(anchor)[0] + 1)}
    path = hamiltonian_path(g, start=start)
    point = ms.footprint == "point"
    meta = {"generator": "hampath", "theorem": "1" if robots == 1 else "corollary 1", "scale": scale,
            "vertices": n, "edges": g.number_of_edges(), "robots": robots, "start_vertex": list(start),
            "graph": draw_graph(g), "t_g": T_G if point else None, "bound": best if point else None,
            "hamiltonian_path_from_start": None if path is None else [list(v) for v in path]}
    if not point:
        meta["note"] = "t_g and the bound are those of the point footprint (the paper's model) only"
    return check_instance(Instance(
        name or f"hampath-v{n}-s{scale}" + (f"-r{robots}" if robots > 1 else ""), ms,
        tiles_grid(width, height, base | tiles_only), tuple(placed), goal=tiles_grid(width, height, base | goal_only),
        meta=meta))


class Layout:
    """The cells of one copy of Theorem 1's construction for ``g``, its top left corner at
    ``(left, top)``: ``base`` (tiles of start and goal), ``tiles_only`` (task tiles) and
    ``goal_only`` (task positions)."""

    def __init__(self, g: nx.Graph, scale: int, left: int = 0, top: int = 0) -> None:
        self.pitch = scale + 2 * HALF + 1
        xs, ys = [x for x, _ in g.nodes], [y for _, y in g.nodes]
        self.origin = (left + HALF - min(xs) * self.pitch, top + HALF - min(ys) * self.pitch)
        self.width = 2 * HALF + 1 + (max(xs) - min(xs)) * self.pitch
        self.height = 2 * HALF + 1 + (max(ys) - min(ys)) * self.pitch
        check_size([load_moveset("point")], left + self.width, top + self.height, "the reduction's construction")
        self.base, self.tiles_only, self.goal_only = set(), set(), set()
        for v in g.nodes:
            cx, cy = self.centre(v)
            self.base |= {(cx + dx, cy + dy) for dx, dy in CROSS | RING}
            self.tiles_only |= {(cx + tx, cy + ty) for _, (tx, ty), _ in CORNERS}
            self.goal_only |= {(cx + px, cy + py) for _, _, (px, py) in CORNERS}
        for u, v in g.edges:
            (ux, uy), (vx, vy) = sorted((self.centre(u), self.centre(v)))
            self.base |= {(x, uy) for x in range(ux + HALF + 1, vx - HALF)} if uy == vy else \
                         {(ux, y) for y in range(uy + HALF + 1, vy - HALF)}

    def centre(self, v: XY) -> XY:
        """The cell of vertex ``v``'s vertex tile."""
        return (self.origin[0] + v[0] * self.pitch, self.origin[1] + v[1] * self.pitch)

    def robot_cell(self, v: XY) -> XY:
        """Where a robot starting at vertex ``v`` stands: a corner of its ring."""
        cx, cy = self.centre(v)
        return (cx + ROBOT_CORNER[0], cy + ROBOT_CORNER[1])

    def up_from(self, v: XY, row: int) -> set[XY]:
        """A line of tiles from the tip of ``v``'s upper arm up to ``row`` (exclusive of the
        tip; ``v`` must have no vertex above it, so the line touches nothing else)."""
        cx, cy = self.centre(v)
        return {(cx, y) for y in range(row, cy - HALF)}


def tiles_grid(width: int, height: int, cells) -> Grid:
    """A grid with tiles on ``cells`` and no obstacles."""
    tiles = np.zeros(width * height, dtype=bool)
    for x, y in cells:
        tiles[y * width + x] = True
    return Grid.from_masks(width, height, np.zeros(width * height, dtype=bool), tiles)


# ---------------------------------------------------------------------------------------------
# exhaustive search over the single robot's states, for the reductions' small cases

def _sites(inst: Instance, walk: np.ndarray, task_set: set[int]) -> dict[int, int]:
    """Each task cell's site: its one neighbour on ``walk`` outside the task cells (a robot
    stands there to pick or place on it); InstanceError where there is not exactly one."""
    nbr = neighbour_table(inst.width, inst.height)
    site = {}
    for c in sorted(task_set):
        around = [m for m in nbr[c].tolist() if m >= 0 and walk[m] and m not in task_set]
        if len(around) != 1:
            raise InstanceError(f"search_optimum: task cell {inst.world.xy(c)} has {len(around)} tile neighbours, "
                                "not 1")
        site[c] = around[0]
    return site


def _successors(world, graph, s: State, task_set: set[int]):
    """``(action, state)`` of every action of the one robot from ``s`` that the rules allow, its
    picks and places on the task cells only."""
    p = s.poses[0]
    for a in range(graph.num_actions):
        if graph.succ[p, a] < 0:
            continue
        if int(graph.kind[a]) in (Kind.PICK, Kind.PLACE) and int(graph.target[p, a]) not in task_set:
            continue
        new = apply(world, s, [a])
        if isinstance(new, State):
            yield a, new


def search_optimum(inst: Instance, limit: int, *, max_states: int = 2_000_000):
    """An optimal schedule of a one-robot instance if its makespan is at most ``limit``;
    ``None`` when no schedule of at most ``limit`` steps exists. A goal cell of the robot counts.

    Breadth-first over the robot's states under the canonical rules, with picks and places only
    on the cells where start and goal differ (the task cells: a manipulation elsewhere has to be
    undone and is never shorter on these instances, see docs/generators.md), cutting every state
    whose steps so far plus a lower bound on the steps still needed exceed ``limit``. The lower
    bound counts one manipulation per cell that still differs from the goal and the weight of a
    minimum spanning tree joining the robot with the site of every such cell (the one tile a
    robot can stand on next to it) and its goal cell, by walking distances over the start and goal
    tiles together.

    Raises :class:`InstanceError` for more than one robot, a robot that is not ``point``, or a
    task cell with other than one tile neighbour, and when ``max_states`` are stored.
    """
    if inst.num_robots != 1 or inst.movesets[0].footprint != "point":
        raise InstanceError("search_optimum: one point robot only")
    world = inst.world
    graph = world.graphs[0]
    start_tiles, goal = inst.start.tiles, inst.goal_tiles
    walk = start_tiles | goal
    task_set = {int(c) for c in np.flatnonzero(start_tiles != goal)}
    site = _sites(inst, walk, task_set)
    # a point robot's pose is its cell, and its walks are symmetric: distances from a site
    walking = Walk(graph, walk)
    end = int(inst.goal_cells[0])
    ends = [end] if end >= 0 else []
    dist = {q: walking.distances(q) for q in set(site.values()) | set(ends)}

    def h(state: State) -> int:
        differ = [c for c in task_set if state.tiles[c] != goal[c]]
        need = sorted({site[c] for c in differ} | set(ends))
        return len(differ) + _mst([state.poses[0]] + need, dist)

    def done(state: State) -> bool:
        return (not state.carrying[0] and np.array_equal(state.tiles, goal)
                and (end < 0 or state.poses[0] == end))

    root = inst.start_state
    if h(root) > limit:
        return None
    parent = {root.key(): None}
    frontier, depth = [root], 0
    while frontier:
        for s in frontier:
            if done(s):
                return Schedule.from_ids(inst, [_unwind(parent, s)], meta={"method": "search"})
        if depth == limit:
            return None
        nxt = []
        for s in frontier:
            for a, new in _successors(world, graph, s, task_set):
                key = new.key()
                if key in parent or depth + 1 + h(new) > limit:
                    continue
                parent[key] = (s.key(), a)
                nxt.append(new)
                if len(parent) > max_states:
                    raise InstanceError(f"search_optimum: more than {max_states} states (a smaller instance)")
        frontier, depth = nxt, depth + 1
    return None


def _mst(points: list, dist: dict) -> int:
    """Prim's minimum spanning tree weight; ``points[0]`` is the robot, the rest are sites."""
    if len(points) <= 1:
        return 0
    best = {q: int(dist[q][points[0]]) for q in points[1:]}
    total = 0
    while best:
        q = min(best, key=best.get)
        total += best.pop(q)
        for r in best:
            best[r] = min(best[r], int(dist[q][r]))
    return total


def _unwind(parent: dict, state: State) -> list[int]:
    actions, key = [], state.key()
    while parent[key] is not None:
        key, a = parent[key]
        actions.append(a)
    return actions[::-1]
