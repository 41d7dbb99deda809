"""Random tiny reconfiguration instances for differential tests against the brute-force search.

Seeded, so every run and machine sees the same instances. Point robots and Bill-Es (S5, S7,
sometimes mixed in one group), 1-3 robots, tiles carried at the start, tiles that must move, goal
cells for some robots; relays and hand-overs are possible whenever two robots are near the same
tiles. A draw that breaks an instance validity rule is dropped (``None``).
"""
from __future__ import annotations

import json
from random import Random

from bille.instances import InstanceError, instance_from_text

STEPS = ((0, -1), (1, 0), (0, 1), (-1, 0))


def _blob(rnd: Random, cells: list, size: int) -> set:
    tiles = {rnd.choice(cells)}
    while len(tiles) < size:
        frontier = sorted({(x + dx, y + dy) for x, y in tiles for dx, dy in STEPS} & set(cells) - tiles)
        if not frontier:
            break
        tiles.add(rnd.choice(frontier))
    return tiles


def _connected(tiles: set) -> bool:
    if not tiles:
        return False
    seen, todo = set(), [next(iter(tiles))]
    while todo:
        c = todo.pop()
        if c in seen:
            continue
        seen.add(c)
        todo += [(c[0] + dx, c[1] + dy) for dx, dy in STEPS if (c[0] + dx, c[1] + dy) in tiles]
    return seen == tiles


def _draw(tiles: set, W: int, H: int) -> str:
    return "\n".join("".join("T" if (x, y) in tiles else "." for x in range(W)) for y in range(H))


def tiny_instance(seed: int, *, max_robots: int = 3):
    """One random tiny reconfiguration instance, or None where the draw is not a valid instance."""
    rnd = Random(seed)
    kind = rnd.choice(["point", "point", "S5", "S7", "mixed"])
    W, H = rnd.randint(3, 5 if kind == "point" else 4), rnd.randint(2, 3)
    cells = [(x, y) for y in range(H) for x in range(W)]
    start = _blob(rnd, cells, rnd.randint(3, max(3, W * H - 3)))
    goal = set(start)
    for _ in range(rnd.randint(0, 2)):  # tiles that must move
        gone = rnd.choice(sorted(goal))
        frontier = sorted({(x + dx, y + dy) for x, y in goal for dx, dy in STEPS} & set(cells) - goal)
        if frontier:
            new = goal - {gone} | {rnd.choice(frontier)}
            if _connected(new):
                goal = new
    robots, used = [], set()
    for _ in range(rnd.randint(1, max_robots)):
        ms = rnd.choice(["point", "S5", "S7"]) if kind == "mixed" else kind
        spots = []
        for f in sorted(start - used):
            if ms == "point":
                spots.append((f, None))
                continue
            spots += [(f, (f[0] - dx, f[1] - dy)) for dx, dy in STEPS
                      if (f[0] - dx, f[1] - dy) in start - used]
        if not spots:
            break
        front, back = rnd.choice(spots)
        robot = {"at": list(front)} if back is None else {"front": list(front), "back": list(back)}
        used |= {front, back} - {None}
        if kind == "mixed":
            robot["moveset"] = ms
        if rnd.random() < 0.35:
            robot["carrying"] = True
            ahead = None if back is None else (2 * front[0] - back[0], 2 * front[1] - back[1])
            if ahead is not None:
                used.add(ahead)
        robots.append(robot)
    far = rnd.random() < 0.5  # a carried tile's goal far from its robot: a relay may pay
    for robot in robots:  # the carried tiles end in the structure
        if not robot.get("carrying"):
            continue
        frontier = sorted({(x + dx, y + dy) for x, y in goal for dx, dy in STEPS} & set(cells) - goal)
        if not frontier:
            return None
        at = robot.get("at") or robot["front"]
        goal.add(max(frontier, key=lambda c: abs(c[0] - at[0]) + abs(c[1] - at[1])) if far else rnd.choice(frontier))
    goals = None
    if rnd.random() < 0.3:
        goals = [list(rnd.choice(sorted(goal))) if rnd.random() < 0.5 else None for _ in robots]
    lines = [f"name: tiny-{seed}", f"moveset: {'S7' if kind == 'mixed' else kind}", "grid: |"]
    lines += ["  " + r for r in _draw(start, W, H).splitlines()]
    lines += ["goal: |"] + ["  " + r for r in _draw(goal, W, H).splitlines()]
    lines.append("robots: " + json.dumps(robots))
    if goals is not None:
        lines.append("robot_goals: " + json.dumps(goals))
    try:
        return instance_from_text("\n".join(lines) + "\n", f"tiny-{seed}")
    except InstanceError:
        return None


def tiny_instances(count: int, first_seed: int = 0, **kw) -> list:
    """The first ``count`` valid instances from ``first_seed`` on."""
    out, seed = [], first_seed
    while len(out) < count:
        inst = tiny_instance(seed, **kw)
        seed += 1
        if inst is not None and inst.is_reconfiguration:
            out.append(inst)
    return out


def bridge_instance(seed: int):
    """Two platforms two columns wide joined by a bridge one cell high and 1-3 long; one tile of
    the west platform goes to the east one; 1-2 point robots. The bridge's cells are often
    pinned (no tile can leave them without splitting the structure), so a schedule without
    scaffold walks the tile round, and relays may need tiles set down in the gap."""
    rnd = Random(seed)
    span, H = rnd.choice([1, 2, 3]), rnd.choice([2, 3])
    W, row, out, into = 4 + span, rnd.randrange(H), rnd.randrange(H), rnd.randrange(H)
    if out == row or into == row:
        return None
    start = {(x, y) for y in range(H) for x in (0, 1, W - 2, W - 1)} | {(x, row) for x in range(2, 2 + span)}
    start.discard((W - 1, into))
    goal = (start - {(0, out)}) | {(W - 1, into)}
    cells = sorted(start)
    robots = [{"at": list(c)} for c in rnd.sample(cells, rnd.choice([1, 2]))]
    def block(tiles):
        return "".join(f"  {line}\n" for line in _draw(tiles, W, H).splitlines())

    text = (f"name: bridge-tiny-{seed}\nmoveset: point\ngrid: |\n{block(start)}goal: |\n{block(goal)}"
            f"robots: {json.dumps(robots)}\n")
    try:
        return instance_from_text(text, f"bridge-tiny-{seed}")
    except InstanceError:
        return None
