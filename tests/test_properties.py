"""Property tests: bille's validator against the independent reference model (refmodel.py)."""
from __future__ import annotations

import json

import pytest

from hypothesis import assume, event, given, strategies as st

import refmodel
from bille.instances import BilleError, instance_from_text
from bille.instances.bundled import bundled_names, bundled_path
from bille.solvers import schedule_from_text, validate

NEIGHBOURS = list(refmodel.HEADING.values())


@st.composite
def scenes(draw):
    """A random connected structure with obstacles and 1-3 robots of random movesets."""
    rnd = draw(st.randoms(use_true_random=False))
    W, H = draw(st.integers(3, 7)), draw(st.integers(2, 6))
    cells = [(x, y) for y in range(H) for x in range(W)]
    tiles = {rnd.choice(cells)}
    for _ in range(draw(st.integers(3, W * H))):
        frontier = [refmodel.add(c, d) for c in tiles for d in NEIGHBOURS]
        frontier = [c for c in frontier if c in cells and c not in tiles]
        if frontier:
            tiles.add(rnd.choice(frontier))
    free = [c for c in cells if c not in tiles]
    obstacles = set(rnd.sample(free, k=min(len(free), draw(st.integers(0, 3)))))
    robots, used = [], set()
    for _ in range(draw(st.integers(1, 3))):
        ms = draw(st.sampled_from(["S5", "S7", "point"]))
        spots = []
        for f in sorted(tiles - used):
            if ms == "point":
                spots.append({"front": f, "back": None, "ms": ms})
                continue
            for d in NEIGHBOURS:
                b = (f[0] - d[0], f[1] - d[1])
                if b in tiles and b not in used:
                    spots.append({"front": f, "back": b, "ms": ms})
        if not spots:
            break
        r = rnd.choice(spots)
        occupied = {r["front"], r["back"]} - {None}
        r["carrying"] = False
        if ms != "point" and rnd.random() < 0.3:
            ahead = (2 * r["front"][0] - r["back"][0], 2 * r["front"][1] - r["back"][1])
            if 0 <= ahead[0] < W and 0 <= ahead[1] < H and ahead not in obstacles and ahead not in used:
                r["carrying"] = True
                occupied.add(ahead)
        elif ms == "point" and rnd.random() < 0.3:
            r["carrying"] = True
        used |= occupied
        robots.append(r)
    return W, H, obstacles, tiles, robots, rnd


def random_walk(W, H, obstacles, tiles, robots, rnd, length):
    """A valid schedule by the reference model; extended until no robot carries a tile."""
    schedule = [[] for _ in robots]
    state = (tiles, robots)
    for t in range(length + 40):
        if t >= length and not any(r["carrying"] for r in state[1]):
            break
        for _ in range(30):
            names = []
            for r in state[1]:
                options = refmodel.MOVESETS[r["ms"]]
                if t >= length and r["carrying"] and rnd.random() < 0.7:
                    options = [a for a in options if a.startswith("place")] or options
                names.append(rnd.choice(options))
            res = refmodel.step(W, H, obstacles, state[0], [dict(r) for r in state[1]], names)
            if res[0] == "ok":
                break
        else:
            names = ["wait"] * len(robots)
            res = refmodel.step(W, H, obstacles, state[0], state[1], names)
        for row, a in zip(schedule, names):
            row.append(a)
        new_robots = [dict(r, **n) for r, n in zip(state[1], res[2])]
        state = (res[1], new_robots)
    return schedule, state


def instance_text(W, H, obstacles, tiles, robots, goal_tiles, robot_goals) -> str:
    def grid(ts):
        return ["  " + "".join("#" if (x, y) in obstacles else "T" if (x, y) in ts else "." for x in range(W))
                for y in range(H)]

    lines = ["name: random", "moveset: S7", "grid: |"] + grid(tiles) + ["goal: |"] + grid(goal_tiles) + ["robots:"]
    for r in robots:
        if r["back"] is None:
            item = {"at": list(r["front"])}
        else:
            item = {"front": list(r["front"]), "back": list(r["back"])}
        item.update(carrying=r["carrying"], moveset=r["ms"])
        lines.append("  - " + json.dumps(item))
    lines.append("robot_goals: " + json.dumps([None if g is None else list(g) for g in robot_goals]))
    return "\n".join(lines) + "\n"


def build(scene, length, goals_mask):
    W, H, obstacles, tiles, robots, rnd = scene
    schedule, (final_tiles, final_robots) = random_walk(W, H, obstacles, tiles, robots, rnd, length)
    assume(not any(r["carrying"] for r in final_robots))
    goals = [r["front"] if keep else None for r, keep in zip(final_robots, goals_mask)]
    text = instance_text(W, H, obstacles, tiles, robots, final_tiles, goals)
    sched_text = "robots:\n" + "".join(f"  - [{', '.join(row)}]\n" for row in schedule)
    return instance_from_text(text, "random"), schedule_from_text(sched_text), schedule, goals, final_tiles


@pytest.mark.slow
@given(scene=scenes(), length=st.integers(0, 25), goals_mask=st.lists(st.booleans(), min_size=3, max_size=3))
def test_random_valid_walks_are_accepted(scene, length, goals_mask):
    inst, sched, rows, goals, _ = build(scene, length, goals_mask)
    report = validate(inst, sched)
    assert report.valid, report.violation
    event(f"walk: {'with' if report.metrics.picks else 'no'} picks, {inst.num_robots} robots")
    kinds = [refmodel.kind(a) for row in rows for a in row]
    assert report.metrics.picks == kinds.count("pick")
    assert report.metrics.places == kinds.count("place")
    assert report.metrics.tiles_traveled == kinds.count("motion")


@given(scene=scenes(), length=st.integers(1, 25), goals_mask=st.lists(st.booleans(), min_size=3, max_size=3),
       where=st.tuples(st.integers(0, 10**6), st.integers(0, 10**6), st.integers(0, 10**6)),
       manipulate=st.booleans())
def test_single_action_mutations_are_judged_like_the_reference(scene, length, goals_mask, where, manipulate):
    inst, _, rows, goals, final_tiles = build(scene, length, goals_mask)
    W, H, obstacles, tiles, robots, _ = scene
    i = where[0] % len(rows)
    t = where[1] % len(rows[i])
    options = refmodel.MOVESETS[robots[i]["ms"]]
    if manipulate:  # picks and places reach the connectivity rule more often
        options = [a for a in options if refmodel.kind(a) in ("pick", "place")]
    mutated = [list(r) for r in rows]
    mutated[i][t] = options[where[2] % len(options)]
    sched = schedule_from_text("robots:\n" + "".join(f"  - [{', '.join(r)}]\n" for r in mutated))
    expected = refmodel.check(W, H, obstacles, tiles, [dict(r) for r in robots], mutated, final_tiles, goals)
    report = validate(inst, sched)
    event(f"mutation: {'valid' if expected is None else expected[1]}")
    if expected is None:
        assert report.valid, report.violation
    else:
        v = report.violation
        assert v is not None, f"reference found {expected}"
        assert (v.step, v.rule, v.robot, v.cells) == expected


SEEDS = [bundled_path(n).read_text() for n in bundled_names()]
NOISE = "#.T[]{},:-\n 0123456789abxyzXYZ'\"&*!|>?\t"


@given(seed=st.sampled_from(SEEDS), edits=st.lists(
    st.tuples(st.sampled_from(["replace", "delete", "insert", "truncate", "dupline"]),
              st.integers(0, 10**6), st.sampled_from(NOISE), st.integers(1, 8)), min_size=1, max_size=4))
def test_corrupted_instance_files_raise_only_bille_errors(seed, edits):
    text = seed
    for op, pos, ch, span in edits:
        p = pos % (len(text) + 1)
        if op == "replace":
            text = text[:p] + ch + text[p + 1:]
        elif op == "delete":
            text = text[:p] + text[p + span:]
        elif op == "insert":
            text = text[:p] + ch * span + text[p:]
        elif op == "truncate":
            text = text[:p]
        else:
            lines = text.splitlines(keepends=True)
            if lines:
                k = pos % len(lines)
                lines.insert(k, lines[k])
            text = "".join(lines)
    try:
        inst = instance_from_text(text, "corrupt.yaml")
    except BilleError as exc:
        event("corrupt: rejected")
        assert str(exc).startswith("corrupt.yaml"), exc
        assert "\n" not in str(exc)
        return
    event("corrupt: still valid")
    inst.world  # a loaded instance compiles
    _ = inst.start_state
