"""The paper's planners: joint A*, M* and Temporal A* (every schedule goes through the validator)."""

import pytest

from bille.instances import OptionError, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.failure import Failure
from bille.solvers import solve, validate
from helpers import make
from refsearch import optimal_soc

PLANNERS = ["astar", "mstar", "temporal-astar"]

SMALL = {
    "corridor-bay": lambda: make("TTTTT\n..T..", [{"at": [0, 0]}, {"at": [4, 0]}], moveset="point",
                                 robot_goals=[[4, 0], [0, 0]]),
    "crowded-2": lambda: load_instance(bundled_path("crowded-2")),
    "s5-swap": lambda: make("TTTTT\nTTTTT", [{"front": [1, 0], "back": [0, 0]}, {"front": [3, 0], "back": [4, 0]}],
                            moveset="S5", robot_goals=[[4, 0], [0, 0]]),
    # robot 0 starts on its goal and must step into the bay to let robot 1 through: the steps it
    # waited at its goal are paid when it leaves
    "leave-goal": lambda: make("TTTTT\n.T...", [{"at": [1, 0]}, {"at": [4, 0]}], moveset="point",
                               robot_goals=[[1, 0], [0, 0]]),
    "one-goal": lambda: make("TTTT\nTTTT", [{"front": [1, 0], "back": [0, 0]}, {"front": [2, 1], "back": [3, 1]}],
                             robot_goals=[[3, 0], None]),
}


def soc(result):
    return result.stats["sum_of_costs"], result.metrics.makespan


@pytest.mark.parametrize("name", SMALL)
def test_astar_and_mstar_are_optimal_against_brute_force(name):
    inst = SMALL[name]()
    expected = optimal_soc(inst)
    for method, opts in [("astar", {}), ("mstar", {"od": False}), ("mstar", {"od": True})]:
        result = solve(inst, method, **opts)
        assert result.status == "optimal"
        assert validate(inst, result.schedule).valid
        assert soc(result) == expected, (method, opts)


@pytest.mark.parametrize("name", ["compare-2", "compare-3", "compare-4", "point-4", "crowded-3"])
def test_astar_and_mstar_agree_on_bundled_maps(name):
    inst = load_instance(bundled_path(name))
    a, m = solve(inst, "astar", time_limit=120), solve(inst, "mstar", time_limit=120)
    assert a.status == m.status == "optimal"
    assert soc(a) == soc(m)


@pytest.mark.parametrize("method", ["astar", "mstar"])
@pytest.mark.parametrize("epsilon", [2.0, 3.0])
def test_inflated_search_stays_within_epsilon(method, epsilon):
    for name in ("compare-3", "compare-4", "point-4"):
        inst = load_instance(bundled_path(name))
        best = solve(inst, "mstar").stats["sum_of_costs"]
        result = solve(inst, method, epsilon=epsilon, time_limit=120)
        assert result.status == "feasible" and validate(inst, result.schedule).valid
        assert result.stats["sum_of_costs"] <= epsilon * best


@pytest.mark.parametrize("name", ["compare-2", "compare-3", "compare-4", "compare-5", "compare-6", "crowded-3"])
@pytest.mark.parametrize("horizon", [5, 8])
def test_temporal_astar_plans_valid_schedules(name, horizon):
    inst = load_instance(bundled_path(name))
    result = solve(inst, "temporal-astar", horizon=horizon, bound=True)
    assert result.status == "feasible", result.stats
    assert validate(inst, result.schedule).valid
    assert result.metrics.makespan >= result.lower_bound


DEAD_END = dict(grid="TTTTTTTTTT\n...T......\n...T......",
                robots=[{"front": [2, 0], "back": [1, 0]}, {"front": [8, 0], "back": [9, 0]}],
                robot_goals=[[9, 0], [0, 0]])


def test_priority_shifting_resolves_a_deadlock_that_fixed_priorities_cannot():
    # robot 0 (first in Q) heads for the dead end where robot 1 stands; robot 1 cannot get out
    # of its way and must be let through first, while robot 0 waits in the side branch
    inst = make(DEAD_END["grid"], DEAD_END["robots"], robot_goals=DEAD_END["robot_goals"])
    fixed = solve(inst, "temporal-astar", horizon=5, shift_priorities=False)
    assert fixed.status == "unsolved" and fixed.failure == Failure("stuck", "deadlock")
    shifting = solve(inst, "temporal-astar", horizon=5)
    assert shifting.status == "feasible" and shifting.stats["priority_shifts"] >= 1
    assert validate(inst, shifting.schedule).valid
    assert shifting.stats["final_priorities"] == [1, 0]


def test_temporal_astar_reports_failure_quickly():
    # crowded-2: whichever robot goes first walks straight at the other, which cannot reach the
    # bay in time; no order of Q helps (joint A* shows a schedule exists)
    inst = load_instance(bundled_path("crowded-2"))
    result = solve(inst, "temporal-astar", horizon=5)
    assert result.stats["expanded"] < 1_000  # it gives up after a few hundred expansions (153)
    assert result.status == "unsolved" and result.schedule is None
    assert result.failure.text == "deadlock"
    assert solve(inst, "astar").status == "optimal"


@pytest.mark.parametrize("method", PLANNERS)
def test_unreachable_goal_gives_up_before_searching(method):
    # an S5 robot heading east on a line cannot turn around to face west by walking; the
    # planners do not search schedules that move tiles, so they give up without a proof
    inst = make("TTT\n...", [{"front": [1, 0], "back": [0, 0]}], moveset="S5", robot_goals=[[0, 0]])
    result = solve(inst, method)
    assert result.status == "unsolved" and result.stats["unreachable"] == [0]


def test_joint_astar_refuses_reconfiguration_instances():
    with pytest.raises(OptionError, match="moves tiles"):
        solve(load_instance(bundled_path("corridor-2")), "astar")


@pytest.mark.parametrize("method", PLANNERS)
def test_bad_options_are_rejected(method):
    inst = load_instance(bundled_path("compare-2"))
    with pytest.raises(OptionError):
        solve(inst, method, epsilon=0.5)


def test_temporal_astar_rejects_a_bad_horizon_and_queue():
    inst = load_instance(bundled_path("compare-2"))
    with pytest.raises(OptionError, match="horizon"):
        solve(inst, "temporal-astar", horizon=0)
    with pytest.raises(OptionError, match="priorities"):
        solve(inst, "temporal-astar", priorities=[0, 0])


def test_temporal_astar_heeds_its_time_limit_between_replans():
    """On point-4 the first step is planned again 64 times (a blocked robot moves up each time):
    with many robots one step can outlast the time limit, so the deadline is read between
    replans, not only between steps. A clock that gains a second per reading runs out after the
    first replan."""
    from bille.instances.run import Budget

    clock = iter(range(10**6))
    result = solve(load_instance(bundled_path("point-4")), "temporal-astar", time_limit=3,
                   budget=Budget(clock=lambda: next(clock)))
    assert result.status == "timeout" and result.failure.text == "time limit"
    assert result.stats["replans"] <= 1


def test_joint_astar_takes_a_thousand_classic_robots_without_recursion():
    # the joint actions were built by one nested generator per robot: RecursionError before
    robots = [{"at": [x, y]} for y in range(0, 64, 2) for x in range(0, 64, 2)][:1000]
    inst = make("\n".join(["T" * 64] * 64), robots, moveset="point", collisions="classic",
                robot_goals=[[r["at"][0] + 1, r["at"][1]] for r in robots])
    result = solve(inst, "astar", time_limit=1)  # one state has 5**1000 joint actions: the limit ends it
    assert result.status == "timeout" and result.failure.text == "time limit"


def test_an_absurd_horizon_is_refused_before_anything_runs():
    # -H 1000000 ran past 120 s at 2.2 GB with a 5 s limit
    with pytest.raises(OptionError, match="horizon 1,000,000 is more than 10,000 steps"):
        solve(load_instance(bundled_path("compare-2")), "temporal-astar", horizon=1_000_000, time_limit=5)
