"""Instances: the problem a schedule solves, and the instance file (docs/rules.md, "Valid instances";
docs/files.md, "Instance").

An instance is a start grid (obstacles, tiles), an optional goal grid (omitted: the start's tiles,
a pure path-planning problem), robots with their start poses, an optional front-foot goal cell per
robot, and an optional reconfiguration sequence (``tasks``). It is a frozen record; everything the
rules need (pose graphs, masks, the start state) is derived from it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InstanceError, MovesetError
from .grid import CELL_CHARS, Grid, detached_cells, is_connected
from .moveset import Moveset, load_moveset
from .limits import check_size
from .posegraph import compile_posegraph
from .rules import COLLISIONS, State, World
from .yamlsource import (
    Source,
    expect_bool,
    expect_list,
    expect_mapping,
    expect_str,
    expect_xy,
    load_yaml_file,
    load_yaml_text,
)

XY = tuple[int, int]
TOP_FIELDS = ("name", "moveset", "collisions", "grid", "goal", "robots", "robot_goals", "tasks", "meta")


@dataclass(frozen=True)
class Robot:
    """A robot's start: front and back foot (``point``: ``front`` is its cell, ``back`` None),
    whether it carries a tile, and its own moveset if it differs from the instance's."""

    front: XY
    back: XY | None = None
    carrying: bool = False
    moveset: Moveset | None = None


@dataclass(frozen=True)
class Task:
    """One step of a reconfiguration sequence: pick the tile at ``pick``, place it at ``place``."""

    pick: XY
    place: XY


@dataclass(frozen=True)
class Instance:
    """A reconfiguration (or path-planning) problem. See the module docstring.

    Building one in code does not check it: pass it through :func:`check_instance` (files are
    checked when loaded).
    """

    name: str
    moveset: Moveset
    start: Grid
    robots: tuple[Robot, ...]
    goal: Grid | None = None
    robot_goals: tuple[XY | None, ...] | None = None
    tasks: tuple[Task, ...] | None = None
    meta: dict[str, Any] | None = field(default=None, hash=False)
    collisions: str = "bille"  # or "classic" (docs/rules.md, "Classic collisions", point robots only)

    # ---- derived --------------------------------------------------------------------------

    @property
    def width(self) -> int:
        return self.start.width

    @property
    def height(self) -> int:
        return self.start.height

    @property
    def num_robots(self) -> int:
        return len(self.robots)

    @property
    def goal_grid(self) -> Grid:
        return self.goal if self.goal is not None else self.start

    @property
    def movesets(self) -> tuple[Moveset, ...]:
        """Each robot's moveset."""
        return tuple(r.moveset or self.moveset for r in self.robots)

    @cached_property
    def world(self) -> World:
        """The compiled world: one pose graph per distinct moveset, shared by its robots.
        Raises :class:`InstanceError` if its tables would not fit in memory (:mod:`.limits`)."""
        check_size(self.movesets or (self.moveset,), self.width, self.height, f"instance '{self.name}'")
        graphs = {}
        for ms in self.movesets:
            if ms not in graphs:
                graphs[ms] = compile_posegraph(ms, self.width, self.height, self.start.obstacles)
        return World(self.width, self.height, self.start.obstacles, tuple(graphs[ms] for ms in self.movesets),
                     classic=self.collisions == "classic")

    @cached_property
    def start_state(self) -> State:
        poses = tuple(g.pose_of(r.front, r.back) for g, r in zip(self.world.graphs, self.robots))
        if -1 in poses:
            i = poses.index(-1)
            raise InstanceError(f"{self.name}: robots[{i}]: its feet form no valid pose (see check_instance)")
        return State(self.start.tiles, poses, tuple(r.carrying for r in self.robots))

    @property
    def goal_tiles(self) -> np.ndarray:
        return self.goal_grid.tiles

    @property
    def goal_cells(self) -> tuple[int, ...]:
        """Front-foot goal cell per robot as a cell index, -1 where any cell will do."""
        goals = self.robot_goals or (None,) * self.num_robots
        return tuple(-1 if g is None else self.start.cell(*g) for g in goals)

    @property
    def is_reconfiguration(self) -> bool:
        """Whether tiles must move (goal tiles differ from start tiles, or robots carry tiles)."""
        return bool(np.any(self.start.tiles != self.goal_tiles)) or any(r.carrying for r in self.robots)


# ---------------------------------------------------------------------------------------------
# instance validity (docs/rules.md)


def check_instance(inst: Instance, src: Source | None = None) -> Instance:
    """Check the instance validity rules; raise :class:`InstanceError` naming the field.

    Returns the instance, so that ``check_instance(Instance(...))`` reads as a constructor.
    """
    src = src or Source(None, InstanceError)
    w, h = inst.width, inst.height
    check_size(inst.movesets or (inst.moveset,), w, h, src.at(("grid",)).rstrip(": ") or f"instance '{inst.name}'")
    start, goal = inst.start, inst.goal_grid
    if (goal.width, goal.height) != (w, h):
        raise src.fail(("goal",), f"the goal is {goal.width}x{goal.height}, the start grid {w}x{h}")
    if not np.array_equal(goal.obstacles, start.obstacles):
        x, y = start.xy(int(np.flatnonzero(goal.obstacles != start.obstacles)[0]))
        raise src.fail(("goal",), f"obstacles differ from the start grid's at ({x}, {y})")
    mapf = inst.collisions == "classic" and np.array_equal(goal.tiles, start.tiles)
    for key, grid in (("grid", start), ("goal", goal)):
        # a MAPF map's free cells may fall into parts (docs/decisions.md, "Classic collisions")
        if not mapf and not is_connected(grid.tiles, w, h):
            _disconnected(grid, "start" if key == "grid" else "goal", src, key)

    _check_robots(inst, src)
    _check_robot_goals(inst, src)
    for k, task in enumerate(inst.tasks or ()):
        for part in ("pick", "place"):
            xy = getattr(task, part)
            _inside(xy, start, src, ("tasks", k, part))
            if start.obstacles[start.cell(*xy)]:
                raise src.fail(("tasks", k, part), f"{xy} is an obstacle")
    return inst


def _check_robots(inst: Instance, src: Source) -> None:
    """The collision rules, the robots' start cells (on the grid, apart) and the tile count."""
    if inst.collisions not in COLLISIONS:
        raise src.fail(("collisions",), f"unknown collision rules '{inst.collisions}' (expected one of: "
                                        f"{', '.join(COLLISIONS)})")
    if inst.collisions == "classic" and any(ms.footprint != "point" for ms in inst.movesets):
        raise src.fail(("collisions",), "classic collisions are for point robots only; a moveset here is a biped")
    owners: dict[XY, int] = {}
    for i, (robot, ms) in enumerate(zip(inst.robots, inst.movesets)):
        for cell, part in _occupied(inst, i, robot, ms, src):
            if cell in owners:
                raise src.fail(("robots", i, part), f"{cell} is also occupied by robots[{owners[cell]}]")
            owners[cell] = i
    carried = sum(r.carrying for r in inst.robots)
    n_start, n_goal = int(inst.start.tiles.sum()), int(inst.goal_grid.tiles.sum())
    if n_goal != n_start + carried:
        raise src.fail(("goal",), f"the goal has {n_goal} tiles, but the start has {n_start} tiles "
                                  f"and {carried} carried: {n_start + carried} expected")


def _check_robot_goals(inst: Instance, src: Source) -> None:
    """One goal cell (or null) per robot, each on a goal tile and no two alike."""
    if inst.robot_goals is None:
        return
    if len(inst.robot_goals) != inst.num_robots:
        raise src.fail(("robot_goals",), f"{len(inst.robot_goals)} entries, expected one per robot "
                                         f"({inst.num_robots}; null for no goal)")
    goal, seen = inst.goal_grid, {}
    for i, g in enumerate(inst.robot_goals):
        if g is None:
            continue
        _inside(g, inst.start, src, ("robot_goals", i))
        if not goal.tiles[goal.cell(*g)]:
            raise src.fail(("robot_goals", i),
                           f"{g} is not a tile of the goal structure; a robot's front foot must end on a tile")
        if g in seen:
            raise src.fail(("robot_goals", i), f"{g} is also the goal of robot {seen[g]}")
        seen[g] = i


def _disconnected(grid: Grid, which: str, src: Source, key: str):
    if not grid.tiles.any():
        raise src.fail((key,), f"the {which} has no tiles")
    x, y = grid.xy(detached_cells(grid.tiles, grid.width, grid.height)[0])
    first = src.text_start.get((key,))
    raise src.fail((key,), f"the {which} tiles are not 4-connected: ({x}, {y}) is cut off from the rest",
                   None if first is None else first + y)


def _inside(xy: XY, grid: Grid, src: Source, path) -> None:
    if not grid.inside(*xy):
        raise src.fail(path, f"{xy} is outside the {grid.width}x{grid.height} grid")


def _occupied(inst: Instance, i: int, robot: Robot, ms: Moveset, src: Source):
    """Check one start robot and yield its occupied cells (feet, carried tile) with field names."""
    grid = inst.start
    path = ("robots", i)
    if ms.footprint == "point":
        if robot.back is not None:
            raise src.fail(path, f"a robot with the point moveset '{ms.name}' has one cell: give 'at', not front/back")
        feet = [("at", robot.front)]
    else:
        if robot.back is None:
            raise src.fail(path, f"a robot with the biped moveset '{ms.name}' needs 'front' and 'back'")
        feet = [("front", robot.front), ("back", robot.back)]
    for part, xy in feet:
        _inside(xy, grid, src, path + (part,))
        c = grid.cell(*xy)
        if grid.obstacles[c]:
            raise src.fail(path + (part,), f"{xy} is an obstacle")
        if not grid.tiles[c]:
            raise src.fail(path + (part,), f"{xy} is not a tile (robots stand on tiles)")
    cells = [(xy, part) for part, xy in feet]
    if robot.back is not None:
        (fx, fy), (bx, by) = robot.front, robot.back
        if abs(fx - bx) + abs(fy - by) != 1:
            raise src.fail(path, f"feet {robot.front} and {robot.back} are not 4-adjacent")
        if robot.carrying:
            ahead = (2 * fx - bx, 2 * fy - by)
            if not grid.inside(*ahead) or grid.obstacles[grid.cell(*ahead)]:
                raise src.fail(path + ("carrying",), f"the carried tile would hover at {ahead}, "
                                                     "outside the grid or on an obstacle")
            cells.append((ahead, "carrying"))
    yield from ((xy, part) for xy, part in cells)


# ---------------------------------------------------------------------------------------------
# reading


def load_instance(path: str | Path, *, check: bool = True) -> Instance:
    """Read an instance file and (unless ``check`` is False) check its validity rules.

    Raises :class:`InstanceError` naming the file, line and field for anything wrong. With
    ``check=False`` only the file's form is checked, so that an invalid instance can be shown.
    """
    data, src = load_yaml_file(path, InstanceError)
    inst = parse_instance(data, src, Path(path).parent, default_name=Path(path).stem)
    return check_instance(inst, src) if check else inst


def instance_from_text(text: str, name: str | None = None, base_dir: str | Path | None = None) -> Instance:
    """Parse and check instance YAML given as text (``name`` labels errors)."""
    data, src = load_yaml_text(text, name, InstanceError)
    return check_instance(parse_instance(data, src, base_dir, default_name=name or "instance"), src)


def parse_instance(data, src: Source, base_dir=None, default_name: str = "instance") -> Instance:
    """Build an instance from parsed YAML, checking the file's form (not the validity rules)."""
    top = expect_mapping(data, src, (), required=("grid", "robots"), optional=TOP_FIELDS)
    name = expect_str(top["name"], src, ("name",)) if "name" in top else default_name
    moveset = _moveset(top.get("moveset", "S7"), src, ("moveset",), base_dir)
    start = _grid(top["grid"], src, "grid")
    goal = _grid(top["goal"], src, "goal") if top.get("goal") is not None else None

    robots = []
    for i, raw in enumerate(expect_list(top["robots"], src, ("robots",))):
        path = ("robots", i)
        own = raw.get("moveset") if isinstance(raw, dict) else None
        ms = _moveset(own, src, path + ("moveset",), base_dir) if own is not None else moveset
        if ms.footprint == "point":
            fields = expect_mapping(raw, src, path, required=("at",), optional=("carrying", "moveset"))
            front, back = expect_xy(fields["at"], src, path + ("at",)), None
        else:
            fields = expect_mapping(raw, src, path, required=("front", "back"), optional=("carrying", "moveset"))
            front = expect_xy(fields["front"], src, path + ("front",))
            back = expect_xy(fields["back"], src, path + ("back",))
        carrying = expect_bool(fields["carrying"], src, path + ("carrying",)) if "carrying" in fields else False
        robots.append(Robot(front, back, carrying, ms if own is not None else None))

    robot_goals = None
    if top.get("robot_goals") is not None:
        goals = expect_list(top["robot_goals"], src, ("robot_goals",), "a list of [x, y] or null per robot")
        robot_goals = tuple(None if g is None else expect_xy(g, src, ("robot_goals", k)) for k, g in enumerate(goals))
    tasks = None
    if top.get("tasks") is not None:
        tasks = []
        for k, raw in enumerate(expect_list(top["tasks"], src, ("tasks",))):
            fields = expect_mapping(raw, src, ("tasks", k), required=("pick", "place"))
            tasks.append(Task(expect_xy(fields["pick"], src, ("tasks", k, "pick")),
                              expect_xy(fields["place"], src, ("tasks", k, "place"))))
        tasks = tuple(tasks)
    meta = top.get("meta")
    if meta is not None and not isinstance(meta, dict):
        raise src.fail(("meta",), "expected a mapping")
    collisions = expect_str(top["collisions"], src, ("collisions",)) if "collisions" in top else "bille"
    return Instance(name, moveset, start, tuple(robots), goal, robot_goals, tasks, meta, collisions)


def _moveset(ref, src: Source, path, base_dir) -> Moveset:
    ref = expect_str(ref, src, path, "a moveset name (S5, S7, point) or a path")
    try:
        return load_moveset(ref, base_dir)
    except MovesetError as exc:
        raise src.fail(path, str(exc)) from None


def _grid(text, src: Source, key: str) -> Grid:
    path = (key,)
    text = expect_str(text, src, path, "the grid as lines of '#', '.' and 'T'")
    rows = text.splitlines()
    while rows and not rows[-1].strip():
        rows.pop()
    first = src.text_start.get(path)  # line of row 0 in a block scalar

    def row_line(r: int) -> int | None:
        return first + r if first is not None else None

    if not rows:
        raise src.fail(path, "the grid has no rows")
    width = len(rows[0])
    for r, row in enumerate(rows):
        if len(row) != width:
            raise src.fail(path, f"row {r} has {len(row)} cells, expected {width} like row 0 (the grid must be a rectangle)", row_line(r))
        for x, ch in enumerate(row):
            if ch not in CELL_CHARS:
                raise src.fail(path, f"row {r}, column {x}: unknown character {ch!r} (expected '#' obstacle, '.' empty or 'T' tile)", row_line(r))
    if width == 0:
        raise src.fail(path, "the grid rows are empty")
    return Grid(width, len(rows), tuple(rows))


# ---------------------------------------------------------------------------------------------
# writing


def instance_at(inst: Instance, st: State, name: str) -> Instance:
    """The instance of reaching ``inst``'s goal from state ``st`` (tiles, poses, loads)."""
    grid = Grid.from_masks(inst.width, inst.height, inst.start.obstacles, st.tiles)
    robots = []
    for i, r in enumerate(inst.robots):
        feet = inst.world.graphs[i].feet_xy(st.poses[i])
        robots.append(Robot(feet[0], feet[1] if len(feet) > 1 else None, bool(st.carrying[i]), r.moveset))
    return Instance(name, inst.moveset, grid, tuple(robots), inst.goal_grid, inst.robot_goals,
                    collisions=inst.collisions)
