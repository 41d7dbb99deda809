"""Classic collisions (docs/rules.md): point robots may follow; vertex and swap conflicts and shared
pick or place targets are rejected; the planners that support the mode agree with brute force."""
import pytest

from bille.instances import InstanceError, OptionError, State, dump_instance, instance_from_text
from bille.solvers import solve, validate
from helpers import make, sched
from test_rules import broken, step

ROW = "TTTT"


def classic(grid, robots, **kw):
    return make(grid, robots, moveset="point", collisions="classic", **kw)


def test_following_into_a_vacated_cell_is_allowed():
    inst = classic(ROW, [{"at": [1, 0]}, {"at": [2, 0]}])
    assert isinstance(step(inst, "east", "east"), State)
    bille = make(ROW, [{"at": [1, 0]}, {"at": [2, 0]}], moveset="point")
    broken(step(bille, "east", "east"), "collision", 0, [(2, 0)])


def test_a_train_of_robots_moves_as_one():
    inst = classic(ROW, [{"at": [0, 0]}, {"at": [1, 0]}, {"at": [2, 0]}])
    assert isinstance(step(inst, "east", "east", "east"), State)


def test_swaps_and_vertex_conflicts_are_rejected():
    inst = classic(ROW, [{"at": [0, 0]}, {"at": [1, 0]}])
    broken(step(inst, "east", "west"), "collision", 0, [(0, 0), (1, 0)])
    three = classic(ROW, [{"at": [0, 0]}, {"at": [2, 0]}])
    broken(step(three, "east", "west"), "collision", 0, [(1, 0)])


def test_pick_and_place_targets_stay_exclusive():
    # robot 1 stands on the tile robot 0 picks
    stand = classic("TTT\nTTT", [{"at": [0, 0]}, {"at": [1, 0]}])
    broken(step(stand, "pick-east", "wait"), "collision", 0, [(1, 0)])
    assert isinstance(step(stand, "pick-south", "wait"), State)
    # two robots place on one cell
    both = instance_from_text("moveset: point\ncollisions: classic\ngrid: |\n  T.T\n  TTT\n  T..\nrobots: "
                              "[{at: [0, 0], carrying: true}, {at: [2, 0], carrying: true}]\ngoal: |\n  TTT\n  TTT\n  TT.\n")
    broken(step(both, "place-east", "place-west"), "collision", 0, [(1, 0)])
    # a robot walks onto the cell another places on
    onto = instance_from_text("moveset: point\ncollisions: classic\ngrid: |\n  TT.T\n  TTTT\nrobots: [{at: [1, 0], "
                              "carrying: true}, {at: [2, 1]}]\ngoal: |\n  TTTT\n  TTTT\n")
    broken(step(onto, "place-east", "north"), "collision", 0, [(2, 0)])


def test_the_validator_judges_whole_schedules_by_the_instance_rules():
    inst = classic(ROW, [{"at": [0, 0]}, {"at": [1, 0]}], robot_goals=[[2, 0], [3, 0]])
    assert validate(inst, sched("east east", "east east")).valid
    bille = make(ROW, [{"at": [0, 0]}, {"at": [1, 0]}], moveset="point", robot_goals=[[2, 0], [3, 0]])
    assert not validate(bille, sched("east east", "east east")).valid


def test_instance_files_say_it_and_only_point_robots_may_use_it():
    inst = classic(ROW, [{"at": [0, 0]}])
    assert "collisions: classic" in dump_instance(inst)
    assert instance_from_text(dump_instance(inst)).collisions == "classic"
    assert "collisions" not in dump_instance(make(ROW, [{"at": [0, 0]}], moveset="point"))
    with pytest.raises(InstanceError, match="collisions.*point robots only"):
        make("TTT\nTTT", [{"front": [1, 0], "back": [0, 0]}], collisions="classic")
    with pytest.raises(InstanceError, match="unknown collision rules 'loose'"):
        make(ROW, [{"at": [0, 0]}], moveset="point", collisions="loose")


CORRIDOR = dict(grid="TTTTT\n..T..", robots=[{"at": [0, 0]}, {"at": [1, 0]}], robot_goals=[[3, 0], [4, 0]])


def test_planners_agree_with_brute_force_under_classic_rules():
    inst = classic(**CORRIDOR)
    best = solve(inst, "bfs")
    assert best.status == "optimal"
    lacam = solve(inst, "lacam", improve=10.0)
    assert lacam.status == "optimal" and lacam.metrics.makespan == best.metrics.makespan
    astar = solve(inst, "astar")
    assert astar.status == "optimal" and validate(inst, astar.schedule).valid
    for r in (best, lacam):
        assert validate(inst, r.schedule).valid
    # following makes the classic optimum shorter than the Bill-E rule's
    bille = solve(make(moveset="point", **CORRIDOR), "bfs")
    assert bille.metrics.makespan > best.metrics.makespan


@pytest.mark.parametrize("method", ["temporal-astar", "mstar", "cpsat", "sat"])
def test_methods_without_the_classic_rules_refuse_it(method):
    with pytest.raises(OptionError, match="classic collisions"):
        solve(classic(**CORRIDOR), method)


def test_pibt_pulls_a_robot_along_to_pass_in_a_corridor():
    # two robots meet head-on in a corridor with one side cell: lacam3's swap emulation lets the
    # generator alone (one configuration per step, no constraint tried) bring both home
    inst = make("TTTTTTT\n...T...", [{"at": [0, 0]}, {"at": [6, 0]}], moveset="point",
                robot_goals=[[6, 0], [0, 0]], collisions="classic")
    result = solve(inst, "lacam", improve=0.0)
    assert result.status == "feasible" and validate(inst, result.schedule).valid
    assert result.stats["nodes"] == result.metrics.makespan + 1


def test_joint_astar_looks_at_the_clock_inside_one_expansion():
    # ten point robots on an open floor: the first expansion alone has 5**10 children; a clock
    # that moves one second per look must end the run within it, not after it
    from bille.heuristics import astar
    from bille.instances.run import Budget, Run
    robots = [{"at": [x, 0]} for x in range(10)]
    inst = classic("\n".join(["T" * 10] * 3), robots, robot_goals=[[x, 2] for x in range(10)])
    clock = iter(range(10**6))
    result = astar.plan(inst, run=Run(Budget(2.5, clock=lambda: next(clock))))
    assert result.status == "timeout" and result.failure.text == "time limit"
    assert result.stats["expanded"] == 1 and 0 < result.stats["generated"] < 5**10
