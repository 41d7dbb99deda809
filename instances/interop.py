"""Other tools' formats, both ways: MovingAI maps and scenarios (Sturtevant 2012) and the YAML of
libMultiRobotPlanning (Hönig et al.): ``map: {dimensions, obstacles}``, ``agents: [{name, start,
goal}]``, and schedules as ``schedule: {agent: [{x, y, t}, ...]}``.

Both formats describe point robots walking on a fixed grid, so only such instances fit: every
robot ``point``, a goal cell for each, no tile that moves, none carried. Cells map as follows: a
tile is a free cell, anything else blocked; read back, free cells are tiles and blocked cells
obstacles (the largest 4-connected part of the free cells stays tiles, as in ``bille gen
movingai``). Coordinates are ``(x, y)`` with ``y`` the row from the top, as in every format here.
"""
from __future__ import annotations

from collections import deque
from pathlib import Path

import numpy as np

from .errors import InstanceError, ScheduleError
from .grid import Grid, detached_cells
from .instance import Instance, Robot, check_instance
from .moveset import load_moveset
from .rules import run
from .schedule import Schedule, bind

MOVES = {(0, 0): "wait", (0, -1): "north", (1, 0): "east", (0, 1): "south", (-1, 0): "west"}


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
    if why:
        raise InstanceError(f"instance '{inst.name}' cannot be written as {fmt}: {why}")


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
    """The robots as a MovingAI ``.scen`` (bucket 0; the last field is the shortest walk)."""
    check_portable(inst, "a MovingAI scenario")
    starts, goals = _cells(inst)
    lines = ["version 1"]
    for s, g in zip(starts, goals):
        length = _walk(inst, s, g)
        lines.append("\t".join(map(str, (0, map_name, inst.width, inst.height, *s, *g, length))))
    return "\n".join(lines) + "\n"


def _walk(inst: Instance, s, g) -> int:
    W, tiles = inst.width, inst.start.tiles
    dist = {s: 0}
    todo = deque([s])
    while todo:
        x, y = todo.popleft()
        if (x, y) == g:
            return dist[(x, y)]
        for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            n = (x + dx, y + dy)
            if 0 <= n[0] < W and 0 <= n[1] < inst.height and tiles[n[1] * W + n[0]] and n not in dist:
                dist[n] = dist[(x, y)] + 1
                todo.append(n)
    return -1


# ---- libMultiRobotPlanning ----------------------------------------------------------------------


def to_mrp(inst: Instance) -> dict:
    """The instance as libMultiRobotPlanning's YAML data."""
    check_portable(inst, "libMultiRobotPlanning YAML")
    starts, goals = _cells(inst)
    blocked = np.flatnonzero(~inst.start.tiles).tolist()
    return {"map": {"dimensions": [inst.width, inst.height],
                    "obstacles": [[c % inst.width, c // inst.width] for c in blocked]},
            "agents": [{"name": f"agent{i}", "start": list(s), "goal": list(g)}
                       for i, (s, g) in enumerate(zip(starts, goals))]}


def is_mrp(data) -> bool:
    return isinstance(data, dict) and "map" in data and "agents" in data


def from_mrp(data: dict, name: str, where: str = "") -> Instance:
    """An instance from libMultiRobotPlanning's YAML data (classic collisions, point robots)."""
    def fail(msg):
        raise InstanceError(f"{where}: {msg}" if where else msg)

    try:
        width, height = (int(v) for v in data["map"]["dimensions"])
        obstacles = [tuple(int(v) for v in xy) for xy in data["map"].get("obstacles") or []]
        agents = [(tuple(int(v) for v in a["start"]), tuple(int(v) for v in a["goal"])) for a in data["agents"]]
    except (KeyError, TypeError, ValueError):
        fail("expected map: {dimensions: [W, H], obstacles: [[x, y], ...]} and agents: [{name, start: [x, y], "
             "goal: [x, y]}, ...]")
    if width < 1 or height < 1 or not agents:
        fail("the map needs positive dimensions and at least one agent")
    free = np.ones(width * height, dtype=bool)
    for x, y in obstacles:
        if not (0 <= x < width and 0 <= y < height):
            fail(f"obstacle ({x}, {y}) is outside the {width}x{height} map")
        free[y * width + x] = False
    tiles = free.copy()
    tiles[detached_cells(free, width, height)] = False
    for k, (s, g) in enumerate(agents):
        for what, (x, y) in (("start", s), ("goal", g)):
            if not (0 <= x < width and 0 <= y < height and tiles[y * width + x]):
                fail(f"agent {k}'s {what} ({x}, {y}) is not a free cell of the map's largest connected part")
    grid = Grid.from_masks(width, height, ~free, tiles)
    inst = Instance(name, load_moveset("point"), grid, tuple(Robot(s) for s, _ in agents),
                    robot_goals=tuple(g for _, g in agents), collisions="classic", meta={"source": "libMultiRobotPlanning"})
    return check_instance(inst)


def schedule_to_mrp(inst: Instance, schedule: Schedule) -> dict:
    """A schedule as libMultiRobotPlanning's ``schedule`` (every robot's cell at every time)."""
    check_portable(inst, "a libMultiRobotPlanning schedule")
    ids = bind(inst, schedule)
    states = [inst.start_state]
    for st in run(inst.world, inst.start_state, ids):
        if not hasattr(st, "poses"):
            raise ScheduleError(f"the schedule breaks a rule: {st}")
        states.append(st)
    cells = [[inst.world.xy(inst.world.graphs[i].feet[st.poses[i]][0]) for st in states]
             for i in range(inst.num_robots)]
    makespan = len(states) - 1
    cost = sum(next((t for t in range(makespan, -1, -1) if path[t] != path[-1]), -1) + 1 for path in cells)
    return {"statistics": {"cost": cost, "makespan": makespan},
            "schedule": {f"agent{i}": [{"x": x, "y": y, "t": t} for t, (x, y) in enumerate(path)]
                         for i, path in enumerate(cells)}}


def schedule_from_mrp(inst: Instance, data: dict, where: str = "") -> Schedule:
    """A schedule from libMultiRobotPlanning's ``schedule`` of agents ``agent0 .. agentN``
    (or in the order given): unit moves between consecutive times, waits where a time is skipped
    and after an agent's last entry."""
    def fail(msg):
        raise ScheduleError(f"{where}: {msg}" if where else msg)

    check_portable(inst, "a libMultiRobotPlanning schedule")
    plans = data.get("schedule") if isinstance(data, dict) else None
    if not isinstance(plans, dict) or len(plans) != inst.num_robots:
        fail(f"expected schedule: with one entry per agent ({inst.num_robots})")
    paths = []
    for name, entries in plans.items():
        try:
            timed = sorted((int(e["t"]), (int(e["x"]), int(e["y"]))) for e in entries)
        except (KeyError, TypeError, ValueError):
            fail(f"agent {name}: expected a list of {{x, y, t}}")
        paths.append((name, timed))
    makespan = max(timed[-1][0] for _, timed in paths)
    rows = []
    for name, timed in paths:
        at = dict(timed)
        cell, row = timed[0][1], []
        for t in range(1, makespan + 1):
            nxt = at.get(t, cell)
            move = MOVES.get((nxt[0] - cell[0], nxt[1] - cell[1]))
            if move is None:
                fail(f"agent {name}: from {cell} to {nxt} at time {t} is not one step")
            row.append(move)
            cell = nxt
        rows.append(tuple(row))
    return Schedule(tuple(rows), meta={"source": "libMultiRobotPlanning"})


def mrp_name(path: str | Path) -> bool:
    """Whether a file name asks for libMultiRobotPlanning YAML (``*.mrp.yaml``)."""
    return Path(path).name.endswith((".mrp.yaml", ".mrp.yml"))
