"""Other tools' formats, both ways: MovingAI maps and scenarios (Sturtevant 2012) and the YAML of
libMultiRobotPlanning (Hönig et al.): ``map: {dimensions, obstacles}``, ``agents: [{name, start,
goal}]``, and schedules as ``statistics: {cost, makespan}`` and ``schedule: {agent: [{x, y, t},
...]}``, each agent's path ending where it last moved, as that library writes them.

Both formats describe point robots walking on a fixed grid, so only such instances fit: every
robot ``point``, a goal cell for each, no tile that moves, none carried. Cells map as follows: a
tile is a free cell, anything else blocked; read back, free cells are tiles and blocked cells
obstacles (the largest 4-connected part of the free cells stays tiles, as in ``bille gen
movingai``). Coordinates are ``(x, y)`` with ``y`` the row from the top, as in every format here.
Agent names read from libMultiRobotPlanning are kept in the instance's ``meta.agents``; without
them agent ``i`` is ``agent{i}``. Anything that is not exactly what a format holds is refused,
naming the file, the line and the field: nothing is rounded or dropped.
"""
from __future__ import annotations

import heapq
import math
from pathlib import Path

import numpy as np

from .errors import InstanceError, ScheduleError
from .grid import Grid
from .instance import Instance, Robot, check_instance
from .limits import check_budget, check_size
from .moveset import load_moveset
from .rules import run
from .schedule import Schedule, bind, identity
from .yamlsource import Source, expect_list, expect_mapping, expect_str, expect_xy

MOVES = {(0, 0): "wait", (0, -1): "north", (1, 0): "east", (0, 1): "south", (-1, 0): "west"}
# bytes per robot and step of a schedule while it is read and checked (names, ids, states)
STEP_BYTES = 64


def check_portable(inst: Instance, fmt: str) -> None:
    """Raise :class:`InstanceError` naming what ``fmt`` cannot hold."""
    why = None
    if any(ms.footprint != "point" for ms in inst.movesets):
        why = "its robots are two-footed (only point robots fit)"
    elif inst.is_reconfiguration:
        why = "its tiles move (only path planning on a fixed grid fits)"
    elif any(r.carrying for r in inst.robots):
        why = "a robot carries a tile"
    elif inst.robot_goals is None or any(g is None for g in inst.robot_goals):
        why = "a robot has no goal cell (every agent needs one)"
    elif inst.collisions != "classic":
        why = ("it uses the Bill-E collision rule, and the format means classic MAPF collisions (a robot may "
               "follow another): read back, it would be another problem with another optimum")
    if why:
        raise InstanceError(f"instance '{inst.name}' cannot be written as {fmt}: {why}")


def agent_names(inst: Instance) -> list[str]:
    """The agents' names: ``meta.agents`` when it names each robot once, else ``agent0 ..``."""
    names = (inst.meta or {}).get("agents")
    if isinstance(names, list) and len(names) == inst.num_robots and len(set(names)) == len(names) \
            and all(isinstance(n, str) and n for n in names):
        return list(names)
    return [f"agent{i}" for i in range(inst.num_robots)]


def check_steps(robots: int, steps: int, what: str, error=ScheduleError) -> None:
    """Refuse, before anything is built, a schedule of ``steps`` steps that cannot fit."""
    check_budget(robots * max(steps, 0) * STEP_BYTES,
                 lambda size: f"{what}: {robots} robots x {steps} steps need about {size}", error)


def _cells(inst: Instance):
    starts = [inst.world.xy(inst.world.graphs[i].feet[p][0]) for i, p in enumerate(inst.start_state.poses)]
    return starts, [tuple(g) for g in inst.robot_goals]


# ---- MovingAI ---------------------------------------------------------------------------------


def map_text(inst: Instance) -> str:
    """The instance's grid as a MovingAI ``.map``: tiles ``.``, every other cell ``@``."""
    check_portable(inst, "a MovingAI map")
    tiles = inst.start.tiles.reshape(inst.height, inst.width)
    rows = ["".join("." if t else "@" for t in row) for row in tiles]
    return f"type octile\nheight {inst.height}\nwidth {inst.width}\nmap\n" + "\n".join(rows) + "\n"


def scen_text(inst: Instance, map_name: str) -> str:
    """The robots as a MovingAI ``.scen``, as the benchmark writes them: the optimal length is
    the octile shortest path on the map (:func:`octile_distance`), the bucket its quarter."""
    check_portable(inst, "a MovingAI scenario")
    starts, goals = _cells(inst)
    free = inst.start.tiles
    lines = ["version 1"]
    for s, g in zip(starts, goals):
        length = octile_distance(free, inst.width, inst.height, s, g)
        lines.append("\t".join(map(str, (int(length // 4), map_name, inst.width, inst.height, *s, *g,
                                         f"{length:.8f}"))))
    return "\n".join(lines) + "\n"


def octile_distance(free: np.ndarray, width: int, height: int, s, g) -> float:
    """The shortest path from ``s`` to ``g`` over ``free`` cells with straight steps of 1 and
    diagonal steps of sqrt(2), a diagonal only where both cells beside it are free (no corner
    cutting, MovingAI's rule); ``inf`` if there is none."""
    diag = math.sqrt(2)
    best = {s: 0.0}
    todo = [(0.0, s)]
    ok = lambda x, y: 0 <= x < width and 0 <= y < height and free[y * width + x]  # noqa: E731
    while todo:
        d, (x, y) = heapq.heappop(todo)
        if (x, y) == g:
            return d
        if d > best[(x, y)]:
            continue
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                n = (x + dx, y + dy)
                if (dx or dy) and ok(*n) and (not (dx and dy) or (ok(x + dx, y) and ok(x, y + dy))):
                    nd = d + (diag if dx and dy else 1.0)
                    if nd < best.get(n, math.inf):
                        best[n] = nd
                        heapq.heappush(todo, (nd, n))
    return math.inf


# ---- libMultiRobotPlanning ----------------------------------------------------------------------


def to_mrp(inst: Instance) -> dict:
    """The instance as libMultiRobotPlanning's YAML data."""
    check_portable(inst, "libMultiRobotPlanning YAML")
    starts, goals = _cells(inst)
    blocked = np.flatnonzero(~inst.start.tiles).tolist()
    return {"map": {"dimensions": [inst.width, inst.height],
                    "obstacles": [[c % inst.width, c // inst.width] for c in blocked]},
            "agents": [{"name": n, "start": list(s), "goal": list(g)}
                       for n, s, g in zip(agent_names(inst), starts, goals)]}


def is_mrp(data) -> bool:
    return isinstance(data, dict) and "map" in data and "agents" in data


def _int(value, src: Source, path, what: str = "a whole number") -> int:
    if not isinstance(value, int) or isinstance(value, bool):
        raise src.fail(path, f"expected {what}, got {value!r}"[:200])
    return value


def from_mrp(data: dict, name: str, src: Source | str | None = None) -> Instance:
    """An instance from libMultiRobotPlanning's YAML data (classic collisions, point robots);
    ``src`` locates errors (a :class:`Source`, or a file name)."""
    if not isinstance(src, Source):
        src = Source(src or None, InstanceError)
    top = expect_mapping(data, src, (), required=("map", "agents"))
    mp = expect_mapping(top["map"], src, ("map",), required=("dimensions",), optional=("obstacles",))
    width, height = expect_xy(mp["dimensions"], src, ("map", "dimensions"))
    if width < 1 or height < 1:
        raise src.fail(("map", "dimensions"), f"expected positive [width, height], got [{width}, {height}]")
    check_size([load_moveset("point")], width, height, src.at(("map", "dimensions")).rstrip(": ") or name)
    free = np.ones(width * height, dtype=bool)
    obstacles = expect_list(mp.get("obstacles") or [], src, ("map", "obstacles"), "a list of [x, y]")
    for k, xy in enumerate(obstacles):
        x, y = expect_xy(xy, src, ("map", "obstacles", k))
        if not (0 <= x < width and 0 <= y < height):
            raise src.fail(("map", "obstacles", k), f"({x}, {y}) is outside the {width}x{height} map")
        if not free[y * width + x]:
            raise src.fail(("map", "obstacles", k), f"({x}, {y}) is listed twice")
        free[y * width + x] = False
    tiles = free.copy()  # every free cell, in as many parts as the map has: classic collisions allow it
    agents = expect_list(top["agents"], src, ("agents",), "a list of agents")
    if not agents:
        raise src.fail(("agents",), "expected at least one agent")
    names, cells = [], []
    for k, agent in enumerate(agents):
        a = expect_mapping(agent, src, ("agents", k), required=("name", "start", "goal"))
        nm = expect_str(a["name"], src, ("agents", k, "name"), "the agent's name")
        if nm in names:
            raise src.fail(("agents", k, "name"), f"agent name {nm!r} is given twice")
        names.append(nm)
        pair = []
        for what in ("start", "goal"):
            x, y = expect_xy(a[what], src, ("agents", k, what))
            if not (0 <= x < width and 0 <= y < height and tiles[y * width + x]):
                raise src.fail(("agents", k, what), f"({x}, {y}) is not a free cell of the map")
            pair.append((x, y))
        cells.append(pair)
    for j, what in enumerate(("start", "goal")):  # said in the file's terms, before the instance's own checks
        seen: dict = {}
        for k, pair in enumerate(cells):
            if pair[j] in seen:
                raise src.fail(("agents", k, what), f"{pair[j]} is also the {what} of agent {names[seen[pair[j]]]}")
            seen[pair[j]] = k
    grid = Grid.from_masks(width, height, ~free, tiles)
    meta = {"source": "libMultiRobotPlanning"}
    if names != [f"agent{i}" for i in range(len(names))]:
        meta["agents"] = names
    inst = Instance(name, load_moveset("point"), grid, tuple(Robot(s) for s, _ in cells),
                    robot_goals=tuple(g for _, g in cells), collisions="classic", meta=meta)
    return check_instance(inst)


def _paths(inst: Instance, schedule: Schedule) -> list[list[tuple[int, int]]]:
    ids = bind(inst, schedule)
    states = [inst.start_state]
    for st in run(inst.world, inst.start_state, ids):
        if not hasattr(st, "poses"):
            raise ScheduleError(f"the schedule breaks a rule: {st}")
        states.append(st)
    return [[inst.world.xy(inst.world.graphs[i].feet[st.poses[i]][0]) for st in states]
            for i in range(inst.num_robots)]


def schedule_to_mrp(inst: Instance, schedule: Schedule) -> dict:
    """A schedule as libMultiRobotPlanning writes one: each agent's cell at every time up to its
    last move (it stays there), and the statistics ``cost`` (the sum of those times) and
    ``makespan`` (their largest); ``runtime`` and ``highLevelExpanded`` where the schedule's
    metadata has the planner's ``time_s`` and ``expansions``."""
    check_portable(inst, "a libMultiRobotPlanning schedule")
    paths = []
    for path in _paths(inst, schedule):
        last = next((t for t in range(len(path) - 1, 0, -1) if path[t] != path[t - 1]), 0)
        paths.append(path[: last + 1])
    stats = {"cost": sum(len(p) - 1 for p in paths), "makespan": max((len(p) - 1 for p in paths), default=0)}
    meta = schedule.meta or {}
    for ours, theirs in (("time_s", "runtime"), ("expansions", "highLevelExpanded")):
        if isinstance(meta.get(ours), (int, float)) and not isinstance(meta[ours], bool):
            stats[theirs] = meta[ours]
    return {"statistics": stats,
            "schedule": {n: [{"x": x, "y": y, "t": t} for t, (x, y) in enumerate(path)]
                         for n, path in zip(agent_names(inst), paths)}}


def schedule_from_mrp(inst: Instance, data: dict, src: Source | str | None = None) -> Schedule:
    """A schedule from libMultiRobotPlanning's ``schedule``: one entry per agent of the instance
    (by name), each a list of ``{x, y, t}`` with ``t`` from 0 (the agent's start) strictly
    increasing; unit moves between consecutive entries, waits where a time is skipped and after
    an agent's last entry. Agents keyed ``agent0``, ``agent1``, ... where the instance names them
    otherwise are taken by index, as libMultiRobotPlanning's ``cbs`` writes them, and the
    schedule's ``meta["agents"]`` says so."""
    if not isinstance(src, Source):
        src = Source(src or None, ScheduleError)
    check_portable(inst, "a libMultiRobotPlanning schedule")
    top = expect_mapping(data, src, (), required=("schedule",), optional=("statistics",))
    plans = top["schedule"]
    if not isinstance(plans, dict):
        raise src.fail(("schedule",), "expected a mapping of agent names to paths")
    names = agent_names(inst)
    by_index = [f"agent{i}" for i in range(len(names))]
    keyed_by_index = names != by_index and set(plans) == set(by_index) and set(plans) != set(names)
    if keyed_by_index:  # libMultiRobotPlanning's cbs names agents by their place in the file
        plans = {names[int(key[5:])]: path for key, path in plans.items()}
    for key in plans:
        if key not in names:
            raise src.fail(("schedule", key), f"agent {key!r} is not an agent of instance '{inst.name}' (its agents: "
                                              f"{', '.join(names[:5])}{' ...' if len(names) > 5 else ''})")
    missing = [n for n in names if n not in plans]
    if missing:
        raise src.fail(("schedule",), f"no path for agent {missing[0]!r}")
    starts, _ = _cells(inst)
    paths = [(name, _timed_path(plans[name], name, tuple(starts[i]), src)) for i, name in enumerate(names)]
    makespan = max(timed[-1][0] for _, timed in paths)
    check_steps(inst.num_robots, makespan, src.at(("schedule",)).rstrip(": ") or "the schedule")
    rows = [_moves(name, timed, makespan, src) for name, timed in paths]
    meta = {"source": "libMultiRobotPlanning"}
    if keyed_by_index:
        meta["agents"] = (f"keyed by index (agent0 .. agent{len(names) - 1}), read in the instance's order "
                          f"({', '.join(names[:3])}{' ...' if len(names) > 3 else ''})")
    return Schedule(tuple(rows), meta=meta, instance=identity(inst))


def _timed_path(entries, name: str, start: tuple, src: Source) -> list[tuple[int, tuple[int, int]]]:
    """One agent's ``{x, y, t}`` entries as ``(t, (x, y))``, checked: from its start at time 0,
    times strictly increasing."""
    entries = expect_list(entries, src, ("schedule", name), "a list of {x, y, t}")
    if not entries:
        raise src.fail(("schedule", name), "an empty path (it starts with {x, y, t: 0} at the agent's start)")
    timed = []
    for k, e in enumerate(entries):
        where = ("schedule", name, k)
        e = expect_mapping(e, src, where, required=("x", "y", "t"))
        x, y, t = (_int(e[c], src, where + (c,)) for c in ("x", "y", "t"))
        if timed and t <= timed[-1][0]:
            raise src.fail(where + ("t",), f"time {t} does not come after time {timed[-1][0]}")
        if not timed and (t != 0 or (x, y) != start):
            raise src.fail(where, f"the path starts at ({x}, {y}) at time {t}; agent {name!r} starts at "
                                  f"{start} at time 0")
        timed.append((t, (x, y)))
    return timed


def _moves(name: str, timed: list, makespan: int, src: Source) -> tuple[str, ...]:
    """An agent's timed cells as ``makespan`` actions: unit moves, waits where a time is
    skipped and after its last entry."""
    cell, row = timed[0][1], []
    for k in range(1, len(timed)):
        (t0, _), (t1, nxt) = timed[k - 1], timed[k]
        move = MOVES.get((nxt[0] - cell[0], nxt[1] - cell[1]))
        if move is None:
            raise src.fail(("schedule", name, k), f"from {cell} at time {t1 - 1} to {nxt} at time {t1} is not "
                                                  "one step")
        row += ["wait"] * (t1 - t0 - 1) + [move]
        cell = nxt
    return tuple(row + ["wait"] * (makespan - len(row)))


