"""The load-transfer maps' family: platforms in a row joined by bridges (``bille gen bridges``).

The paper's load-transfer maps (lt-1 .. lt-8) are rectangular platforms of tiles in a row, each
joined to the next by a bridge one tile wide with *bays* (a tile below the bridge, where robots
can pass each other), and a goal that takes the west platform's outer column and builds it
beside the east platform. :func:`bridges` builds any map of that family, so that a result on
lt-1 can be checked on its neighbours: a wider gap, more bays, fewer tiles moved, a robot more.

Layout, with platforms of ``width x height`` tiles and the grid's border row and column empty:

- platform ``p`` covers columns ``1 + p (width + gap) ..`` (``width`` of them) and rows
  ``1 .. height``; the bridges run along row ``1 + min(2, height - 2)`` (the third row of a
  platform at least four high) across the ``gap`` columns between two platforms; a bay at offset
  ``b`` is the cell below the bridge's ``b``-th column (0 is the first);
- the goal moves ``moved`` tiles: those of the west platform's first column, from the top, go to
  the same rows of the column just east of the east platform;
- ``robots[p]`` robots start on platform ``p``: the first on the bridge row, the others on the
  rows from the top; the west platform's face east, back foot beside the moving column, the
  others face west from their west edge (so none stands on a moving tile);
- with ``tasks``, the paper's building sequence: each moving tile straight across, from the top.

With the defaults it is lt-1; ``gap=10, bays=(3, 7)`` gives lt-2, ``width=5, robots=(1, 2)``
lt-5, and three 5x4 platforms with gaps of 5 and a bay in the middle (offset 2) lt-8
(tests/test_generators.py checks them against the bundled maps). The map has no randomness.
"""
from __future__ import annotations

import numpy as np

from ..errors import InstanceError
from ..grid import Grid
from ..instance import Instance, Robot, Task, check_instance
from ..limits import check_size
from ..moveset import load_moveset


def _check_numbers(platforms: int, width: int, height: int, gap: int, bays, moved: int, robots: tuple) -> None:
    """Raise :class:`InstanceError` for numbers that make no map of :func:`bridges`."""
    if platforms < 2:
        raise InstanceError(f"gen bridges: at least 2 platforms, got {platforms}")
    if width < 4 or height < 3:
        raise InstanceError(f"gen bridges: platforms of at least 4x3 tiles, got {width}x{height}")
    if gap < 1:
        raise InstanceError(f"gen bridges: the gap between platforms must be at least 1 column, got {gap}")
    if not 1 <= moved <= height:
        raise InstanceError(f"gen bridges: 1 to {height} tiles can move (the west platform's first column), "
                            f"got {moved}")
    bad = [b for b in bays if not 0 <= b < gap]
    if bad:
        raise InstanceError(f"gen bridges: bay offset {bad[0]} is not on a bridge of {gap} columns (0 .. {gap - 1})")
    if len(robots) != platforms:
        raise InstanceError(f"gen bridges: {len(robots)} robot counts for {platforms} platforms (one per platform)")
    if any(not 0 <= r <= height for r in robots) or not sum(robots):
        raise InstanceError(f"gen bridges: 0 to {height} robots per platform and at least one in all, got "
                            f"{','.join(map(str, robots))}")


def _robots(ms, robots: tuple, lefts: list[int], row: int, height: int) -> list[Robot]:
    """``robots[p]`` robots on platform ``p``, the bridge's row first, facing the bridge (those of
    the west platform east, the others west)."""
    placed = []
    rows = [row] + [y for y in range(1, 1 + height) if y != row]
    for p, count in enumerate(robots):
        for y in rows[:count]:
            if ms.footprint == "point":
                placed.append(Robot((lefts[p] + 1, y) if p == 0 else (lefts[p], y)))
            elif p == 0:
                placed.append(Robot((lefts[p] + 2, y), (lefts[p] + 1, y)))
            else:
                placed.append(Robot((lefts[p] + 1, y), (lefts[p] + 2, y)))
    return placed


def bridges(*, platforms: int = 2, width: int = 4, height: int = 4, gap: int = 6, bays: tuple[int, ...] = (3,),
            moved: int = 4, robots: tuple[int, ...] | None = None, moveset: str = "S7", tasks: bool = False,
            name: str | None = None) -> Instance:
    """A map of platforms joined by bridges (module docstring). ``robots``: per platform, west
    first (default one each). Raises :class:`InstanceError` for numbers that do not make such a
    map (one line naming the number)."""
    robots = tuple(robots) if robots is not None else (1,) * platforms
    _check_numbers(platforms, width, height, gap, bays, moved, robots)
    ms = load_moveset(moveset)
    W, H = 1 + platforms * width + (platforms - 1) * gap + 2, height + 2
    check_size([ms], W, H, "gen bridges")
    row = 1 + min(2, height - 2)
    start = np.zeros((H, W), dtype=bool)
    lefts = [1 + p * (width + gap) for p in range(platforms)]
    for x0 in lefts:
        start[1:1 + height, x0:x0 + width] = True
    for x0 in lefts[:-1]:
        first = x0 + width
        start[row, first:first + gap] = True
        for b in bays:
            start[row + 1, first + b] = True
    goal = start.copy()
    east = lefts[-1] + width
    goal[1:1 + moved, 1] = False
    goal[1:1 + moved, east] = True
    placed = _robots(ms, robots, lefts, row, height)
    plan = tuple(Task((1, y), (east, y)) for y in range(1, 1 + moved)) if tasks else None
    zeros = np.zeros(W * H, dtype=bool)
    label = name or (f"bridges-{platforms}x{width}x{height}-g{gap}-b{'.'.join(map(str, bays)) or 'none'}"
                     f"-m{moved}-r{'.'.join(map(str, robots))}")
    inst = Instance(label, ms, Grid.from_masks(W, H, zeros, start.ravel()), tuple(placed),
                    goal=Grid.from_masks(W, H, zeros, goal.ravel()), tasks=plan,
                    meta={"generator": "bridges"})
    return check_instance(inst)
