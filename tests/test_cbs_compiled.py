"""Conflict-based search's compiled low level (point robots) against the Python one it replaces:
the same paths, MDDs and corridor distances on random constraint sets, and the same constraint
tree, optimum and schedule with either, each schedule through the validator."""
from random import Random

import numpy as np
import pytest

from bille.heuristics.cbs import lowlevel, lowlevel_compiled as compiled, mdd_compiled, search as tree_search
from bille.heuristics.cbs.classic import ClassicAvoid
from bille.heuristics.cbs.constraints import AFTER, EDGE, NEVER, RANGE, VERTEX, Table
from bille.heuristics.cbs.corridor import Corridors
from bille.heuristics.cbs.method import agents_of
from bille.heuristics.joint import JointProblem
from bille.instances.generators.movingai import from_movingai
from bille.solvers import solve, validate
from bille.tools.bench.maps import scenario_of, shipped_maps
from test_cbs import TINY, path_planning


def _movingai(name: str, agents: int):
    folder = shipped_maps()
    return from_movingai(folder / f"{name}.map", scenario_of(folder, name), agents=agents)


def _constraints(rnd: Random, path) -> tuple:
    """Up to a dozen constraints on and around ``path``'s cells and moves, of every kind."""
    out = []
    for _ in range(rnd.randrange(13)):
        t = rnd.randrange(path.cost + 4)
        cell = path.poses[min(t, path.cost)]
        r = rnd.random()
        if r < 0.55:
            out.append((VERTEX, cell, t))
        elif r < 0.75 and 1 <= t <= path.cost:
            out.append((EDGE, path.poses[t - 1], path.poses[t], t))
        elif r < 0.9:
            out.append((RANGE, cell, t))
        else:
            out.append((AFTER, t))
    return tuple(out)


@pytest.mark.parametrize("name", ["random-32-32-10", "room-32-32-4"])
def test_the_compiled_search_and_mdd_are_the_python_ones(name):
    rnd = Random(7)
    problem = JointProblem.of(_movingai(name, 12), "cbs")
    agents = agents_of(problem, compiled=True)
    free = [lowlevel.search(a, Table(()), None, True) for a in agents]
    scratch, compared = compiled.Scratch(), 0
    for trial in range(150):
        k = rnd.randrange(len(agents))
        agent, table = agents[k], Table(_constraints(rnd, free[k]))
        avoid = ClassicAvoid(free, k, len(agent.dist)) if trial % 2 else None
        want = lowlevel.search(agent, table, avoid, True)
        got = compiled.search(agent, agent.arrays, table, avoid, scratch)
        assert (want is None) == (got is None)
        if want is None:
            continue
        assert (got.poses, got.actions, got.cells, got.cost) == (want.poses, want.actions, want.cells, want.cost)
        a, b = lowlevel.mdd(agent, table, True, want.cost), mdd_compiled.mdd(agent, agent.arrays, table, want.cost)
        assert list(b.levels) == list(a.levels)
        assert [sorted(s, key=lambda m: m[:2]) for s in b.steps] == [sorted(s, key=lambda m: m[:2]) for s in a.steps]
        compared += 1
    assert compared > 100  # most draws keep a path


def test_the_compiled_corridor_distances_are_the_python_ones():
    rnd = Random(2)
    problem = JointProblem.of(_movingai("warehouse-10-20-10-2-1", 6), "cbs")
    plain, fast = Corridors(agents_of(problem)), Corridors(agents_of(problem, compiled=True))
    cells = len(problem.dist_table[0])
    for _ in range(200):
        k, target = rnd.randrange(6), rnd.randrange(cells)
        avoid = frozenset(rnd.randrange(cells) for _ in range(rnd.randrange(30))) - {plain.agents[k].start}
        assert fast.distance(k, target, avoid) == plain.distance(k, target, avoid)
    assert plain.distance(0, plain.agents[0].start) == 0 and NEVER > cells


def _runs(monkeypatch, inst, compiled_low: bool):
    """``solve(inst, "cbs")`` with the low level compiled from its first search, or never."""
    monkeypatch.setattr(tree_search, "SWITCH", 0 if compiled_low else 1 << 60)
    monkeypatch.setattr(tree_search, "loaded", lambda: compiled_low)
    return solve(inst, "cbs", max_nodes=2000, time_limit=None)


CLASSIC = [inst for inst in TINY if inst.collisions == "classic"] + [
    inst for inst in map(path_planning, range(60, 200)) if inst is not None and inst.collisions == "classic"][:20]


@pytest.mark.parametrize("inst", CLASSIC[:25], ids=lambda i: i.name)
def test_cbs_builds_the_same_tree_with_either_low_level(monkeypatch, inst):
    a, b = _runs(monkeypatch, inst, False), _runs(monkeypatch, inst, True)
    assert (a.status, a.stats.get("expanded"), a.stats.get("low_expanded")) == \
        (b.status, b.stats.get("expanded"), b.stats.get("low_expanded"))
    if a.schedule is not None:
        assert validate(inst, b.schedule).valid
        assert a.schedule.actions == b.schedule.actions


@pytest.mark.slow
def test_cbs_on_a_movingai_map_is_the_same_with_either_low_level(monkeypatch):
    inst = _movingai("random-32-32-10", 50)
    a, b = _runs(monkeypatch, inst, False), _runs(monkeypatch, inst, True)
    assert a.status == b.status == "optimal" and a.stats["expanded"] > 10
    assert (a.counters.sum_of_costs, a.stats["expanded"]) == (b.counters.sum_of_costs, b.stats["expanded"])
    assert validate(inst, b.schedule).valid


def test_a_long_run_switches_to_the_compiled_low_level(monkeypatch):
    """Without Numba loaded the searches start in Python and switch once they have taken
    SWITCH expansions; the tree is the same as with Python throughout."""
    inst = _movingai("room-32-32-4", 20)
    monkeypatch.setattr(tree_search, "loaded", lambda: False)
    monkeypatch.setattr(tree_search, "SWITCH", 1 << 60)
    plain = solve(inst, "cbs", max_nodes=2000, time_limit=None)
    monkeypatch.setattr(tree_search, "SWITCH", plain.stats["low_expanded"] // 2)
    calls, real = [], compiled.search
    monkeypatch.setattr(compiled, "search", lambda *args, **kw: calls.append(1) or real(*args, **kw))
    switched = solve(inst, "cbs", max_nodes=2000, time_limit=None)
    assert calls and plain.stats["expanded"] > 5  # it switched, in a tree of several nodes
    assert (switched.status, switched.stats["expanded"], switched.counters.sum_of_costs) == \
        (plain.status, plain.stats["expanded"], plain.counters.sum_of_costs)
    assert validate(inst, switched.schedule).valid
