"""Text pictures of instances for the terminal (``bille show``).

Robot ``i`` is drawn with the ``i``-th letter: its front foot upper case, its back foot lower case,
a carried tile as ``*``; in the goal, a robot's goal cell carries its upper-case letter.
"""
from __future__ import annotations

import string

from bille.instances import Instance
from bille.instances.grid import HEADING_NAMES

_LETTERS = string.ascii_uppercase


def robot_letter(i: int) -> str:
    return _LETTERS[i] if i < len(_LETTERS) else "@"


def draw(instance: Instance) -> list[str]:
    """Start (with robots) and goal (with robot goal cells) side by side."""
    start = [list(r) for r in instance.start.rows]
    goal = [list(r) for r in instance.goal_grid.rows]

    def put(rows, xy, ch):
        x, y = xy
        if 0 <= y < len(rows) and 0 <= x < len(rows[y]):
            rows[y][x] = ch

    for i, r in enumerate(instance.robots):
        letter = robot_letter(i)
        if r.back is not None:
            put(start, r.back, letter.lower())
            if r.carrying:
                put(start, (2 * r.front[0] - r.back[0], 2 * r.front[1] - r.back[1]), "*")
        put(start, r.front, letter)
    for i, g in enumerate(instance.robot_goals or ()):
        if g is not None:
            put(goal, g, robot_letter(i))
    width = max(instance.width, 5)
    lines = [f"{'start':<{width}}   goal"]
    lines += [f"{''.join(s):<{width}}   {''.join(g)}" for s, g in zip(start, goal)]
    return lines


def describe(instance: Instance) -> list[str]:
    """One line per robot: feet, heading, moveset, load, goal."""
    out = []
    goals = instance.robot_goals or (None,) * instance.num_robots
    for i, (r, ms, g) in enumerate(zip(instance.robots, instance.movesets, goals)):
        if r.back is None:
            where = f"at {r.front}"
        else:
            d = (r.front[0] - r.back[0], r.front[1] - r.back[1])
            name = HEADING_NAMES[[(0, -1), (1, 0), (0, 1), (-1, 0)].index(d)] if d in [(0, -1), (1, 0), (0, 1), (-1, 0)] else "?"
            where = f"front {r.front} back {r.back} heading {name}"
        load = ", carrying a tile" if r.carrying else ""
        goal = f"goal {g}" if g is not None else "no goal cell"
        out.append(f"  {robot_letter(i)} robot {i}: {where}, moveset {ms.name}{load}, {goal}")
    return out


def motion_diagram(moveset, name: str) -> list[str]:
    """A drawing of one motion in the local frame (heading N), from the moveset data.

    Three panels, rows ``y = -2 .. 2``: *before* (``F`` front, ``B`` back, ``c`` a carried
    tile), *after* (new feet), and the *collision set* (``o`` always, ``+`` only when carrying).
    """
    act = moveset.actions[moveset.index[name]]
    point = moveset.footprint == "point"
    before = {(0, 0): "F"} if point else {(0, 0): "F", (0, 1): "B", (0, -1): "c"}
    after = {act.front: "F"} if point else {act.back: "B", act.front: "F"}
    before_feet = [(0, 0)] if point else [(0, 0), (0, 1)]
    after_feet = [act.front] + ([] if point else [act.back])
    coll = set(before_feet) | set(after_feet) | set(act.swept) | ({act.target} if act.target else set())
    cells = {c: "o" for c in coll}
    for c in act.carried:
        cells.setdefault(c, "+")
    if act.target is not None:
        after[act.target] = "x"

    def panel(marks):
        return [" ".join(marks.get((x, y), ".") for x in range(-2, 3)) for y in range(-2, 3)]

    rows = zip(panel(before), panel(after), panel(cells))
    return [f"{b}    {a}    {c}" for b, a, c in rows]
