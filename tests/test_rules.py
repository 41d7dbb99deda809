"""Every rule of docs/rules.md: a correct case accepted, a broken one rejected with the right step,
rule, robot and cells."""
import numpy as np

from bille.instances import State, Violation, apply
from bille.solvers import validate
from helpers import make, sched


def step(inst, *names):
    """Apply one joint action given by action names to the start state."""
    ids = [ms.index[n] for ms, n in zip(inst.movesets, names)]
    return apply(inst.world, inst.start_state, ids)


def broken(result, rule, robot, cells):
    assert isinstance(result, Violation), f"expected a {rule} violation, got a valid step"
    assert (result.rule, result.robot, set(result.cells)) == (rule, robot, set(cells)), result
    return result


def tiles_of(inst, state):
    return {inst.start.xy(c) for c in np.flatnonzero(state.tiles)}


# ---- rule 1: precondition ----------------------------------------------------------------------

LINE2 = """
TTT.
TTTT
"""


def test_pick_of_a_tile_is_accepted_and_removes_it():
    inst = make("TTTT\nTTTT", [{"front": [1, 0], "back": [0, 0]}])
    new = step(inst, "pick")
    assert isinstance(new, State) and new.carrying == (True,)
    assert (2, 0) not in tiles_of(inst, new)


def test_pick_and_place_back_is_a_valid_schedule():
    inst = make("TTTT\nTTTT", [{"front": [1, 0], "back": [0, 0]}])
    report = validate(inst, sched("pick place"))
    assert report.valid and report.metrics.picks == 1 and report.metrics.places == 1


def test_pick_facing_an_empty_cell_is_rejected():
    inst = make(LINE2, [{"front": [2, 0], "back": [1, 0]}])
    broken(step(inst, "pick"), "precondition", 0, [(3, 0)])


def test_pick_while_carrying_is_rejected():
    inst = make(LINE2, [{"front": [1, 0], "back": [0, 0], "carrying": True}], goal="TTTT\nTTTT")
    broken(step(inst, "pick"), "precondition", 0, [(2, 0)])


def test_place_without_a_tile_is_rejected():
    inst = make(LINE2, [{"front": [2, 0], "back": [1, 0]}])
    broken(step(inst, "place"), "precondition", 0, [(3, 0)])


def test_place_on_a_tile_is_rejected_and_on_an_empty_cell_accepted():
    inst = make(LINE2, [{"front": [1, 0], "back": [0, 0], "carrying": True}], goal="TTTT\nTTTT")
    broken(step(inst, "place"), "precondition", 0, [(2, 0)])
    inst = make(LINE2, [{"front": [2, 0], "back": [1, 0], "carrying": True}], goal="TTTT\nTTTT")
    assert validate(inst, sched("place")).valid


def test_place_on_an_obstacle_or_outside_is_rejected():
    inst = make("T#.\nTT.", [{"at": [0, 0], "carrying": True}], goal="T#.\nTTT", moveset="point")
    broken(step(inst, "place-east"), "precondition", 0, [(1, 0)])
    broken(step(inst, "place-west"), "precondition", 0, [(-1, 0)])


# ---- rule 2: workspace -------------------------------------------------------------------------


def test_stepping_off_the_grid_is_rejected():
    inst = make("TTT", [{"front": [2, 0], "back": [1, 0]}])
    broken(step(inst, "fwd"), "workspace", 0, [(3, 0)])
    assert isinstance(step(inst, "back"), State)


def test_sweeping_an_obstacle_is_rejected():
    inst = make("TTT\nTT#", [{"front": [1, 0], "back": [1, 1]}])
    broken(step(inst, "fwd-right"), "workspace", 0, [(2, 1)])  # swept cell
    assert isinstance(step(inst, "fwd-left"), State)


CARRY_MAP = """
.....
#....
TTTTT
TTTTT
"""


def test_a_carried_tile_may_not_pass_an_obstacle():
    inst = make(CARRY_MAP, [{"front": [2, 2], "back": [2, 3], "carrying": True}], goal=".....\n#.T..\nTTTTT\nTTTTT")
    broken(step(inst, "fwd-left"), "workspace", 0, [(0, 1)])
    assert isinstance(step(inst, "fwd-right"), State)
    # without a tile the same motion is fine
    free = make(CARRY_MAP, [{"front": [2, 2], "back": [2, 3]}])
    assert isinstance(step(free, "fwd-left"), State)


# ---- rule 3: collision -------------------------------------------------------------------------

ROW = "TTTT"


def test_swapping_is_rejected():
    inst = make(ROW, [{"at": [0, 0]}, {"at": [1, 0]}], moveset="point")
    broken(step(inst, "east", "west"), "collision", 0, [(0, 0), (1, 0)])


def test_following_into_a_vacated_cell_is_rejected():
    inst = make(ROW, [{"at": [1, 0]}, {"at": [2, 0]}], moveset="point")
    broken(step(inst, "east", "east"), "collision", 0, [(2, 0)])
    assert isinstance(step(inst, "west", "east"), State)  # moving apart is fine


def test_sweeping_through_another_robot_is_rejected():
    # robot 0 heading N at (1,0)/(1,1); fwd-right sweeps (2,1), where robot 1 stands
    inst = make("TTT\nTTT\nTTT", [{"front": [1, 0], "back": [1, 1]}, {"front": [2, 1], "back": [2, 2]}])
    broken(step(inst, "fwd-right", "wait"), "collision", 0, [(2, 1)])
    assert isinstance(step(inst, "fwd-left", "wait"), State)


def test_a_carried_tile_collides_with_another_robot():
    grid = "TTTTT\nTTTTT"
    goal = "TTTTT\nTTTTT\n...T."
    robots = [{"front": [1, 1], "back": [0, 1], "carrying": True}, {"front": [3, 0], "back": [4, 0]}]
    inst = make(grid + "\n.....", robots, goal=goal)
    # robot 0's tile hovers at (2,1); stepping forward carries it over (2,1) and (3,1): free
    assert isinstance(step(inst, "fwd", "wait"), State)
    # robot 1 stepping back-left lands its foot on (3,1)
    broken(step(inst, "fwd", "back-left"), "collision", 0, [(3, 1)])


def test_robots_apart_may_move_together():
    inst = make("TTTTTT", [{"front": [1, 0], "back": [0, 0]}, {"front": [4, 0], "back": [5, 0]}])
    assert validate(inst, sched("fwd back", "fwd back")).valid


# ---- rule 4: support ---------------------------------------------------------------------------


def test_stepping_off_the_structure_is_rejected():
    inst = make("TT.\nTTT", [{"front": [1, 0], "back": [0, 0]}])
    broken(step(inst, "fwd"), "support", 0, [(2, 0)])
    inst = make("TTT\nTTT", [{"front": [1, 0], "back": [0, 0]}])
    assert isinstance(step(inst, "fwd"), State)


def test_a_point_robot_steps_only_onto_tiles():
    inst = make("TT\nT.", [{"at": [0, 1]}], moveset="point")
    broken(step(inst, "east"), "support", 0, [(1, 1)])
    assert isinstance(step(inst, "north"), State)


# ---- rule 5: connectivity ----------------------------------------------------------------------


def test_a_pick_that_splits_the_structure_is_rejected():
    inst = make("TTTTT", [{"at": [0, 0]}], moveset="point")
    broken(step(inst, "pick-east"), "connectivity", None, [(0, 0)])


def test_a_pick_of_a_leaf_tile_is_accepted():
    inst = make("TTTTT", [{"at": [3, 0]}], moveset="point")
    assert isinstance(step(inst, "pick-east"), State)


def test_equal_halves_keep_the_half_with_the_first_cell():
    inst = make("TTTTT", [{"front": [1, 0], "back": [0, 0]}])
    broken(step(inst, "pick"), "connectivity", None, [(3, 0), (4, 0)])


# ---- goal --------------------------------------------------------------------------------------


def test_goal_tiles_must_match_at_the_last_step():
    inst = make("TTTT\n....", [{"at": [0, 0]}], goal="TTT.\n..T.", moveset="point")
    v = validate(inst, sched("wait wait")).violation
    assert (v.step, v.rule, v.robot, v.cells) == (2, "goal", None, ((3, 0), (2, 1)))


def test_robot_goal_cells_must_be_reached():
    inst = make("TTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[2, 0]])
    v = validate(inst, sched("east wait")).violation
    assert (v.step, v.rule, v.robot, v.cells) == (2, "goal", 0, ((2, 0),))
    assert validate(inst, sched("east east wait")).valid


def test_reconfiguration_reaches_its_goal():
    inst = make("TTT.\n....", [{"at": [1, 0]}], goal="TT..\n.T..", moveset="point")
    report = validate(inst, sched("pick-east place-south"))
    assert report.valid and report.metrics.makespan == 2


# ---- ordering, step numbers and metrics --------------------------------------------------------


def test_violation_reports_its_step():
    inst = make("TTTTT", [{"at": [0, 0]}], moveset="point")
    v = validate(inst, sched("east east east east east")).violation
    assert (v.step, v.rule) == (5, "workspace")


def test_lower_rule_number_wins_within_a_step():
    inst = make("TTT.", [{"at": [0, 0]}, {"at": [2, 0]}], moveset="point")
    # robot 0 steps off the grid (rule 2), robot 1 picks an empty cell (rule 1)
    broken(step(inst, "west", "pick-east"), "precondition", 1, [(3, 0)])


def test_lower_robot_wins_within_a_rule():
    inst = make("TTTT", [{"at": [0, 0]}, {"at": [3, 0]}], moveset="point")
    broken(step(inst, "west", "east"), "workspace", 0, [(-1, 0)])


def test_metrics_drop_trailing_waits_and_count_actions():
    inst = make("TTTTT\nTTTTT", [{"front": [1, 0], "back": [0, 0]}, {"front": [2, 1], "back": [3, 1]}])
    m = validate(inst, sched("pick place wait wait", "wait back fwd wait")).metrics
    assert (m.makespan, m.tiles_traveled, m.waits, m.picks, m.places) == (3, 2, 2, 1, 1)


def test_an_empty_schedule_is_valid_when_the_start_is_the_goal():
    inst = make("TT", [{"at": [0, 0]}], moveset="point")
    report = validate(inst, sched(""))
    assert report.valid and report.metrics.makespan == 0
