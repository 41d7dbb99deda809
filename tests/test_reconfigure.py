"""The reconfiguration loop: sequences, allocation, manipulation rules, load transfer."""
from __future__ import annotations

import numpy as np
import pytest

from bille.heuristics.loop.allocation import Allocation
from bille.heuristics.loop.goals import Goals
from bille.heuristics.loop.manipulation import Manipulation
from bille.heuristics.loop import reconfigure
from bille.heuristics.loop.motion import MOTIONS, TemporalAStar
from bille.heuristics.loop.reconfigure import DEADLOCK, Leg, Loop, LoopState
from bille.heuristics.loop.sequence import NoSequence, SequenceError, check, derive, sequence_of
from bille.heuristics.loop.transfer import LoadTransfer
from bille.heuristics.temporal_astar import Options as LoopRecord
from bille.instances import OptionError, instance_from_text, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.generators.random import random_reconfiguration
from bille.instances.grid import is_connected
from bille.instances.moveset import Kind
from bille.instances.run import Run
from bille.instances.rules import State, apply
from bille.instances.schedule import Schedule
from bille.solvers import solve, validate
from helpers import make, manipulations
from bille.tools.cli import main


def plan(inst, motion="temporal-astar", run=None, **options):
    """The loop with a motion layer and Temporal A*'s options record (the loop's and its own)."""
    record = LoopRecord(**options)
    record.check_instance(inst)
    return reconfigure.plan(inst, record, run, motion=motion)


def cli(capsys, *argv):
    with pytest.raises(SystemExit) as info:
        main(list(argv))
    out, err = capsys.readouterr()
    return info.value.code, out, err


def bundled(name):
    return load_instance(bundled_path(name))


def cell(inst, x, y):
    return y * inst.width + x


# ---- sequences ---------------------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(6))
def test_a_derived_sequence_keeps_the_structure_connected_one_task_at_a_time(seed):
    inst = random_reconfiguration(14, 14, 45, 2, 8, seed=seed)
    jobs = derive(inst)
    assert len(jobs) == 8
    tiles = inst.start.tiles.copy()
    for job in jobs:  # replayed here, independently of check()
        assert tiles[job.pick] and not tiles[job.place]
        tiles[job.pick] = False
        assert is_connected(tiles, inst.width, inst.height)
        tiles[job.place] = True
        assert is_connected(tiles, inst.width, inst.height)
    assert np.array_equal(tiles, inst.goal_tiles)


def test_a_tile_that_stays_moves_out_of_the_way_and_back():
    # the one tile to move, (0, 0), cannot go first (the rest would fall apart), and the robot
    # stands on the only other tile it could fill (1, 1) from: the tile under it serves first
    inst = make("TT.\nT..", [{"at": [0, 1]}], goal=".T.\nTT.", moveset="point", robot_goals=[[0, 1]])
    jobs = derive(inst)
    assert [(inst.world.xy(j.pick), inst.world.xy(j.place)) for j in jobs] == [((0, 1), (1, 1)), ((0, 0), (0, 1))]
    check(inst, jobs)
    for method in ("temporal-astar", "mstar", "lacam"):
        result = solve(inst, method, time_limit=30)
        assert result.status == "feasible" and "loop" not in result.stats, (method, result.stats)
        assert validate(inst, result.schedule).valid
        assert result.metrics.makespan >= solve(inst, "bfs").metrics.makespan


def test_a_derivation_that_exhausts_its_search_says_so():
    # an S7 robot in a one-row corridor cannot turn with the tile: no job can run at all
    inst = make("TTTT.", [{"front": [2, 0], "back": [3, 0]}], goal=".TTTT")
    with pytest.raises(NoSequence, match="all 1 tile sets they reach were searched"):
        derive(inst)
    paper = solve(inst, "temporal-astar", time_limit=30)
    assert paper.status == "unsolved" and "were searched" in paper.failure.text
    assert solve(inst, "bfs").status == "infeasible"
    assert solve(inst, "lacam", time_limit=30).status == "infeasible"  # the whole-state search agrees


def test_given_tasks_are_used_as_given():
    inst = bundled("lt-4")
    jobs = sequence_of(inst)
    assert [(inst.world.xy(j.pick), inst.world.xy(j.place)) for j in jobs] == [(t.pick, t.place) for t in inst.tasks]


def test_a_carried_tile_becomes_a_delivery():
    jobs = sequence_of(bundled("corridor-2"))
    assert len(jobs) == 1 and jobs[0].pick is None and jobs[0].carrier == 1


BAD_TASKS = {
    "picks an empty cell": ("{pick: [0, 0], place: [4, 1]}", "holds no tile"),
    "places on a tile": ("{pick: [0, 1], place: [2, 1]}", "already holds a tile"),
    "disconnects": ("{pick: [2, 1], place: [4, 1]}", "disconnects the structure"),
    "misses the goal": ("{pick: [0, 1], place: [1, 0]}", "do not reach the goal"),
}


def _with_tasks(task: str):
    return instance_from_text(f"""name: bad
moveset: point
grid: |
  .....
  TTTT.
goal: |
  .....
  .TTTT
robots: [{{at: [3, 1]}}]
tasks:
  - {task}
""")


@pytest.mark.parametrize("case", sorted(BAD_TASKS))
def test_bad_tasks_are_named(case):
    task, message = BAD_TASKS[case]
    with pytest.raises(SequenceError, match=message) as info:
        sequence_of(_with_tasks(task))
    assert "tasks" in str(info.value)


@pytest.mark.parametrize("case", sorted(BAD_TASKS))
def test_bad_tasks_exit_2_on_the_command_line(case, tmp_path, capsys):
    task, message = BAD_TASKS[case]
    path = tmp_path / "bad.yaml"
    path.write_text(f"name: bad\nmoveset: point\ngrid: |\n  .....\n  TTTT.\ngoal: |\n  .....\n  .TTTT\n"
                    f"robots: [{{at: [3, 1]}}]\ntasks:\n  - {task}\n")
    for command in (["plan-sequence"], ["solve", "-m", "temporal-astar"]):  # the loop reads the tasks
        code, out, err = cli(capsys, *command, str(path))
        assert code == 2 and out == ""
        lines = err.strip().splitlines()
        assert len(lines) == 1 and message in lines[0] and "tasks" in lines[0]


def test_plan_sequence_prints_the_tasks(capsys):
    code, out, _ = cli(capsys, "plan-sequence", "reconfig-30")
    assert code == 0
    assert "3 tasks (derived)" in out and out.count("pick:") == 3


def test_check_rejects_a_sequence_that_does_not_reach_the_goal():
    inst = bundled("reconfig-30")
    with pytest.raises(SequenceError, match="goal"):
        check(inst, derive(inst)[:2])


# ---- the loop end to end -------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["corridor-2", "reconfig-30", "bridge-2", "lt-1", "lt-4"])
@pytest.mark.parametrize("transfer", [False, True])
def test_every_schedule_of_the_loop_validates(name, transfer):
    inst = bundled(name)
    result = solve(inst, "temporal-astar", horizon=10, load_transfer=transfer)
    if result.schedule is None:  # the loop is not complete; a stop must say why
        assert result.status == "unsolved" and result.failure.text
        return
    assert result.status == "feasible"
    report = validate(inst, result.schedule)
    assert report.valid and report.metrics.makespan == result.metrics.makespan
    assert report.metrics.picks == report.metrics.places - sum(r.carrying for r in inst.robots)


@pytest.mark.parametrize("name", ["corridor-2", "lt-1"])
def test_mstar_as_the_motion_layer(name):
    inst = bundled(name)
    result = solve(inst, "mstar")
    assert result.status == "feasible" and validate(inst, result.schedule).valid
    assert result.stats["motion"] == "mstar"


def test_load_transfer_shortens_a_head_on_bridge():
    # lt-1: one robot per platform; tiles go west to east over a one-tile-wide bridge with a bay
    inst = bundled("lt-1")
    off = solve(inst, "temporal-astar", horizon=10)
    on = solve(inst, "temporal-astar", horizon=10, load_transfer=True, d_tr=5)
    assert on.stats["relays"] > 0
    assert on.metrics.makespan < off.metrics.makespan
    assert on.metrics.tiles_traveled < off.metrics.tiles_traveled


def test_swapping_drop_offs_shortens_tiles_going_both_ways():
    inst = bundled("lt-4")
    off = solve(inst, "temporal-astar", horizon=10)
    on = solve(inst, "temporal-astar", horizon=10, load_transfer=True)
    assert on.stats["swaps"] > 0
    assert on.metrics.makespan < off.metrics.makespan and on.metrics.tiles_traveled < off.metrics.tiles_traveled


# ---- the parts, each given a state ---------------------------------------------------------------

def _state(inst, poses, carrying, legs, jobs=()):
    """A loop state with the instance's start tiles and no job left to hand out but ``jobs``."""
    return LoopState(inst.world, State(inst.start.tiles, tuple(poses), tuple(carrying)), legs, list(jobs), 0,
                     list(range(inst.num_robots)))


def _carriers_on_the_bridge(to0, to1):
    """lt-4 with robot 0 on the bridge heading east and robot 1 three cells east of it heading
    west, both carrying; robot 0 drops at ``to0``, robot 1 at ``to1``."""
    inst = bundled("lt-4")
    g = inst.world.graphs[0]
    poses = (g.pose_of((8, 3), (7, 3)), g.pose_of((11, 3), (12, 3)))
    legs = [[Leg(Kind.PLACE, cell(inst, *to0), 0)], [Leg(Kind.PLACE, cell(inst, *to1), 1)]]
    return inst, _state(inst, poses, (True, True), legs)


def test_the_swap_fires_when_the_drop_offs_lie_past_each_other():
    inst, s = _carriers_on_the_bridge((17, 1), (0, 2))
    chosen = LoadTransfer(inst).decide(s)
    assert [t.kind for t in chosen] == ["swap"] and chosen[0].saving > 0
    assert [inst.world.xy(legs[0].cell) for legs in s.legs] == [(17, 1), (0, 2)]  # a decision, not applied
    s.transfer(chosen[0])
    assert [inst.world.xy(legs[0].cell) for legs in s.legs] == [(0, 2), (17, 1)]


def test_the_swap_does_not_fire_when_each_drop_off_is_on_its_own_side():
    inst, s = _carriers_on_the_bridge((0, 2), (17, 1))
    assert LoadTransfer(inst).decide(s) == []


def test_d_tr_limits_the_pairs_considered():
    inst, s = _carriers_on_the_bridge((17, 1), (0, 2))  # the robots are 3 apart
    far, near = LoadTransfer(inst, d_tr=2), LoadTransfer(inst, d_tr=3)
    assert far.decide(s) == [] and far.stats["pairs_considered"] == 0
    assert near.decide(s) and near.stats["pairs_considered"] == 1


def _relay_on_lt1():
    # robot 0 carries east, about to leave the west platform; robot 1 comes west over the bridge
    # to pick a tile of the west platform: they cannot pass each other on the bridge
    inst = bundled("lt-1")
    g = inst.world.graphs[0]
    x1, x2, a2 = cell(inst, 15, 1), cell(inst, 1, 2), cell(inst, 15, 2)
    legs = [[Leg(Kind.PLACE, x1, 0)], [Leg(Kind.PICK, x2, 1), Leg(Kind.PLACE, a2, 1)]]
    return inst, _state(inst, (g.pose_of((4, 2), (3, 2)), g.pose_of((6, 3), (7, 3))), (True, False), legs)


def test_a_relay_hands_the_jobs_over():
    inst, s = _relay_on_lt1()
    x1, x2, a2 = (leg.cell for leg in s.legs[0] + s.legs[1])
    part = LoadTransfer(inst)
    (t,) = part.decide(s)
    assert t.kind == "relay" and t.giver == 0 and t.taker == 1
    s.transfer(t)
    assert [(leg.kind, leg.cell) for leg in s.legs[0]] == [(Kind.PLACE, t.cell), (Kind.PICK, x2), (Kind.PLACE, a2)]
    assert [(leg.kind, leg.cell) for leg in s.legs[1]] == [(Kind.PICK, t.cell), (Kind.PLACE, x1)]
    assert s.legs[0][0].relay and s.legs[1][0].relay
    assert part.decide(s) == []  # robots in the middle of a relay are left alone


def test_a_backtrack_restores_the_state_and_never_makes_the_transfer_again():
    inst, s = _relay_on_lt1()
    part = LoadTransfer(inst)
    chosen = part.decide(s)
    assert not part.can_backtrack()
    part.remember(s, {"seen"}, {"relays": 0}, chosen)
    s.transfer(chosen[0])
    before, seen, counts = part.backtrack()
    assert [[leg.cell for leg in legs] for legs in before.legs] == [[cell(inst, 15, 1)], [cell(inst, 1, 2), cell(inst, 15, 2)]]
    assert seen == {"seen"} and counts == {"relays": 0} and part.stats["backtracks"] == 1
    assert chosen[0] not in part.decide(before) and not part.can_backtrack()


def test_a_pick_that_would_disconnect_waits():
    inst = bundled("lt-1")
    g = inst.world.graphs[0]
    start = LoopState.start(inst, sequence_of(inst), [0, 1])
    part = Manipulation(inst, start)
    goals = Goals(inst, part)
    bridge = cell(inst, 5, 3)  # the first bridge tile: picking it splits the structure
    legs = [[Leg(Kind.PICK, bridge, 0), Leg(Kind.PLACE, cell(inst, 15, 1), 0)], []]
    s = _state(inst, (g.pose_of((4, 3), (3, 3)), g.pose_of((13, 1), (14, 1))), (False, False), legs)
    assert part.decide(s) == ({}, {})
    assert part.stats["deferred_manipulations"] == 1 and 0 not in part.ready(s)
    assert goals.of(s, 0) is None  # it gives way meanwhile
    # the same robot facing a tile of the outer column picks it at once
    legs = [[Leg(Kind.PICK, cell(inst, 1, 1), 0), Leg(Kind.PLACE, cell(inst, 15, 1), 0)], []]
    s = _state(inst, (g.pose_of((2, 1), (3, 1)), s.poses[1]), (False, False), legs)
    fixed, _ = part.decide(s)
    assert list(fixed) == [0] and g.kind[fixed[0]] == Kind.PICK
    assert s.state.tiles[cell(inst, 1, 1)]  # a decision: the state is the loop's to change


def test_allocation_gives_the_next_job_to_the_nearest_idle_robot():
    inst = bundled("lt-3")  # both robots start east; the first pick is on the west platform
    s = LoopState.start(inst, sequence_of(inst), [0, 1])
    decided = Allocation([0, 1]).decide(s)
    first = s.jobs[0].pick
    dists = [int(s.walk(i).facing_distances(first)[p]) for i, p in enumerate(s.poses)]
    nearest = int(np.argmin(dists))
    assert decided == [(nearest, 0), (1 - nearest, 1)] and s.next_job == 0
    assert Allocation([1 - nearest]).decide(s) == [(1 - nearest, 0)]  # only the active robots take jobs
    for robot, k in decided:
        s.assign(robot, k)
    assert s.legs[nearest][0].cell == first and s.next_job == 2
    assert Allocation([0, 1]).decide(s) == []  # no robot is idle


def test_a_goal_is_named_by_what_it_means():
    inst = bundled("lt-3")
    s = LoopState.start(inst, sequence_of(inst), [0, 1])
    s.assign(0, 0)
    goals = Goals(inst, Manipulation(inst, s))
    goal = goals.of(s, 0)
    assert goal.key[-1] == ("pick", s.jobs[0].pick, s.jobs[0].place)
    assert goal.dist[s.poses[0]] == int(s.walk(0).facing_distances(s.jobs[0].pick)[s.poses[0]])
    # the same tiles in another array: the same goal, its plain lists made once
    again = LoopState(inst.world, State(s.state.tiles.copy(), s.poses, s.state.carrying), s.legs, s.jobs, s.next_job)
    assert goals.of(again, 0) is goal and goal.lists[0] == goal.dist.tolist()


@pytest.mark.parametrize("name", sorted(MOTIONS))
def test_a_motion_layer_alone_plans_a_step_the_rules_accept(name):
    inst = bundled("lt-1")
    s = LoopState.start(inst, sequence_of(inst), [0, 1])
    for robot, k in Allocation([0, 1]).decide(s):
        s.assign(robot, k)
    stats = {k: 0 for k in ("priority_shifts", "replans", "cautious_steps", "expanded", "goals_dropped")}
    layer = MOTIONS[name](LoopRecord())
    layer.start(inst, stats)
    goals = Goals(inst, Manipulation(inst, s), parking=layer.parking).all(s)
    assert layer.name == name and all(g is not None for g in goals)
    joint = layer.step(s, {}, goals, {}, None)
    after = apply(inst.world, s.state, joint, step=1)
    assert isinstance(after, State) and after.poses != s.poses  # someone moved towards a pick
    assert sum(g.dist[p] for g, p in zip(goals, after.poses)) < sum(g.dist[p] for g, p in zip(goals, s.poses))


def test_a_motion_layer_given_as_an_object_runs_the_loop():
    inst = bundled("reconfig-30")
    calls = []

    class Counting(TemporalAStar):
        def step(self, s, fixed, goals, intents, budget):
            calls.append(len(s.steps))
            return super().step(s, fixed, goals, intents, budget)

    by_name = plan(inst, motion="temporal-astar", horizon=10)
    given = plan(inst, motion=Counting(horizon=10))
    assert given.status == by_name.status == "feasible" and given.schedule == by_name.schedule
    assert given.method == "temporal-astar" and calls == list(range(len(calls))) and len(calls) > 0
    assert validate(inst, given.schedule).valid


def test_a_transfer_that_leads_into_a_deadlock_is_undone():
    # on lt-5 a relay sends the taker into the room the two carrying robots must leave through
    # the corridor it blocks; the loop goes back to before that relay and never makes it again
    inst = load_instance(bundled_path("lt-5"))
    result = plan(inst, load_transfer=True, d_tr=5, horizon=10)
    assert result.status == "feasible" and result.stats["backtracks"] >= 1
    assert validate(inst, result.schedule).valid


def test_an_early_pick_keeps_the_tile_a_later_place_stands_on():
    # job 6 picks (9, 8), the tile a robot stands on to place job 5's tile at (11, 8); picked
    # early, it left both robots carrying tiles that neither could place (a deadlock)
    inst = random_reconfiguration(15, 15, 60, 2, 10, seed=2)
    loop = Loop(inst, LoopRecord(horizon=10))
    w = inst.width
    assert [(j.pick % w, j.pick // w, j.place % w, j.place // w) for j in loop.s.jobs[5:7]] == [
        (6, 8, 11, 8), (9, 8, 12, 8)]
    result = loop.run("temporal-astar")
    assert result.status == "feasible"
    assert validate(inst, result.schedule).valid


def test_a_sequence_the_loop_cannot_derive_is_unsolved_not_bad_input(capsys, tmp_path):
    # no job can run (an S7 robot cannot turn in a one-row corridor): the derivation gives up,
    # which is a status (exit 1), not bad input (exit 2)
    path = tmp_path / "hard.yaml"
    path.write_text("name: hard\nmoveset: S7\ngrid: |\n  TTTT.\ngoal: |\n  .TTTT\n"
                    "robots: [{front: [2, 0], back: [3, 0]}]\n")
    code, out, _ = cli(capsys, "solve", "-m", "temporal-astar", str(path))
    assert code == 1 and "unsolved" in out
    code, _, err = cli(capsys, "plan-sequence", str(path))
    assert code == 1 and "tile sets they reach were searched" in err


def test_the_sequence_search_reaches_random_instances_with_ten_moved_tiles():
    # bille gen random --robots 4 --moved 10 --seed 2: 2,000 tile sets found no sequence
    from bille.heuristics.loop.sequence import derive
    from bille.instances.generators.random import random_reconfiguration

    inst = random_reconfiguration(10, 8, 30, 4, 10, seed=2)
    jobs = derive(inst)  # checked inside: a valid sequence, ending in the goal's tiles
    assert len(jobs) >= 10


# ---- fewer robots taking jobs ------------------------------------------------------------------

def _manipulators(inst, schedule) -> set[int]:
    return {robot for _, robot, _, _ in manipulations(inst, schedule)}


@pytest.mark.parametrize("motion", ["temporal-astar", "mstar", "lacam"])
@pytest.mark.parametrize("name", ["corridor-2", "reconfig-30"])
def test_only_the_active_robots_take_jobs(motion, name):
    inst = bundled(name)  # on corridor-2 robot 1 carries a tile at the start: it delivers it anyway
    carriers = {i for i, r in enumerate(inst.robots) if r.carrying}
    for active in ([0], [1]):
        result = plan(inst, motion=motion, active=active, run=Run.limited(30))
        assert result.status == "feasible", result.stats
        assert validate(inst, result.schedule).valid
        picking = _manipulators(inst, result.schedule)
        assert picking <= set(active) | carriers
        if not carriers:  # every job went to the active robot
            assert picking == set(active)


def test_active_names_robots_of_the_instance():
    inst = bundled("corridor-2")
    for active in ([2], [], [-1]):
        with pytest.raises(OptionError, match="active must name"):
            plan(inst, active=active)
    for active in ([True], "0,1"):
        with pytest.raises(OptionError, match="active"):
            plan(inst, active=active)
    with pytest.raises(OptionError, match="option active works in the reconfiguration loop only"):
        solve(bundled("compare-2"), "temporal-astar", active=[0])


@pytest.mark.slow
def test_where_every_robot_blocks_the_others_fewer_robots_finish():
    # four robots on a crowded random map: the loop with all four deadlocks; three get through.
    # No time limit anywhere: the runs end at the loop's own bounds, whatever the machine's speed
    from bille.solvers.incumbent import fewer_robots

    inst = random_reconfiguration(10, 8, 30, 4, 10, seed=6)
    for transfer in (False, True):
        assert plan(inst, load_transfer=transfer).failure == DEADLOCK
    found = fewer_robots(inst, None)
    assert found is not None and "+robots" in found.method
    schedule = Schedule.from_ids(inst, found.ids)
    report = validate(inst, schedule)
    assert report.valid and report.metrics.makespan == found.makespan
    assert len(_manipulators(inst, schedule)) < inst.num_robots


IDLE_IN_THE_WAY = dict(grid="TTTTTTT\nTTTTTTT\n.......\n.......", goal="TTTTTTT\nTTTT.TT\nT......\n.......",
                       robots=[{"front": [4, 0], "back": [3, 0]}, {"front": [1, 1], "back": [0, 1]}])


@pytest.mark.parametrize("options", [{}, {"load_transfer": True}, {"horizon": 10}])
def test_an_idle_robot_on_the_only_pose_facing_the_place_is_evicted(options):
    # robot 1 has no job and stands where robot 0 must stand to place its tile at (0, 2)
    inst = make(IDLE_IN_THE_WAY["grid"], IDLE_IN_THE_WAY["robots"], goal=IDLE_IN_THE_WAY["goal"])
    result = plan(inst, **options)
    assert result.status == "feasible", result.failure
    assert result.stats["evictions"] >= 1
    assert validate(inst, result.schedule).valid


def test_a_run_that_does_not_go_round_in_circles_evicts_no_one():
    inst = make(IDLE_IN_THE_WAY["grid"], [IDLE_IN_THE_WAY["robots"][0], {"front": [6, 0], "back": [5, 0]}],
                goal=IDLE_IN_THE_WAY["goal"])
    result = plan(inst)
    assert result.status == "feasible" and result.stats["evictions"] == 0
    assert validate(inst, result.schedule).valid


def test_a_motion_layer_cut_short_says_why():
    from bille.heuristics.loop.joint_motion import DEADLOCK, cut, timed_out
    from bille.instances.run import Budget

    spent = Budget(0.0)
    assert cut(spent).kind == "time-limit" and timed_out(cut(spent))
    stopped = Budget(60.0)
    stopped.cancel()
    assert cut(stopped).kind == "interrupted" and timed_out(cut(stopped))
    assert not timed_out(DEADLOCK) and not timed_out(None)
