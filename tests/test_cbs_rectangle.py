"""Rectangle reasoning: the split's completeness checked on every walk of small grids, and the
optima of instances where it is used against the brute force."""
import itertools
from random import Random

import pytest

from bille.heuristics.cbs.lowlevel import Path
from bille.heuristics.cbs.rectangle import rectangle
from helpers import make, split_with_and_without
from refsearch import optimal_soc

STEPS = ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1))


def walks(start, length, W, H):
    """Every walk of ``length`` steps (waits included) from ``start`` on an open W x H grid."""
    out = [(start,)]
    for _ in range(length):
        out = [w + ((w[-1][0] + dx, w[-1][1] + dy),) for w in out for dx, dy in STEPS
               if 0 <= w[-1][0] + dx < W and 0 <= w[-1][1] + dy < H]
    return out


def straight(s, c):
    """A monotone walk from ``s`` to ``c``: across first, then down or up."""
    cells, (x, y) = [s], s
    while x != c[0]:
        x += 1 if c[0] > x else -1
        cells.append((x, y))
    while y != c[1]:
        y += 1 if c[1] > y else -1
        cells.append((x, y))
    return cells


def rectangles(seed):
    """A vertex conflict of two robots that came straight, with random goals, on a small open
    grid; the rectangle split found for it (None if there is none)."""
    rnd = Random(seed)
    W, H = rnd.randint(3, 5), rnd.randint(3, 5)
    cells = [(x, y) for y in range(H) for x in range(W)]
    c = rnd.choice(cells)
    t = rnd.randint(1, 3)
    ring = [z for z in cells if abs(z[0] - c[0]) + abs(z[1] - c[1]) == t]
    if len(ring) < 2:
        return None
    s1, s2 = rnd.sample(ring, 2)
    g1, g2 = rnd.choice(cells), rnd.choice(cells)
    index = lambda z: z[1] * W + z[0]  # noqa: E731
    walks = [straight(s, c) + straight(c, g)[1:] for s, g in ((s1, g1), (s2, g2))]  # on to the goals:
    paths = [Path(tuple(index(z) for z in w), (), (), len(w) - 1) for w in walks]  # larger rectangles qualify
    found = rectangle((1, 0, 1, t, index(c)), paths, (None, None), (index(g1), index(g2)), W)
    return None if found is None else (W, H, s1, s2, found[0])


CASES = [case for case in map(rectangles, range(400)) if case is not None]


def test_rectangles_are_found_in_many_shapes():
    assert len(CASES) >= 100 and len(SHORT) >= 40
    assert sum(map(larger, CHECKED)) >= 20  # rectangles beyond the conflict cell, from the goals
    assert len({(len(b1), len(b2)) for *_, (_, _, _, _, (b1, b2)) in CASES}) >= 4


SHORT = [case for case in CASES if max(time for *_, time in case[4][4][0] + case[4][4][1]) <= 5]


def larger(case) -> bool:
    """Whether the rectangle reaches past the conflict cell (its far corner is later than it)."""
    *_, (_, _, _, t, (b1, b2)) = case
    return max(time for *_, time in b1 + b2) > t


CHECKED = SHORT[:30] + [case for case in SHORT[30:] if larger(case)]


@pytest.mark.parametrize("case", CHECKED, ids=lambda case: f"{case[0]}x{case[1]}")
def test_two_walks_that_both_break_their_barriers_meet(case):
    """The split is complete: every pair of walks (waits included) that is on a cell of its
    barrier at that cell's time stands on one cell at one time (module docstring's theorem)."""
    W, H, s1, s2, (_, r1, _, _, (b1, b2)) = case
    start = {0: s1, 1: s2}
    length = max(time for *_, time in b1 + b2)
    breaking = []
    for robot, barrier in ((r1, b1), (1 - r1, b2)):
        hits = {(b % W, b // W, time) for _, b, time in barrier}
        breaking.append([w for w in walks(start[robot], length, W, H)
                         if any((*w[time], time) in hits for time in range(length + 1))])
    assert breaking[0] and breaking[1]
    for w1, w2 in itertools.product(*breaking):
        assert any(a == b for a, b in zip(w1, w2)), (w1, w2)


def crossing(seed):
    """Two point robots crossing an open grid, one left to right, one bottom to top (None when
    the draw gives both one start or one goal)."""
    rnd = Random(seed)
    W, H = rnd.choice([(4, 4), (5, 4), (4, 5)])
    robots, goals = [], []
    for k in range(2):
        s, g = ((0, rnd.randrange(H)), (W - 1, rnd.randrange(H))) if k % 2 == 0 else \
            ((rnd.randrange(W), H - 1), (rnd.randrange(W), 0))
        robots.append(s)
        goals.append(g)
    if robots[0] == robots[1] or goals[0] == goals[1]:
        return None
    return make("\n".join("T" * W for _ in range(H)), [{"at": list(s)} for s in robots], moveset="point",
                collisions="classic", robot_goals=[list(g) for g in goals], name=f"cross{seed}")


@pytest.mark.slow
def test_where_a_rectangle_is_split_the_optimum_is_the_brute_forces():
    used = 0
    for seed in range(200):
        inst = crossing(seed)
        if inst is None:
            continue
        found = split_with_and_without(inst, "rectangle", 2000)
        if found is None:
            continue
        used += 1
        result, plain = found
        assert result.stats["sum_of_costs"] == plain.stats["sum_of_costs"] == optimal_soc(inst)[0], inst.name
        if used == 8:
            break
    assert used == 8
