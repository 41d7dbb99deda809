"""MovingAI grid benchmarks (Sturtevant 2012) as path-planning instances: ``bille gen movingai``.

A ``.map`` file (``type octile``, ``height H``, ``width W``, ``map``, then H rows) becomes a grid
whose passable cells (``.``, ``G``, ``S``) are tiles and whose other cells (``@``, ``O``, ``T``,
``W``) are obstacles; only the largest 4-connected part of the passable cells stays tiles (the
structure must be connected), the rest become empty cells. Robots use the ``point`` footprint,
so the instance is classic MAPF on a 4-connected grid (``collisions: classic``, docs/rules.md, unless
asked for the Bill-E rule). Agents come from a ``.scen`` file (its
rows in order, skipping those whose start or goal is outside the kept part or already used) or,
without one, are drawn at random with the seed.
"""
from __future__ import annotations

import math
import random
from pathlib import Path

import numpy as np

from ..errors import InstanceError
from ..grid import Grid, detached_cells
from ..instance import Instance, Robot, check_instance
from ..limits import check_size
from ..moveset import load_moveset

PASSABLE = set(".GS")
BLOCKED = set("@OTW")


def read_map(path: str | Path) -> tuple[int, int, np.ndarray]:
    """``(width, height, passable)`` of a ``.map`` file (``passable`` a flat boolean mask)."""
    lines = _lines(path)
    head: dict[str, str] = {}
    k = 0
    while k < len(lines) and lines[k].strip() != "map":
        key, _, value = lines[k].strip().partition(" ")
        head[key] = value.strip()
        k += 1
    if k == len(lines):
        raise InstanceError(f"{path}: no 'map' line (expected a MovingAI map: type, height, width, map)")
    try:
        height, width = int(head["height"]), int(head["width"])
    except (KeyError, ValueError):
        raise InstanceError(f"{path}: expected 'height H' and 'width W' lines before 'map'") from None
    if height < 1 or width < 1:
        raise InstanceError(f"{path}: expected a positive height and width, got height {height} and width {width}")
    check_size([load_moveset("point")], width, height, str(path))
    rows = lines[k + 1 : k + 1 + height]
    if len(rows) != height:
        raise InstanceError(f"{path}: {len(rows)} map rows, expected height {height}")
    passable = np.zeros(width * height, dtype=bool)
    for y, row in enumerate(rows):
        row = row.rstrip("\r\n")
        if len(row) != width:
            raise InstanceError(f"{path}:{k + 2 + y}: row {y} has {len(row)} cells, expected width {width}")
        for x, ch in enumerate(row):
            if ch in PASSABLE:
                passable[y * width + x] = True
            elif ch not in BLOCKED:
                raise InstanceError(f"{path}:{k + 2 + y}: column {x + 1}: unknown map character {ch!r} "
                                    f"(expected one of {''.join(sorted(PASSABLE | BLOCKED))})")
    return width, height, passable


def read_scen(path: str | Path, size: tuple[int, int] | None = None) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """The ``(start, goal)`` cells of a ``.scen`` file's rows, in order. Every row has the nine
    fields of the format (bucket, map, width, height, start x, start y, goal x, goal y, optimal
    length); with ``size``, its width and height must be the map's."""
    out = []
    for k, line in enumerate(_lines(path), start=1):
        parts = line.split("\t") if "\t" in line else line.split()
        if k == 1 and parts and parts[0] == "version":
            continue
        if not line.strip():
            continue
        if len(parts) != 9:
            raise InstanceError(f"{path}:{k}: expected 9 fields (bucket, map, width, height, start x, start y, "
                                f"goal x, goal y, length), got {len(parts)}")
        try:
            bucket, width, height, sx, sy, gx, gy = (int(v) for v in (parts[0], *parts[2:8]))
        except ValueError:
            raise InstanceError(f"{path}:{k}: the bucket, width, height and coordinates must be whole numbers") from None
        try:
            length = float(parts[8])
        except ValueError:
            length = math.nan
        if not (bucket >= 0 and 0 <= length < math.inf):
            raise InstanceError(f"{path}:{k}: expected a bucket of at least 0 and a finite length of at least 0, "
                                f"got {parts[0]!r} and {parts[8]!r}")
        if size is not None and (width, height) != size:
            raise InstanceError(f"{path}:{k}: the row says the map is {width}x{height}, the map is {size[0]}x{size[1]}")
        out.append(((sx, sy), (gx, gy)))
    return out


def scen_map(scen: str | Path) -> Path:
    """The ``.map`` file a scenario names in its first row, in the scenario's folder."""
    scen = Path(scen)
    lines = _lines(scen)
    first = next(((k, line) for k, line in enumerate(lines[1:], 2) if line.strip()), None)
    if first is None:
        raise InstanceError(f"{scen}: no rows")
    k, line = first
    fields = line.split("\t") if "\t" in line else line.split()
    if len(fields) < 2 or not fields[1].strip():
        raise InstanceError(f"{scen}:{k}: expected the map's name in the second field")
    return scen.parent / Path(fields[1]).name


def from_movingai(map_path: str | Path, scen_path: str | Path | None = None, *, agents: int | None,
                  seed: int = 0, name: str | None = None, collisions: str = "classic") -> Instance:
    """An instance of ``agents`` point robots on the map (see the module docstring), under
    ``collisions``: ``classic`` (the benchmark's own rules, the default) or ``bille``. ``agents``
    None takes every usable row of the scenario."""
    if agents is None and scen_path is None:
        raise InstanceError("without a scenario the number of agents must be given")
    if agents is not None and agents < 1:
        raise InstanceError(f"--agents must be at least 1, got {agents}")
    width, height, passable = read_map(map_path)
    if not passable.any():
        raise InstanceError(f"{map_path}: no passable cell")
    tiles = passable.copy()
    tiles[detached_cells(passable, width, height)] = False  # keep the largest connected part
    inside = lambda xy: 0 <= xy[0] < width and 0 <= xy[1] < height and tiles[xy[1] * width + xy[0]]  # noqa: E731
    pairs: list = []
    if scen_path is not None:
        starts: set = set()
        goals: set = set()
        for s, g in read_scen(scen_path, (width, height)):  # as the benchmark means it: starts apart, goals apart
            if inside(s) and inside(g) and s not in starts and g not in goals and (agents is None or len(pairs) < agents):
                pairs.append((s, g))
                starts.add(s)
                goals.add(g)
        source = str(scen_path)
        if agents is None:
            agents = len(pairs)
            if not agents:
                raise InstanceError(f"{scen_path}: no usable row (start and goal in the map's largest connected part)")
    else:
        rnd = random.Random(seed)
        cells = [(c % width, c // width) for c in np.flatnonzero(tiles).tolist()]
        if 2 * agents > len(cells):
            raise InstanceError(f"{map_path}: its largest connected part has {len(cells)} cells, room for at most "
                                f"{len(cells) // 2} agents with distinct start and goal cells; {agents} asked")
        chosen = rnd.sample(cells, 2 * agents)
        pairs = list(zip(chosen[:agents], chosen[agents:]))
        source = f"random, seed {seed}"
    if len(pairs) < agents:
        raise InstanceError(f"{map_path}: only {len(pairs)} agents with distinct start and goal cells in the "
                            f"largest connected part ({int(tiles.sum())} cells; {source}), {agents} asked")
    grid = Grid.from_masks(width, height, ~passable, tiles)
    inst = Instance(name or Path(map_path).stem, load_moveset("point"), grid, tuple(Robot(s) for s, _ in pairs),
                    robot_goals=tuple(g for _, g in pairs), collisions=collisions,
                    meta={"generator": "movingai", "map": Path(map_path).name, "agents": agents, "scenario": source})
    return check_instance(inst)


def _lines(path) -> list[str]:
    try:
        return Path(path).read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise InstanceError(f"{path}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InstanceError(f"{path}: not a text file") from None
