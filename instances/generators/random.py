"""Random and paper-style instances: ``bille gen random``, ``crowded`` and ``corridor``.

Every generator takes a seed and is deterministic (one :class:`random.Random` per call, sets
iterated in sorted order). Instances come out checked (:func:`~bille.instances.check_instance`).

- :func:`random_reconfiguration`: a random connected polyomino, robots on it, and a goal that
  differs in exactly ``moved`` tiles, made by ``moved`` single-tile moves each of which keeps the
  structure connected; those moves, in order, are the optional task list (a valid reconfiguration
  sequence: executed one at a time, every pick and every place leaves the tiles connected).
- :func:`crowded`: the planner comparison's kind of map: robots packed into a small structure
  with holes, each with the goal cell of another robot, so that they must get past each other.
- :func:`corridor`: the load-transfer maps' kind: two rooms joined by a one-tile-wide corridor;
  robots start in both rooms and either swap rooms (path planning) or carry ``moved`` tiles from
  the left room's outer column to the right room's outer side (reconfiguration).
"""
from __future__ import annotations

import bisect
import random

import numpy as np

from ..errors import InstanceError
from ..grid import Grid, articulation_points, may_pick, neighbour_table
from ..instance import Instance, Robot, Task, check_instance
from ..limits import check_size
from ..moveset import load_moveset
from ..posegraph import compile_posegraph
from ..walking import UNREACHABLE, runnable, walk_for

XY = tuple[int, int]
_STEPS = ((1, 0), (-1, 0), (0, 1), (0, -1))


def random_reconfiguration(width: int, height: int, tiles: int, robots: int, moved: int, *, seed: int = 0,
                           moveset: str = "S7", tasks: bool = False, name: str | None = None) -> Instance:
    """A random reconfiguration instance (see the module docstring).

    Raises :class:`InstanceError` when the numbers cannot fit: more tiles than cells, robots
    that do not find room, more moved tiles than can move.
    """
    _positive(width=width, height=height, tiles=tiles)
    check_size([load_moveset(moveset)], width, height, "gen random")
    if robots < 0 or moved < 0:
        raise InstanceError(f"robots and moved must be at least 0, got {robots} and {moved}")
    if tiles > width * height:
        raise InstanceError(f"{tiles} tiles do not fit a {width}x{height} grid ({width * height} cells)")
    rnd = random.Random(seed)
    ms = load_moveset(moveset)
    start = _polyomino(width, height, tiles, rnd)
    placed = _place_robots(start, width, height, robots, ms.footprint, rnd)
    held = {c for r in placed for c in _feet(r)}
    graph = compile_posegraph(ms, width, height, np.zeros(width * height, dtype=bool))
    now = start.copy()
    sequence: list[Task] = []
    for k in range(moved):
        move = _random_move(now, start, held, width, height, graph, rnd)
        if move is None:
            raise InstanceError(f"cannot move {moved} tiles of {tiles} on a {width}x{height} grid with {robots} "
                                f"robots: only {k} moves keep the structure connected (fewer --moved, more room)")
        pick, place = move
        now[pick], now[place] = False, True
        sequence.append(Task((pick % width, pick // width), (place % width, place // width)))
    zeros = np.zeros(width * height, dtype=bool)
    inst = Instance(name or f"random-{width}x{height}-t{tiles}-r{robots}-m{moved}-s{seed}", ms,
                    Grid.from_masks(width, height, zeros, start), tuple(placed),
                    goal=Grid.from_masks(width, height, zeros, now), tasks=tuple(sequence) if tasks else None,
                    meta={"generator": "random", "seed": seed, "moved": moved})
    return check_instance(inst)


def crowded(width: int, height: int, robots: int, *, holes: float = 0.1, seed: int = 0, moveset: str = "S7",
            name: str | None = None) -> Instance:
    """Robots packed on a ``width x height`` block with a fraction ``holes`` of it missing (kept
    connected); robot ``i``'s goal cell is robot ``i + 1``'s start front foot (cyclically), so
    every robot must get past others. Every goal is reachable by its robot walking alone."""
    _positive(width=width, height=height, robots=robots)
    check_size([load_moveset(moveset)], width, height, "gen crowded")
    if not 0 <= holes < 0.5:
        raise InstanceError(f"holes must lie in [0, 0.5), got {holes}")
    if robots < 2:
        raise InstanceError("a crowded map needs at least 2 robots")
    ms = load_moveset(moveset)
    rnd = random.Random(seed)
    n = width * height
    crowded_out = 0
    for _attempt in range(200):
        tiles = np.ones(n, dtype=bool)
        for c in rnd.sample(range(n), int(holes * n)):
            if may_pick(tiles, width, height, c):  # keeps the rest connected
                tiles[c] = False
        try:
            placed = _place_robots(tiles, width, height, robots, ms.footprint, rnd)
        except InstanceError:
            crowded_out += 1
            if crowded_out >= 10:  # the robots do not fit, whatever the holes: say so now
                break
            continue
        goals = tuple(placed[(i + 1) % robots].front for i in range(robots))
        zeros = np.zeros(n, dtype=bool)
        inst = Instance(name or f"crowded-{width}x{height}-r{robots}-s{seed}", ms, Grid.from_masks(width, height, zeros, tiles),
                        tuple(placed), robot_goals=goals, meta={"generator": "crowded", "seed": seed})
        if _goals_reachable(inst):
            return check_instance(inst)
    raise InstanceError(f"no crowded {width}x{height} map with {robots} robots found in {_attempt + 1} tries "
                        f"(more room, fewer robots or fewer holes)")


def corridor(length: int, robots: int, *, room: int = 3, moved: int = 0, seed: int = 0, moveset: str = "S7",
             name: str | None = None) -> Instance:
    """Two ``room x room`` rooms of tiles joined by a one-tile-wide corridor of ``length`` tiles.

    Robots alternate between the rooms (robot 0 left). With ``moved == 0`` each robot's goal is a
    cell of the other room (head-on meetings in the corridor); otherwise ``moved`` tiles of the
    left room's outer column move to a column beyond the right room, and robots have no goals.
    """
    _positive(length=length, robots=robots, room=room)
    if room < 2:
        raise InstanceError(f"rooms must be at least 2x2, got {room}")
    if moved > room:
        raise InstanceError(f"at most {room} tiles can move (one column of a room), got {moved}")
    ms = load_moveset(moveset)
    rnd = random.Random(seed)
    width, height = 2 * room + length + 3, room + 2
    check_size([ms], width, height, "gen corridor")
    left = [(1 + x, 1 + y) for y in range(room) for x in range(room)]
    right = [(1 + room + length + x, 1 + y) for y in range(room) for x in range(room)]
    mid = 1 + room // 2
    hall = [(1 + room + k, mid) for k in range(length)]
    tiles = np.zeros(width * height, dtype=bool)
    for x, y in left + right + hall:
        tiles[y * width + x] = True
    goal = tiles.copy()
    if moved:
        rows = sorted(rnd.sample(range(room), moved))
        for y in rows:
            goal[(1 + y) * width + 1] = False
            goal[(1 + y) * width + 1 + 2 * room + length] = True
    sides = (left, right)
    placed: list[Robot] = []
    used: set[XY] = {(1, 1 + y) for y in range(room)} if moved else set()  # keep the moving column free
    for i in range(robots):
        robot = _robot_in(sides[i % 2], used, ms.footprint, rnd, heading=1 if i % 2 == 0 else -1)
        if robot is None:
            who = "1 robot does" if robots == 1 else f"{robots} robots do"
            kept = " with the moving tiles' column kept free" if moved else ""
            raise InstanceError(f"{who} not fit two {room}x{room} rooms{kept} (larger --room, fewer robots)")
        placed.append(robot)
        used |= set(_feet(robot)) | _neighbours(robot.front)
    goals = None
    if not moved:
        goals = []
        taken: set[XY] = set()
        for i in range(robots):
            other = sorted(set(sides[(i + 1) % 2]) - taken)
            goals.append(rnd.choice(other))
            taken.add(goals[-1])
        goals = tuple(goals)
    zeros = np.zeros(width * height, dtype=bool)
    inst = Instance(name or f"corridor-l{length}-r{robots}-m{moved}-s{seed}", ms, Grid.from_masks(width, height, zeros, tiles),
                    tuple(placed), goal=Grid.from_masks(width, height, zeros, goal) if moved else None,
                    robot_goals=goals, meta={"generator": "corridor", "seed": seed})
    return check_instance(inst)


# ---- pieces -----------------------------------------------------------------------------------

def _positive(**values) -> None:
    for key, v in values.items():
        if v < 1:
            raise InstanceError(f"{key} must be at least 1, got {v}")


def _polyomino(width: int, height: int, count: int, rnd: random.Random) -> np.ndarray:
    """A random connected set of ``count`` cells grown from the grid's centre: each new cell is
    drawn from the empty cells beside the set, each as often as it has tiles beside it (a
    Fenwick tree of those counts by cell, so a draw costs O(log cells), not a pass over the set)."""
    tiles = np.zeros(width * height, dtype=bool)
    beside = _Counts(width * height)

    def grow(c: int) -> None:
        tiles[c] = True
        beside.set(c, 0)
        for n in _around(c, width, height):
            if not tiles[n]:
                beside.set(n, beside.count[n] + 1)

    grow((height // 2) * width + width // 2)
    for _ in range(count - 1):
        if not beside.total:
            raise InstanceError(f"{count} tiles do not fit the grid")
        grow(beside.find(rnd.choice(range(beside.total))))
    return tiles


class _Counts:
    """Counts per index with prefix sums (a Fenwick tree): :meth:`find` is the index that holds
    the ``k``-th entry (0-based) when every index ``i`` is listed ``count[i]`` times in order."""

    def __init__(self, n: int) -> None:
        self.count = [0] * n
        self.tree = [0] * (n + 1)
        self.total = 0

    def set(self, i: int, value: int) -> None:
        delta = value - self.count[i]
        if delta:
            self.count[i] = value
            self.total += delta
            i += 1
            while i < len(self.tree):
                self.tree[i] += delta
                i += i & -i

    def find(self, k: int) -> int:
        pos, bit = 0, 1 << (len(self.tree) - 1).bit_length()
        while bit:
            nxt = pos + bit
            if nxt < len(self.tree) and self.tree[nxt] <= k:
                pos, k = nxt, k - self.tree[nxt]
            bit >>= 1
        return pos


def _around(c: int, width: int, height: int) -> list[int]:
    x, y = c % width, c // width
    return [(y + dy) * width + x + dx for dx, dy in _STEPS if 0 <= x + dx < width and 0 <= y + dy < height]


def _feet(r: Robot) -> list[XY]:
    return [r.front] if r.back is None else [r.front, r.back]


def _neighbours(xy: XY) -> set[XY]:
    return {(xy[0] + dx, xy[1] + dy) for dx, dy in _STEPS}


def _place_robots(tiles: np.ndarray, width: int, height: int, count: int, footprint: str,
                  rnd: random.Random) -> list[Robot]:
    """``count`` robots on distinct tiles (bipeds: two adjacent tiles), with a free cell between
    robots so that the start is not a deadlock by construction."""
    cells = [(c % width, c // width) for c in np.flatnonzero(tiles).tolist()]
    placed: list[Robot] = []
    used: set[XY] = set()
    free = sorted(cells)  # point robots: the free cells, kept sorted as they are taken
    for _ in range(count):
        if footprint == "point":
            robot = Robot(rnd.choice(free)) if free else None
        else:
            robot = _robot_in(cells, used, footprint, rnd)
        if robot is None:
            raise InstanceError(f"{'1 robot does' if count == 1 else f'{count} robots do'} not fit on {len(cells)} tiles")
        placed.append(robot)
        taken = (set(_feet(robot)) | _neighbours(robot.front)) - used
        used |= taken
        for xy in taken:
            k = bisect.bisect_left(free, xy)
            if k < len(free) and free[k] == xy:
                del free[k]
    return placed


def _robot_in(cells: list[XY], used: set[XY], footprint: str, rnd: random.Random, heading: int = 0) -> Robot | None:
    free = set(cells) - used
    if footprint == "point":
        options = sorted(free)
        return Robot(rnd.choice(options)) if options else None
    steps = ((heading, 0),) if heading else _STEPS
    pairs = [((x, y), (x - dx, y - dy)) for x, y in sorted(free) for dx, dy in steps if (x - dx, y - dy) in free]
    return Robot(*rnd.choice(pairs)) if pairs else None


def _random_move(now: np.ndarray, start: np.ndarray, held: set, width: int, height: int, graph,
                 rnd: random.Random) -> tuple[int, int] | None:
    """A tile of the start still in place that may be picked, and an empty cell never a start
    tile next to the rest, so that every move adds one to the difference; a robot of ``graph``
    must be able to pick the tile and carry it to face the place."""
    nbr = neighbour_table(width, height)
    cut = articulation_points(now, width, height)
    picks = [c for c in np.flatnonzero(now & start & ~cut).tolist() if (c % width, c // width) not in held]
    rnd.shuffle(picks)
    for pick in picks:
        rest = now.copy()
        rest[pick] = False
        places = sorted({c2 for c in np.flatnonzero(rest).tolist() for c2 in _around(c, width, height)
                         if not rest[c2] and not start[c2]})
        rnd.shuffle(places)
        for place in places:
            if runnable(now, cut, pick, place, nbr, graph, width, height):
                return pick, place
    return None


def _goals_reachable(inst: Instance) -> bool:
    """Whether every robot can walk alone to its goal cell: at once where a pose with the front
    foot on the goal is in the start pose's strongly connected component, else by search."""
    tiles = inst.start.tiles
    for i, (g, goal) in enumerate(zip(inst.world.graphs, inst.robot_goals)):
        walk = walk_for(g, tiles)
        pose = inst.start_state.poses[i]
        cell = goal[1] * inst.width + goal[0]
        comp = walk.components()
        if (comp[(g.feet[:, 0] == cell) & walk.standing] == comp[pose]).any():
            continue
        if walk.distances(cell)[pose] >= UNREACHABLE:
            return False
    return True
