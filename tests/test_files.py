"""Instance and schedule files: exact round trips, bundled data, and one clear error per bad input."""
from pathlib import Path

import pytest

from bille.instances import InstanceError, ScheduleError, dump_instance, instance_from_text, load_instance, save_instance
from bille.instances.bundled import bundled_names, bundled_path
from bille.solvers import Schedule, dump_schedule, load_schedule, save_schedule, schedule_from_text, validate

BUNDLED = bundled_names()


def test_there_are_bundled_instances_with_schedules():
    assert len(BUNDLED) >= 5
    for name in BUNDLED:
        assert bundled_path(f"{name}.schedule").is_file(), name


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_schedule_is_valid(name):
    inst = load_instance(bundled_path(name))
    report = validate(inst, load_schedule(bundled_path(f"{name}.schedule")))
    assert report.valid, report.violation


@pytest.mark.parametrize("name", BUNDLED)
def test_instance_round_trip_is_exact(name, tmp_path):
    inst = load_instance(bundled_path(name))
    text = dump_instance(inst)
    again = instance_from_text(text, name)
    assert again == inst
    assert dump_instance(again) == text
    save_instance(inst, tmp_path / "x.yaml")
    assert load_instance(tmp_path / "x.yaml") == inst


@pytest.mark.parametrize("name", BUNDLED)
def test_schedule_round_trip_is_exact(name, tmp_path):
    sched = load_schedule(bundled_path(f"{name}.schedule"))
    text = dump_schedule(sched)
    assert schedule_from_text(text) == sched
    assert dump_schedule(schedule_from_text(text)) == text
    save_schedule(sched, tmp_path / "s.yaml")
    assert load_schedule(tmp_path / "s.yaml") == sched


def test_meta_and_quoted_names_round_trip():
    text = 'name: "odd: name"\nmoveset: point\ngrid: |\n  TT\nrobots: [{at: [0, 0]}]\nmeta: {source: test, n: 3}\n'
    inst = instance_from_text(text)
    assert inst.name == "odd: name" and inst.meta == {"source": "test", "n": 3}
    assert instance_from_text(dump_instance(inst)) == inst
    sched = Schedule((("east", "west"),), meta={"method": "hand"})
    assert schedule_from_text(dump_schedule(sched)) == sched


def test_moveset_by_path_relative_to_the_instance(tmp_path):
    src = Path(__file__).parent.parent / "instances" / "movesets" / "S5.yaml"
    (tmp_path / "mine.yaml").write_text(src.read_text().replace("name: S5", "name: mine"))
    (tmp_path / "inst.yaml").write_text("moveset: mine.yaml\ngrid: |\n  TTT\nrobots: [{front: [1, 0], back: [0, 0]}]\n")
    inst = load_instance(tmp_path / "inst.yaml")
    assert inst.moveset.name == "mine" and "back-right" not in inst.moveset.index
    assert "moveset: mine.yaml" in dump_instance(inst)


GOOD = """\
name: t
moveset: S7
grid: |
  .....
  TTTTT
  .....
robots:
  - {front: [1, 1], back: [0, 1]}
"""

# (what is wrong, the file text, the expected line, words the message must contain)
BAD_INSTANCES = [
    ("ragged grid", GOOD.replace("  TTTTT\n", "  TTTT\n"), 5, ["row 1", "4 cells", "expected 5"]),
    ("unknown character", GOOD.replace("  TTTTT\n", "  TTXTT\n"), 5, ["row 1, column 2", "'X'"]),
    ("robot off the tiles", GOOD.replace("front: [1, 1], back: [0, 1]", "front: [1, 0], back: [0, 0]"), 8, ["robots[0].front", "not a tile"]),
    ("overlapping robots", GOOD + "  - {front: [1, 1], back: [2, 1]}\n", 9, ["robots[1].front", "also occupied by robots[0]"]),
    ("non-adjacent feet", GOOD.replace("back: [0, 1]", "back: [3, 1]"), 8, ["robots[0]", "not 4-adjacent"]),
    ("unknown moveset", GOOD.replace("moveset: S7", "moveset: S6"), 2, ["moveset", "unknown moveset 'S6'"]),
    ("outside the grid", GOOD.replace("front: [1, 1]", "front: [9, 1]"), 8, ["robots[0].front", "outside the 5x3 grid"]),
    ("disconnected start", GOOD.replace("  .....\n  TTTTT", "  T....\n  .TTTT"), 4, ["grid", "not 4-connected", "(0, 0) is cut off"]),
    ("disconnected goal", GOOD + "goal: |\n  .....\n  .TTTT\n  T....\n", 12, ["goal", "not 4-connected", "(0, 2) is cut off"]),
    ("tile counts", GOOD + "goal: |\n  .....\n  TTTT.\n  .....\n", 9, ["goal", "4 tiles", "5 expected"]),
    ("YAML syntax", GOOD.replace("robots:\n", "robots: [\n"), 8, ["YAML syntax error"]),
    ("empty file", "", None, ["empty"]),
    ("not a mapping", "- 1\n- 2\n", 1, ["expected a mapping"]),
    ("missing field", "grid: |\n  TT\n", 1, ["missing field 'robots'"]),
    ("unknown field", GOOD + "robts: []\n", 9, ["robts", "unknown field"]),
    ("bad coordinate", GOOD.replace("front: [1, 1]", "front: [1, one]"), 8, ["robots[0].front", "pair of integers"]),
    ("goal cell off the goal tiles", GOOD + "robot_goals: [[2, 0]]\n", 9, ["robot_goals[0]", "not a tile"]),
    ("robot_goals length", GOOD + "robot_goals: [null, null]\n", 9, ["robot_goals", "one per robot"]),
    ("shared goal cell", GOOD + "  - {front: [3, 1], back: [4, 1]}\nrobot_goals: [[2, 1], [2, 1]]\n", 10, ["robot_goals[1]", "also the goal of robot 0"]),
    ("carried tile on an obstacle", "grid: |\n  ..#..\n  TTTTT\n  TTTTT\n  .....\ngoal: |\n  ..#..\n  TTTTT\n  TTTTT\n  ..T..\n"
     "robots: [{front: [2, 1], back: [2, 2], carrying: true}]\n", 11, ["robots[0].carrying", "(2, 0)", "obstacle"]),
    ("duplicate key", GOOD + "name: u\n", 9, ["duplicate key 'name'"]),
    ("point robot with feet", GOOD.replace("moveset: S7", "moveset: point"), 8, ["robots[0]", "unknown field"]),
]


@pytest.mark.parametrize("what,text,line,words", BAD_INSTANCES, ids=[b[0] for b in BAD_INSTANCES])
def test_bad_instance_is_one_clear_error(what, text, line, words, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(InstanceError) as info:
        load_instance(path)
    assert_one_clear_line(str(info.value), path, line, words)


def assert_one_clear_line(message, path, line, words):
    """One line, starting with ``file:line:``, holding the words that say what is wrong."""
    assert "\n" not in message
    prefix = f"{path}:{line}: " if line is not None else f"{path}: "
    assert message.startswith(prefix), message
    for word in words:
        assert word in message, message


def test_unknown_field_lists_each_field_once(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(GOOD + "robts: []\n")
    with pytest.raises(InstanceError) as info:
        load_instance(path)
    expected = str(info.value).split("expected one of: ")[1].rstrip(")").split(", ")
    assert len(expected) == len(set(expected)) and {"grid", "robots", "goal", "tasks"} <= set(expected), expected


def test_unreadable_files_name_the_path(tmp_path):
    with pytest.raises(InstanceError, match="no such file"):
        load_instance(tmp_path / "missing.yaml")
    with pytest.raises(InstanceError, match="is a directory"):
        load_instance(tmp_path)
    (tmp_path / "bin.yaml").write_bytes(b"\xff\xfe\x00grid")
    with pytest.raises(InstanceError, match="not UTF-8"):
        load_instance(tmp_path / "bin.yaml")


SCHEDULE = "robots:\n  - [fwd, wait]\n"
BAD_SCHEDULES = [
    ("unknown action", SCHEDULE.replace("fwd", "jump"), 2, ["robots[0][0]", "unknown action 'jump'", "S7"]),
    ("action not in S5", SCHEDULE.replace("fwd", "back-left"), 2, ["unknown action 'back-left'"]),
    ("wrong list lengths", SCHEDULE + "  - [wait]\n", 3, ["robots[1]", "1 actions, expected 2"]),
    ("robot count", SCHEDULE + "  - [wait, wait]\n", 1, ["2 robots", "has 1"]),
    ("not a list", "robots: fwd\n", 1, ["robots", "expected a list"]),
    ("missing action", "robots:\n  - [fwd, null]\n", 2, ["robots[0][1]", "expected an action name, got nothing"]),
    ("YAML syntax", "robots:\n  - [fwd, wait\n", 3, ["YAML syntax error"]),
    ("empty file", "", None, ["empty"]),
]


@pytest.mark.parametrize("what,text,line,words", BAD_SCHEDULES, ids=[b[0] for b in BAD_SCHEDULES])
def test_bad_schedule_is_one_clear_error(what, text, line, words, tmp_path):
    inst = instance_from_text(GOOD.replace("moveset: S7", "moveset: S5" if "S5" in what else "moveset: S7"))
    path = tmp_path / "bad.schedule.yaml"
    path.write_text(text)
    with pytest.raises(ScheduleError) as info:
        validate(inst, load_schedule(path))
    assert_one_clear_line(str(info.value), path, line, words)


def test_save_does_not_leave_partial_files(tmp_path):
    inst = load_instance(bundled_path(BUNDLED[0]))
    with pytest.raises(InstanceError, match="cannot write"):
        save_instance(inst, tmp_path / "no" / "such" / "dir.yaml")
    assert list(tmp_path.iterdir()) == []
