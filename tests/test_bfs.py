"""The reference breadth-first solver: optimal makespans, proofs of infeasibility, limits."""
import pytest

from bille.instances import OptionError
from bille.solvers import METHODS, solve, validate
from bille.solvers.bfs import Options, plan
from helpers import make


def test_point_robot_walks_the_shortest_route():
    inst = make("TTTT\nT..T\nTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[3, 2]])
    result = solve(inst, "bfs")
    assert result.status == "optimal" and result.metrics.makespan == 5
    assert validate(inst, result.schedule).valid


@pytest.mark.slow
def test_two_robots_must_take_turns_in_a_corridor():
    # both want to cross the single cell (2, 0); the optimum makes one wait or detour
    inst = make("TTTTT\n..T..", [{"at": [0, 0]}, {"at": [4, 0]}], moveset="point", robot_goals=[[4, 0], [0, 0]])
    result = solve(inst, "bfs")
    assert result.status == "optimal"
    assert validate(inst, result.schedule).valid
    # robot 1 steps into the bay (2, 1) by step 3; robot 0 may enter (2, 0) only a step after
    # robot 1 has left it (no following), crosses by step 6; robot 1 is home at step 8
    assert result.metrics.makespan == 8


def test_reconfiguration_needs_a_pick_and_a_place():
    inst = make("TTT.\n....", [{"at": [1, 0]}], goal="TT..\n.T..", moveset="point")
    result = solve(inst, "bfs")
    assert result.status == "optimal" and result.metrics.makespan == 2
    assert (result.metrics.picks, result.metrics.places) == (1, 1)


def test_a_robot_that_cannot_turn_around_is_proved_infeasible():
    # an S5 robot heading east on a line of three tiles must turn around to put its front foot
    # on (0, 0); turning needs tiles beside the line, and the search shows that moving the one
    # spare tile never makes room
    stuck = make("TTT\n...", [{"front": [1, 0], "back": [0, 0]}], moveset="S5", robot_goals=[[0, 0]])
    result = solve(stuck, "bfs")
    assert result.status == "infeasible" and result.schedule is None


def test_limits_give_unsolved_with_a_proved_lower_bound():
    inst = make("TTTTTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[7, 0]])
    result = plan(inst, Options(max_steps=3))  # the search's own proof: nothing within 3 steps
    assert result.status == "unsolved" and result.lower_bound == 4 and result.schedule is None
    assert result.failure.text == "step bound"
    assert solve(inst, "bfs", max_steps=3).lower_bound == 4  # the static bound only where asked for
    assert solve(inst, "bfs", max_steps=3, bound=True).lower_bound == 7


def test_unknown_options_are_rejected():
    inst = make("TT", [{"at": [0, 0]}], moveset="point")
    with pytest.raises(OptionError, match="unknown option 'horizon'"):
        solve(inst, "bfs", horizon=3)
    with pytest.raises(OptionError, match="unknown method"):
        solve(inst, "magic")
    assert "bfs" in METHODS


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_bfs_looks_at_the_clock_inside_one_state(engine):
    # ten point robots: the start state alone has millions of joint actions; a clock that moves
    # one second per look ends the run within them, with the bound it has proved
    from bille.instances.run import Budget, Run
    robots = [{"at": [x, 0]} for x in range(10)]
    inst = make("\n".join(["T" * 10] * 3), robots, moveset="point", collisions="classic",
                robot_goals=[[x, 2] for x in range(10)])
    clock = iter(range(10**6))
    result = plan(inst, Options(engine=engine), run=Run(Budget(2.5, clock=lambda: next(clock))))
    assert result.status == "timeout" and result.failure.text == "time limit"
    assert result.stats["depth"] == 0 and result.lower_bound == 1
