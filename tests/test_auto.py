"""``auto``, the default method: the brute force with proof on a small joint state space, anytime
solving otherwise, and anytime with the rest of the time when the brute force runs out."""
from __future__ import annotations

import dataclasses

import pytest

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.claim import Claim
from bille.instances.failure import Failure
from bille.instances.result import Result
from bille.instances.run import Budget
from bille.solvers import auto, solve, validate

CROWDED = load_instance(bundled_path("crowded-2"))  # about 18,000 joint states: the brute force in a second
LARGE = load_instance(bundled_path("lt-4"))


def test_the_estimate_tells_tiny_maps_from_large_ones():
    assert auto.joint_states(load_instance(bundled_path("point-4"))) <= auto.SMALL < auto.joint_states(
        load_instance(bundled_path("bridge-2")))
    assert auto.joint_states(LARGE) > 10**12


def test_on_a_small_state_space_the_brute_force_proves_the_optimum():
    result = solve(CROWDED)  # auto is the default
    reference = solve(CROWDED, "bfs")
    assert result.method == "auto" and result.stats["auto"]["method"] == "bfs"
    assert "joint states" in result.stats["auto"]["why"]
    assert result.status == "optimal" and validate(CROWDED, result.schedule).valid
    assert result.metrics.makespan == result.lower_bound == reference.metrics.makespan


def test_a_brute_force_out_of_its_share_hands_over_with_its_bound(monkeypatch):
    shares, handed = [], []
    ticks = iter(100 + 0.0063 * k for k in range(1000))  # the run's clock: each look takes 0.0063 s

    def out_of_time(instance, *, run=None, **kw):
        shares.append(run.budget.seconds())
        return Result("bfs", "timeout", lower_bound=9, failure=Failure("time-limit", "time limit"))

    def anytime(instance, *, run, bounds, progress=None):
        handed.append((run.budget.seconds(), bounds.lower, bounds.parts.get("brute force")))
        return Result("anytime", "timeout", lower_bound=bounds.lower)

    monkeypatch.setattr("bille.solvers.bfs.plan", out_of_time)
    monkeypatch.setattr("bille.solvers.anytime.plan", anytime)
    result = solve(CROWDED, "auto", time_limit=20, budget=Budget(clock=lambda: next(ticks)))
    (share,), ((left, lower, proved),) = shares, handed
    given = share / auto.BFS_SHARE  # auto's own time limit: what solve() left after the bound
    assert 0 < result.stats["bound_s"] < 0.1 and given == pytest.approx(20 - result.stats["bound_s"], abs=0.1)
    assert 0 < left <= given and lower == proved == 9  # crowded-2: a static bound below 9
    assert result.lower_bound == 9 and result.stats["auto"]["method"] == "anytime"
    assert "ran out of its" in result.stats["auto"]["why"]


def test_on_a_large_state_space_anytime_runs_from_the_start(monkeypatch):
    handed = []

    def anytime(instance, *, run, bounds, progress=None):
        handed.append(run.budget.seconds())
        return Result("anytime", "timeout", lower_bound=bounds.lower)

    monkeypatch.setattr("bille.solvers.bfs.plan", lambda *a, **k: (_ for _ in ()).throw(AssertionError("bfs ran")))
    monkeypatch.setattr("bille.solvers.anytime.plan", anytime)
    result = solve(LARGE, time_limit=30)
    assert len(handed) == 1 and result.stats["auto"]["method"] == "anytime"
    assert "more than" in result.stats["auto"]["why"]


def test_the_command_line_says_what_auto_chose(cli, capsys):
    assert cli(["solve", "crowded-2"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("auto: optimal in ") and out[1].startswith("auto chose bfs: about ")


def test_classic_mapf_goes_to_conflict_based_search(monkeypatch):
    # libMultiRobotPlanning's mapf_swap2: two robots swap ends of a row with a bay above
    from helpers import make

    inst = make("T.T.\nTTTT\nT..T", [{"at": [0, 1]}, {"at": [3, 1]}], moveset="point", collisions="classic",
                robot_goals=[[3, 1], [0, 1]])
    monkeypatch.setattr("bille.solvers.bfs.plan", lambda *a, **k: (_ for _ in ()).throw(AssertionError("bfs ran")))
    result = solve(inst, time_limit=20)
    assert result.stats["auto"]["method"] == "cbs" and result.status == "optimal"
    assert validate(inst, result.schedule).valid and result.stats["sum_of_costs"] == 8


def test_classic_mapf_hands_over_to_lacam_when_cbs_runs_out(monkeypatch):
    from helpers import make

    inst = make("T.T.\nTTTT\nT..T", [{"at": [0, 1]}, {"at": [3, 1]}], moveset="point", collisions="classic",
                robot_goals=[[3, 1], [0, 1]])
    methods = __import__("bille.solvers.registry", fromlist=["METHODS"]).METHODS
    lacam = methods["lacam"]
    monkeypatch.setitem(methods, "cbs",
                        lambda instance, options, run: Result("cbs", "timeout", claim=Claim("sum-of-costs", lower=7)))
    result = solve(inst, time_limit=20)
    # lacam proves its makespan over walking schedules here: its own claim stands
    assert result.stats["auto"]["method"] == "lacam" and result.status == "optimal"
    assert result.claim == Claim("makespan", walking_only=True) and validate(inst, result.schedule).valid
    # a schedule without proof carries the sum-of-costs bound cbs proved
    monkeypatch.setitem(methods, "lacam", lambda *a, **k: dataclasses.replace(lacam(*a, **k), status="feasible"))
    result = solve(inst, time_limit=20)
    assert result.status == "feasible" and result.claim == Claim("sum-of-costs", lower=7)
    assert validate(inst, result.schedule).valid


def test_a_classic_reconfiguration_goes_to_the_brute_force_whatever_its_size(monkeypatch):
    """lacam plans no tile moves under classic collisions: auto gave an error on a large one."""
    from helpers import make

    inst = make("TTT.\nTTT.", [{"at": [0, 0]}], moveset="point", collisions="classic",
                goal="TTTT\nTT..", robot_goals=[[0, 1]])
    monkeypatch.setattr(auto, "SMALL", 0)  # as large as any
    result = solve(inst, time_limit=20)
    assert result.stats["auto"]["method"] == "bfs" and result.status == "optimal"
    assert validate(inst, result.schedule).valid


def test_the_estimate_of_a_thousand_robots_is_a_number():
    # the exact product of the robots' poses overflowed a float: OverflowError before
    from helpers import make
    robots = [{"at": [x, y]} for y in range(0, 40, 2) for x in range(0, 40, 2)]
    inst = make("\n".join(["T" * 40] * 40), robots, moveset="point")
    assert auto.joint_states(inst) == float("inf")
