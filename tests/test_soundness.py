"""Soundness: every lower bound and every claimed optimum against the brute-force search.

A bound is a theorem about every schedule, so no part of it may exceed an optimum that the
breadth-first search (``bfs``, the reference: every joint action under the canonical rules)
proves; an instance that a static argument calls impossible must be one that the search
exhausts; and both exact back ends must claim exactly the search's optimum. The instances are
random tiny reconfigurations (``tinyworlds.py``): point robots and Bill-Es, 1-3 robots, carried
tiles, tiles that must move, relays possible. A few dozen run in the quick suite, hundreds in the
slow one.
"""
from __future__ import annotations

import functools

import pytest

from bille.solvers import bind, schedule_from_text, solve, validate
from bille.solvers.bfs import Options as BfsOptions
from bille.solvers.bfs import plan as bfs
from bille.solvers.bounds import lower_bound
from bille.solvers.bounds.ground import EVERYWHERE
from bille.solvers.bounds.routing import routing_bound
from helpers import make
from tinyworlds import tiny_instances

MAX_STATES = 5_000  # the reference gives up beyond this; such instances are not counted
# on the many: 1,500 states decide 93 of 200 optima in half the time of 5,000 (101)
MANY_STATES = 1_500


@functools.cache
def reference(inst, states: int = MAX_STATES):
    return bfs(inst, BfsOptions(max_states=states, engine="python"))


def check_bounds(instances, states: int = MAX_STATES) -> dict:
    """Every bound part against the reference; returns counts of what was decided."""
    counts = {"optimal": 0, "infeasible": 0, "undecided": 0, "routing binds": 0, "scaffold binds": 0,
              "crossings binds": 0, "split binds": 0}
    for inst in instances:
        ref, bounds = reference(inst, states), lower_bound(inst)
        if ref.status == "optimal":
            counts["optimal"] += 1
            assert validate(inst, ref.schedule).valid
            assert not bounds.impossible, (inst.name, bounds.impossible)
            for part, value in bounds.parts.items():
                assert value is None or value <= ref.lower_bound, (inst.name, part, value, ref.lower_bound)
            # the routing program split by robot (an integer program, a fraction of a second on
            # these): where the linear program is within a step of the bound, where it can bind
            routing = bounds.parts.get("routing (LP)")
            near = routing is not None and routing >= bounds.lower - 1
            split = routing_bound(inst, EVERYWHERE, split=True) if near else None
            if split is not None:
                assert split <= ref.lower_bound, (inst.name, "routing split by robot", split, ref.lower_bound)
                assert routing is None or split >= routing, (inst.name, split, routing)  # its relaxation is the LP
                counts["split binds"] += split > max(v for v in bounds.parts.values() if v is not None)
            programs = ("routing (LP)", "scaffold scenarios (LP)")
            others = [v for k, v in bounds.parts.items() if k not in programs and v is not None]
            counts["routing binds"] += (bounds.parts.get("routing (LP)") or 0) > max(others, default=0)
            counts["crossings binds"] += (bounds.parts.get("crossings") or 0) > max(
                (v for k, v in bounds.parts.items() if k != "crossings" and v is not None), default=0)
            counts["scaffold binds"] += (bounds.parts.get("scaffold scenarios (LP)") or 0) > max(
                others + [bounds.parts.get("routing (LP)") or 0])
        elif ref.status == "infeasible":
            counts["infeasible"] += 1
        else:
            counts["undecided"] += 1
    return counts


def check_exact(instances, methods=("cpsat", "sat"), limit: int = 8, states: int = MAX_STATES) -> int:
    """Both exact back ends claim exactly the reference's optimum; returns how many were compared."""
    compared = 0
    for inst in instances:
        ref = reference(inst, states)
        if ref.status == "optimal":
            for method in methods:
                got = solve(inst, method, time_limit=60)
                assert got.status == "optimal", (inst.name, method, got.status, got.stats.get("contradiction"))
                assert got.metrics.makespan == ref.lower_bound == got.lower_bound, (inst.name, method)
                assert validate(inst, got.schedule).valid
            compared += 1
        elif ref.status == "infeasible":
            cap = lower_bound(inst).lower + 2
            for method in methods:
                got = solve(inst, method, max_makespan=max(cap, 1), time_limit=120)
                assert got.schedule is None and got.status in ("infeasible", "unsolved"), (inst.name, method)
            compared += 1
        if compared >= limit:
            break
    return compared


# ---- the relay of the report, and its kind ------------------------------------------------------

RELAY = dict(grid="""
    .....
    ..TTT
    ..TTT""", goal="""
    .....
    ..TTT
    .TTTT""", robots=[{"at": [2, 2]}, {"at": [4, 2], "carrying": True}])


@pytest.mark.parametrize("method", ["bfs", "cpsat", "sat"])
def test_a_relay_beats_the_first_tile_moved(method):
    # robot 0 picks the tile east of it (a tile that stays) and places it west; robot 1 refills
    # the gap with the tile it carries: 2 steps, where "one robot carries a tile from a cell that
    # must empty to one that must fill" would say 3
    inst = make(RELAY["grid"], RELAY["robots"], goal=RELAY["goal"], moveset="point")
    assert lower_bound(inst).lower <= 2
    result = solve(inst, method, time_limit=60)
    assert result.status == "optimal" and result.metrics.makespan == 2 == result.lower_bound
    assert validate(inst, result.schedule).valid


def test_a_carried_tile_goes_straight_to_where_it_is_needed():
    # a Bill-E carrying a tile beside a cell to fill, and a tile that must go far away: the
    # carried tile fills at once while the other robot moves the far tile
    inst = make("""
        TTTTT.
        TTTTT.""", [{"front": [3, 0], "back": [2, 0], "carrying": True}, {"front": [1, 1], "back": [0, 1]}],
        goal="""
        TTTTTT
        TTTTT.""", moveset="S7")
    ref = reference(inst)
    assert ref.status == "optimal"
    bounds = lower_bound(inst)
    assert all(v is None or v <= ref.lower_bound for v in bounds.parts.values())
    for method in ("cpsat", "sat"):
        assert solve(inst, method, time_limit=60).metrics.makespan == ref.lower_bound


def test_solve_refuses_a_bound_above_the_makespan(monkeypatch):
    # a method whose proof contradicts its own valid schedule is reported as an error
    import bille.solvers as solvers
    from bille.instances.result import Result

    inst = make("TTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[3, 0]])
    good = bfs(inst)

    def lying(instance, options=None, run=None):
        return Result("bfs", "optimal", good.schedule, lower_bound=good.lower_bound + 1)

    monkeypatch.setitem(solvers.METHODS, "bfs", lying)
    result = solve(inst, "bfs")
    assert result.status == "error" and "above the makespan" in result.stats["contradiction"]


def test_solve_refuses_an_optimum_without_its_proof(monkeypatch):
    import bille.solvers as solvers
    from bille.instances.result import Result

    inst = make("TTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[2, 0]])
    # walk to the end and back: valid, 4 steps, but the optimum is 2 (the proof said 2)
    schedule = schedule_from_text("robots:\n  - [east, east, east, west]\n")
    assert validate(inst, schedule).metrics.makespan == 4 and bfs(inst).lower_bound == 2

    def lying(instance, options=None, run=None):
        return Result("bfs", "optimal", schedule, lower_bound=2)

    monkeypatch.setitem(solvers.METHODS, "bfs", lying)
    result = solve(inst, "bfs")
    assert result.status == "error" and "claimed with a proof of 2" in result.stats["contradiction"]


def test_a_relay_found_by_the_random_search():
    # tiny-70 of tinyworlds: robot 1 picks the tile beside it and sets it down on the cell to
    # fill while robot 0 puts its tile in the gap (3 steps; the carrier alone needs 5)
    inst = make("""
        .TT.
        .TTT
        ...T""", [{"at": [3, 2], "carrying": True}, {"at": [2, 0]}], goal="""
        TTT.
        .TTT
        ...T""", moveset="point")
    assert reference(inst).lower_bound == 3
    assert lower_bound(inst).lower <= 3
    for method in ("cpsat", "sat"):
        result = solve(inst, method, time_limit=60)
        assert result.status == "optimal" and result.metrics.makespan == 3


def test_walking_back_for_the_second_tile_counts():
    # tiny-82 of tinyworlds: the robot carries a tile and must fill (0, 2) and (2, 2) and empty
    # (3, 1), so after its first place it walks back for the tile at (3, 1); only the routing
    # bound counts that walk, and it meets the optimum
    inst = make("""
        TTTT
        TTTT
        .T..""", [{"at": [3, 0], "carrying": True}], goal="""
        TTTT
        TTT.
        TTT.""", moveset="point")
    bounds = lower_bound(inst)
    assert bounds.parts["routing (LP)"] == reference(inst).lower_bound == 7
    others = [v for k, v in bounds.parts.items() if k not in ("routing (LP)", "scaffold scenarios (LP)")]
    assert max(v for v in others if v is not None) <= 5


def test_the_scaffold_scenarios_price_the_tiles_a_shortcut_needs():
    # an S5 robot turns a row of four tiles into the row shifted east; the routing program lets
    # it walk over the empty cells beside the rows, which it can only do on tiles set down there
    inst = make("""
        .....
        TTTT.
        TTTT.
        .....""", [{"front": [1, 2], "back": [0, 2]}], goal="""
        .....
        .TTTT
        TTTT.
        .....""", moveset="S5")
    parts = lower_bound(inst).parts
    assert parts["routing (LP)"] == 7 < parts["scaffold scenarios (LP)"] == reference(inst).lower_bound == 9


# ---- random tiny instances ----------------------------------------------------------------------

QUICK = tiny_instances(30)
MANY = tiny_instances(200, first_seed=10_000, max_robots=2)  # 3 robots make the reference slow


@pytest.mark.slow
def test_bounds_never_exceed_the_optimum():
    counts = check_bounds(QUICK)
    assert counts["optimal"] >= 12 and counts["infeasible"] >= 3, counts


def test_exact_back_ends_claim_the_optimum():
    assert check_exact(QUICK, limit=10) == 10


@pytest.mark.slow
def test_bounds_never_exceed_the_optimum_on_many():
    counts = check_bounds(MANY, MANY_STATES)
    assert counts["optimal"] >= 80 and counts["infeasible"] >= 40, counts
    assert counts["routing binds"] >= 10, counts  # the LP is put to the test, not only the others
    assert counts["scaffold binds"] >= 1, counts  # and the scaffold scenarios
    assert counts["split binds"] >= 1, counts  # and the routing program split by robot


@pytest.mark.slow
def test_exact_back_ends_claim_the_optimum_on_many():
    assert check_exact(MANY, limit=50, states=MANY_STATES) == 50


@pytest.mark.parametrize("method", ["astar", "mstar", "temporal-astar", "lacam", "cpsat", "sat", "anytime", "bfs"])
def test_no_robots_and_nothing_to_do_is_solved_in_no_steps(method):
    found = solve(make("TTT\nT.T", []), method)
    assert found.status in ("optimal", "feasible") and found.metrics.makespan == 0
    assert found.schedule.num_robots == 0 and validate(make("TTT\nT.T", []), found.schedule).valid


def test_tiles_to_move_and_no_robot_is_proved_impossible():
    inst = make("TTT\nT..", [], goal="TTT\n..T")
    assert "no robot" in lower_bound(inst).impossible[0]
    assert solve(inst, "cpsat").status == "infeasible"


@pytest.mark.slow
def test_every_schedule_keeps_to_its_own_scaffold_scenario():
    # the theorem behind the scaffold scenarios, scenario by scenario: the program of a
    # schedule's own scenario (its lines' places forced, its ground only) is at most its makespan
    from bille.solvers.bounds.classes import tiles_over_time
    from bille.solvers.bounds.scaffold import corridor_lines, scenario_of, scenario_value
    from tinyworlds import bridge_instance

    from bille.instances import load_instance
    from bille.instances.bundled import bundled_path
    from bille.solvers import load_schedule

    found = []  # (instance, a valid schedule)
    for inst in [inst for inst in QUICK[:10] + [bridge_instance(s) for s in range(8)] if inst is not None]:
        ref = reference(inst)
        if ref.status == "optimal" and inst.is_reconfiguration:
            found.append((inst, ref.schedule))
    tiny = len(found)  # on these, the program split by robot too (an integer program, seconds on the lt maps)
    for name in ("lt-1", "lt-4", "bridge-2"):
        found.append((load_instance(bundled_path(name)), load_schedule(bundled_path(f"{name}.schedule"))))
    seen, splits = set(), 0
    for i, (inst, schedule) in enumerate(found):
        ids = bind(inst, schedule)
        tiles = tiles_over_time(inst, ids)
        for line, corridor in corridor_lines(inst):
            mine = scenario_of(inst, line, corridor, tiles)
            value = scenario_value(inst, line, corridor, mine, mine)
            assert value is None or value <= ids.shape[1], (inst.name, mine, value, ids.shape[1])
            seen.add(bool(mine))
            if i < tiny:
                split = scenario_value(inst, line, corridor, mine, mine, split=True)
                assert split is None or value is None or value <= split <= ids.shape[1], (inst.name, mine, split)
                splits += split is not None
    assert seen == {True, False}  # schedules with scaffold and without
    assert splits >= 5


@pytest.mark.slow
def test_the_scaffold_scenarios_taken_further_never_exceed_the_optimum():
    # what anytime adds to the static bound's scaffold part (the search run on, each least
    # scenario's program split by robot) against the brute force's proved optima; it rises above
    # the static bound on some of these, and on one at least to the optimum
    from bille.instances.run import Budget

    raised, met = 0, 0
    for inst in MANY:
        ref = reference(inst, MANY_STATES)
        bounds = lower_bound(inst) if ref.status == "optimal" else None
        if bounds is None or bounds.scaffold is None:
            continue
        value = bounds.scaffold.advance(Budget().child(20), split=True)
        assert value is None or value <= ref.lower_bound, (inst.name, value, ref.lower_bound)
        raised += value is not None and value > bounds.lower
        met += value is not None and bounds.lower < value == ref.lower_bound
    assert raised >= 3 and met >= 1, (raised, met)
