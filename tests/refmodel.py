"""An independent, slow model of the rules of docs/rules.md, written from the rule book's table.

It shares no code with bille's pose graph or rules: coordinates are tuples, sets are Python
sets, connectivity is a plain BFS. The tests compare bille's validator against it.
"""
from __future__ import annotations

from collections import deque

HEADING = {"N": (0, -1), "E": (1, 0), "S": (0, 1), "W": (-1, 0)}


def rot(v, h):
    """Local (heading N) offset to the world frame of heading vector h (docs/rules.md)."""
    x, y = v
    return {(0, -1): (x, y), (1, 0): (-y, x), (0, 1): (-x, -y), (-1, 0): (y, -x)}[h]


def box(x0, x1, y0, y1):
    return [(x, y) for x in range(x0, x1 + 1) for y in range(y0, y1 + 1)]


# name: (new front, new back, extra swept cells, carried-tile cells, pick/place target)
BIPED = {
    "wait": ((0, 0), (0, 1), [], [(0, -1)], None),
    "fwd": ((0, -1), (0, 0), [], [(0, -1), (0, -2)], None),
    "back": ((0, 1), (0, 2), [], [(0, -1), (0, 0)], None),
    "fwd-right": ((1, 0), (0, 0), [(1, 1)], box(0, 2, -1, 0), None),
    "fwd-left": ((-1, 0), (0, 0), [(-1, 1)], box(-2, 0, -1, 0), None),
    "back-right": ((0, 1), (1, 1), [(1, 0)], box(-1, 0, -1, 1), None),
    "back-left": ((0, 1), (-1, 1), [(-1, 0)], box(0, 1, -1, 1), None),
    "pick": ((0, 0), (0, 1), [], [], (0, -1)),
    "place": ((0, 0), (0, 1), [], [], (0, -1)),
}
MOVESETS = {
    "S5": ["wait", "fwd", "back", "fwd-right", "fwd-left", "pick", "place"],
    "S7": list(BIPED),
    "point": ["wait", "north", "east", "south", "west"]
    + [f"{k}-{d}" for k in ("pick", "place") for d in ("north", "east", "south", "west")],
}
POINT_DIR = {"north": (0, -1), "east": (1, 0), "south": (0, 1), "west": (-1, 0)}


def kind(name):
    if name.startswith("pick"):
        return "pick"
    if name.startswith("place"):
        return "place"
    return "wait" if name == "wait" else "motion"


def add(a, b):
    return (a[0] + b[0], a[1] + b[1])


def motion(robot, name):
    """(new front, new back, collision set without carried cells, carried cells, target)."""
    f, b = robot["front"], robot["back"]
    if b is None:  # point
        if name == "wait":
            return f, None, {f}, set(), None
        if name in POINT_DIR:
            nf = add(f, POINT_DIR[name])
            return nf, None, {f, nf}, set(), None
        t = add(f, POINT_DIR[name.split("-")[1]])
        return f, None, {f, t}, set(), t
    h = (f[0] - b[0], f[1] - b[1])
    nf, nb, swept, carried, target = BIPED[name]
    w = lambda v: add(f, rot(v, h))  # noqa: E731
    coll = {f, b, w(nf), w(nb)} | {w(s) for s in swept}
    t = w(target) if target else None
    if t:
        coll.add(t)
    return w(nf), w(nb), coll, {w(c) for c in carried}, t


def connected(tiles):
    return len(components(tiles)) == 1


def components(tiles):
    left, comps = set(tiles), []
    while left:
        start = min(left, key=lambda c: (c[1], c[0]))
        comp, todo = {start}, deque([start])
        while todo:
            c = todo.popleft()
            for d in HEADING.values():
                n = add(c, d)
                if n in left and n not in comp:
                    comp.add(n)
                    todo.append(n)
        left -= comp
        comps.append(comp)
    return comps


def order(cells):
    return tuple(sorted(set(cells), key=lambda c: (c[1], c[0])))


def step(W, H, obstacles, tiles, robots, names):
    """One joint action. Returns ("ok", tiles, robots) or ("bad", rule, robot, cells)."""
    inside = lambda c: 0 <= c[0] < W and 0 <= c[1] < H  # noqa: E731
    moves = [motion(r, a) for r, a in zip(robots, names)]
    for i, (r, a, (nf, nb, coll, carried, t)) in enumerate(zip(robots, names, moves)):
        k = kind(a)
        if k == "pick" and (r["carrying"] or t not in tiles):
            return ("bad", "precondition", i, (t,))
        if k == "place" and (not r["carrying"] or t in tiles or t in obstacles or not inside(t)):
            return ("bad", "precondition", i, (t,))
    sets = []
    for i, (r, (nf, nb, coll, carried, t)) in enumerate(zip(robots, moves)):
        c = coll | (carried if r["carrying"] else set())
        bad = [x for x in c if not inside(x) or x in obstacles]
        if bad:
            return ("bad", "workspace", i, order(bad))
        sets.append(c)
    for i in range(len(sets)):
        for j in range(i + 1, len(sets)):
            if sets[i] & sets[j]:
                return ("bad", "collision", i, order(sets[i] & sets[j]))
    new = set(tiles)
    for a, (nf, nb, coll, carried, t) in zip(names, moves):
        if kind(a) == "pick":
            new.discard(t)
        elif kind(a) == "place":
            new.add(t)
    for i, (nf, nb, *_rest) in enumerate(moves):
        off = [c for c in (nf, nb) if c is not None and c not in new]
        if off:
            return ("bad", "support", i, order(off))
    if new != set(tiles) and not connected(new):
        if not new:
            return ("bad", "connectivity", None, ())
        comps = components(new)
        main = max(comps, key=len)  # first of the largest, in (y, x) order of first cell
        return ("bad", "connectivity", None, order(new - main))
    out = []
    for r, a, (nf, nb, *_rest) in zip(robots, names, moves):
        carrying = (r["carrying"] and kind(a) != "place") or kind(a) == "pick"
        out.append({"front": nf, "back": nb, "carrying": carrying})
    return ("ok", new, out)


def check(W, H, obstacles, tiles, robots, schedule, goal_tiles, robot_goals):
    """Replay a schedule (list of per-robot name lists). Returns None if valid, else
    (step, rule, robot, cells)."""
    length = len(schedule[0]) if schedule else 0
    for t in range(length):
        res = step(W, H, obstacles, tiles, robots, [row[t] for row in schedule])
        if res[0] == "bad":
            return (t + 1, res[1], res[2], res[3])
        _, tiles, robots = res
    if set(tiles) != set(goal_tiles):
        return (length, "goal", None, order(set(tiles) ^ set(goal_tiles)))
    for i, r in enumerate(robots):
        if r["carrying"]:
            return (length, "goal", i, ())
    for i, g in enumerate(robot_goals):
        if g is not None and robots[i]["front"] != g:
            return (length, "goal", i, (g,))
    return None
