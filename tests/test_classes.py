"""Classes of schedules and their bounds, against a brute force restricted to each class.

A class bound is a theorem about the schedules of its class, so it may exceed the unconditional
optimum but never the class's own optimum, which ``refsearch.class_optimum`` finds by a
breadth-first search that never leaves the class (its rules written again from the definitions).
"""
from __future__ import annotations

import pytest

from bille.instances import load_instance
from bille.instances.schedule import Schedule
from bille.instances.bundled import bundled_path
from bille.solvers import load_schedule, solve, validate
from bille.solvers.bounds import lower_bound
from bille.solvers.bounds.classes import BY_KEY, CLASSES, class_bounds, classes_of
from helpers import make, sched
from refsearch import class_optimum
from test_soundness import MANY, QUICK, reference
from tinyworlds import bridge_instance


def check_classes(instances) -> dict:
    """Every class bound against the class's brute-force optimum, every class schedule found
    validated and recognised; returns counts of what was compared."""
    counts = {"compared": 0, "above the optimum": 0, "empty": 0, "undecided": 0}
    for inst in instances:
        ref = reference(inst)
        if ref.status != "optimal" or not inst.is_reconfiguration:
            continue
        bounds = class_bounds(inst, unconditional=lower_bound(inst).lower)
        mine = classes_of(inst, ref.schedule)
        for c in CLASSES:
            try:
                best, ids = class_optimum(inst, c.key)
            except RuntimeError:
                counts["undecided"] += 1
                continue
            got = bounds[c.key]
            if best is None:  # the class has no schedule: the optimum's schedule is not in it
                counts["empty"] += 1
                assert c.key not in mine, (inst.name, c.key)
                continue
            assert not got.empty and got.lower <= best, (inst.name, c.key, got, best)
            schedule = Schedule.from_ids(inst, ids)
            assert validate(inst, schedule).valid
            assert c.key in classes_of(inst, schedule), (inst.name, c.key)
            if c.key in mine:  # an optimal schedule of the class is an optimum of the class
                assert best == ref.lower_bound, (inst.name, c.key)
            counts["compared"] += 1
            counts["above the optimum"] += best > ref.lower_bound
    return counts


def test_class_bounds_never_exceed_the_class_optimum():
    counts = check_classes([inst for inst in QUICK if inst.num_robots <= 2])  # three: minutes
    # the classes matter: some cost more than the optimum, some have no schedule at all
    assert counts["compared"] >= 30 and counts["above the optimum"] >= 2 and counts["empty"] >= 3, counts


@pytest.mark.slow
def test_class_bounds_never_exceed_the_class_optimum_on_many():
    counts = check_classes(MANY[:30])
    assert counts["compared"] >= 30, counts


@pytest.mark.slow
def test_class_bounds_never_exceed_the_class_optimum_across_a_bridge():
    bridges = [inst for inst in map(bridge_instance, range(24)) if inst is not None]
    counts = check_classes(bridges)
    assert counts["compared"] >= 10, counts


CROSSING = make("""
    TTT.
    TTT.
    TTT.""", [{"at": [1, 0]}, {"at": [2, 2]}], goal="""
    .TTT
    .TTT
    .TTT""", moveset="point")
# three tiles go from the west column to the east one: in a schedule that keeps the structure
# each crosses in one trip (nothing can be set down in between), so one of the two robots crosses
# twice and walks back in between, which the routing program spreads over both


@pytest.mark.slow
def test_the_crossings_part_counts_a_robot_that_carries_across_twice():
    parts = lower_bound(CROSSING, ground=BY_KEY["keep-structure"].ground(CROSSING)).parts
    best, ids = class_optimum(CROSSING, "keep-structure", max_states=300_000)
    assert validate(CROSSING, Schedule.from_ids(CROSSING, ids)).valid
    assert parts["routing (LP)"] == 6 < parts["crossings"] == 7 <= best == 8


NEEDS_SCAFFOLD = make("""
    T.T.
    TTT.""", [{"at": [2, 1]}, {"at": [0, 0], "carrying": True}], goal="""
    T.TT
    TTT.""", moveset="point")
# robot 1 cannot pass robot 0 on the path of tiles: the optimum (3 steps) sets the carried tile
# down on the empty cell (1, 0) for robot 0 to carry on to (3, 0)


def test_a_schedule_with_scaffold_is_in_no_class():
    result = solve(NEEDS_SCAFFOLD, "bfs")
    assert result.status == "optimal" and result.metrics.makespan == 3
    assert classes_of(NEEDS_SCAFFOLD, result.schedule) == []
    for c in CLASSES:
        assert class_optimum(NEEDS_SCAFFOLD, c.key) == (None, None)


STRIP = make("""
    TTT.
    TTTT""", [{"at": [1, 0]}], goal="""
    TT.T
    TTTT""", moveset="point")
STRAIGHT = ["pick-east", "south", "east", "east", "place-north"]


@pytest.mark.parametrize("before, classes", [
    ([], ["no-scaffold", "keep-structure", "single-carry"]),
    (["pick-east", "place-east"], ["no-scaffold", "keep-structure"]),  # (2, 0) changes three times
    (["pick-west", "place-west"], ["no-scaffold"]),  # (0, 0) is kept by the goal, but moved
])
def test_a_schedule_belongs_to_the_classes_its_tiles_keep_to(before, classes):
    schedule = sched(" ".join(before + STRAIGHT))
    assert validate(STRIP, schedule).valid
    assert classes_of(STRIP, schedule) == classes


def test_the_classes_nest():
    # every schedule of single-carry keeps the structure, and every one that keeps it has no
    # scaffold: so their bounds, and their optima, rise along the chain
    for inst in QUICK[:12] + [STRIP, NEEDS_SCAFFOLD]:
        if not inst.is_reconfiguration:
            continue
        got = class_bounds(inst)
        values = [got[k].lower for k in ("no-scaffold", "keep-structure", "single-carry") if not got[k].empty]
        assert values == sorted(values), (inst.name, got)


@pytest.mark.parametrize("name", ["lt-1", "lt-4", "bridge-2"])
def test_the_bundled_schedules_and_their_class_bounds(name):
    inst = load_instance(bundled_path(name))
    schedule = load_schedule(bundled_path(f"{name}.schedule"))
    report = validate(inst, schedule)
    assert report.valid
    keys = classes_of(inst, schedule)
    bounds = class_bounds(inst, unconditional=lower_bound(inst).lower)
    for key in keys:
        assert bounds[key].lower <= report.metrics.makespan, (key, bounds[key])


def test_no_class_on_a_fixed_structure():
    inst = load_instance(bundled_path("point-4"))
    assert class_bounds(inst) == {}
    assert classes_of(inst, solve(inst, "astar").schedule) == []
    assert set(BY_KEY) == {"no-scaffold", "keep-structure", "single-carry"}


def test_solve_reports_the_class_bounds_beside_the_bound_for_every_schedule():
    result = solve(STRIP, "bfs", bound=True)
    assert result.status == "optimal" and result.lower_bound == result.metrics.makespan == 5
    assert result.stats["classes"] == ["no-scaffold", "keep-structure", "single-carry"]
    got = result.stats["class_bounds"]
    assert set(got) == set(BY_KEY) and all(got[k]["lower_bound"] <= 5 for k in got)
    scaffold = solve(NEEDS_SCAFFOLD, "bfs", bound=True)
    assert scaffold.stats["classes"] == [] and scaffold.lower_bound <= 3
    assert "class_bounds" not in solve(STRIP, "bfs").stats  # only where the bound is computed


def test_a_schedule_below_its_class_bound_is_a_contradiction(monkeypatch):
    import bille.solvers.bounds.classes as classes

    real = classes.class_bounds

    def too_high(instance, **kw):  # a broken class bound: one more than this instance's optimum
        return {k: classes.ClassBound(k, 6) for k in real(instance, **kw)}

    monkeypatch.setattr(classes, "class_bounds", too_high)
    result = solve(STRIP, "bfs", bound=True)
    assert result.status == "error" and "no-scaffold schedule of makespan 5" in result.stats["contradiction"]


def test_the_gap_report_shows_each_schedules_class_and_its_gap_within():
    from bille.tools.gap import parse_configs, run

    rows = run([STRIP, NEEDS_SCAFFOLD], parse_configs("bfs"), time_limit=30)
    strip, scaffold = rows
    assert strip["classes"] == "no-scaffold keep-structure single-carry" and strip["class"] == "single-carry"
    assert strip["class_lower_bound"] <= strip["makespan"] == 5
    assert strip["class_gap_percent"] == round(100 * (5 - strip["class_lower_bound"]) / strip["class_lower_bound"], 1)
    assert scaffold["classes"] == "" and scaffold["class"] is None and scaffold["class_gap_percent"] is None


BRIDGE = make("""
    TT...T.
    TTTTTTT""", [{"at": [5, 1]}], goal="""
    .T...TT
    TTTTTTT""", moveset="point")
# 12 tiles, one robot: picking any cell of the bridge (2..4, 1) would leave fewer than 11 cells on
# either side, so without scaffold the tile must walk round by the bridge, and it cannot be
# relayed over it


def test_pinned_cells_raise_the_no_scaffold_bound_to_the_class_optimum():
    from bille.solvers.bounds.ground import Ground
    from bille.solvers.bounds.classes import pinned

    both = BRIDGE.start.tiles | BRIDGE.goal_tiles
    assert sorted(BRIDGE.world.xy(c) for c in pinned(BRIDGE, both).nonzero()[0]) == \
        [(1, 1), (2, 1), (3, 1), (4, 1), (5, 1)]
    loose = lower_bound(BRIDGE, ground=Ground(feet=both, picks=both, places=both)).lower
    got = class_bounds(BRIDGE)["no-scaffold"].lower
    best, _ = class_optimum(BRIDGE, "no-scaffold")
    assert loose < got == best == 13


@pytest.mark.slow
@pytest.mark.parametrize("restriction", ["no_scaffold", "keep_structure", "single_carry"])
def test_a_restricted_exact_search_starts_at_its_class_bound_and_finds_the_class_optimum(restriction):
    key = restriction.replace("_", "-")
    compared = 0
    for inst in [BRIDGE, STRIP] + [i for i in QUICK if i.num_robots <= 2][:6]:
        if not inst.is_reconfiguration:
            continue
        best, _ = class_optimum(inst, key)
        result = solve(inst, "cpsat", time_limit=60, **{restriction: True})
        if best is None:
            assert result.status in ("unsolved", "infeasible") and result.schedule is None, (inst.name, result.status)
            continue
        assert result.status == "optimal" and result.metrics.makespan == best, (inst.name, result.status, best)
        assert key in result.stats["classes"] and result.claim.lower == best
        ref = reference(inst)  # the bound for every schedule stays one: never the class's
        assert ref.status != "optimal" or result.lower_bound <= ref.lower_bound
        compared += 1
    assert compared >= 4


def test_a_restricted_search_on_a_fixed_structure_or_below_its_class_bound():
    inst = load_instance(bundled_path("point-4"))  # no tile moves: every schedule keeps the structure
    assert solve(inst, "cpsat", keep_structure=True, time_limit=30).status == "optimal"
    capped = solve(BRIDGE, "cpsat", keep_structure=True, max_makespan=10, time_limit=30)
    assert capped.status == "unsolved" and capped.claim.lower == 13
    assert "its class needs 13" in capped.failure.text and capped.lower_bound <= 13


@pytest.mark.slow
@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_the_exact_methods_without_scaffold_find_the_class_optimum_of_the_brute_force(method):
    # the model's restriction (cells empty at the start and in the goal stay empty) against the
    # breadth-first search that never leaves the class, on tiny instances, two of them where a
    # schedule that sets a tile down outside the start and the goal is shorter (5 against 4, 8
    # against 6)
    compared = costlier = 0
    needs_scaffold = [i for i in MANY if i.name in ("tiny-10101", "tiny-10102")]
    for inst in [BRIDGE] + needs_scaffold + [i for i in QUICK if i.num_robots <= 2 and i.is_reconfiguration][:10]:
        best, _ = class_optimum(inst, "no-scaffold")
        result = solve(inst, method, no_scaffold=True, time_limit=60)
        if best is None:
            assert result.schedule is None and result.status in ("unsolved", "infeasible"), inst.name
            continue
        assert result.status == "optimal" and result.metrics.makespan == best, (inst.name, result.status, best)
        assert validate(inst, result.schedule).valid and "no-scaffold" in classes_of(inst, result.schedule)
        assert result.claim.lower == best and result.lower_bound <= reference(inst).lower_bound
        compared += 1
        costlier += best > reference(inst).lower_bound
    assert compared >= 8 and costlier == 2
