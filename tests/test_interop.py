"""bille convert: MovingAI and libMultiRobotPlanning both ways, and the poses of check --poses."""
import csv
import json

import numpy as np
import pytest

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.schedule import load_schedule, save_schedule
from bille.solvers import solve, validate
from bille.tools.cli import main
from helpers import make


def cli(capsys, *argv):
    with pytest.raises(SystemExit) as done:
        main([str(a) for a in argv])
    out = capsys.readouterr()
    return done.value.code, out.out, out.err


def same_problem(a, b):
    assert (a.width, a.height, a.num_robots) == (b.width, b.height, b.num_robots)
    assert np.array_equal(a.start.tiles, b.start.tiles) and np.array_equal(a.goal_tiles, b.goal_tiles)
    assert a.start_state.poses == b.start_state.poses and list(a.goal_cells) == list(b.goal_cells)


@pytest.fixture
def mapf(tmp_path):
    inst = make("TTTTT\nT.T.T\nTTTTT", [{"at": [0, 0]}, {"at": [4, 2]}, {"at": [2, 1]}], moveset="point",
                robot_goals=[[4, 2], [0, 0], [2, 0]], collisions="classic")
    path = tmp_path / "mine.yaml"
    from bille.instances import save_instance

    save_instance(inst, path)
    return inst, path


@pytest.mark.parametrize("target", ["out.mrp.yaml", "out.scen"])
def test_instances_round_trip(mapf, tmp_path, capsys, target):
    inst, path = mapf
    assert cli(capsys, "convert", path, tmp_path / target)[0] == 0
    assert cli(capsys, "convert", tmp_path / target, tmp_path / "back.yaml")[0] == 0
    back = load_instance(tmp_path / "back.yaml")
    same_problem(inst, back)
    assert back.collisions == "classic"
    if target.endswith(".scen"):
        assert (tmp_path / "out.map").read_text().startswith("type octile\nheight 3\nwidth 5\nmap\n")
        rows = (tmp_path / "out.scen").read_text().splitlines()
        assert rows[0] == "version 1" and rows[1].split("\t")[4:] == ["0", "0", "4", "2", "6"]


def test_schedules_round_trip_through_libmultirobotplanning(mapf, tmp_path, capsys):
    inst, path = mapf
    found = solve(inst, "lacam", time_limit=10)
    save_schedule(found.schedule, tmp_path / "s.yaml")
    assert cli(capsys, "convert", tmp_path / "s.yaml", tmp_path / "s.mrp.yaml", "--instance", path)[0] == 0
    import yaml

    data = yaml.safe_load((tmp_path / "s.mrp.yaml").read_text())
    assert data["statistics"]["makespan"] == found.metrics.makespan
    assert data["schedule"]["agent0"][0] == {"x": 0, "y": 0, "t": 0}
    assert cli(capsys, "convert", tmp_path / "s.mrp.yaml", tmp_path / "back.yaml", "--instance", path)[0] == 0
    back = load_schedule(tmp_path / "back.yaml")
    report = validate(inst, back)
    assert report.valid and report.metrics.makespan == found.metrics.makespan


@pytest.mark.parametrize("source, why", [("lt-4", "two-footed"), ("corridor-2", "two-footed")])
def test_formats_that_cannot_hold_an_instance_say_why(tmp_path, capsys, source, why):
    code, out, err = cli(capsys, "convert", source, tmp_path / "x.mrp.yaml")
    assert code == 2 and why in err and not (tmp_path / "x.mrp.yaml").exists()


def test_moving_tiles_and_missing_goals_are_refused(tmp_path, capsys):
    from bille.instances import save_instance

    moving = make("TTT.\n....", [{"at": [1, 0]}], goal="TT..\n.T..", moveset="point")
    save_instance(moving, tmp_path / "m.yaml")
    code, _, err = cli(capsys, "convert", tmp_path / "m.yaml", tmp_path / "m.scen")
    assert code == 2 and "tiles move" in err and not (tmp_path / "m.map").exists()
    code, _, err = cli(capsys, "convert", bundled_path("compare-2").with_suffix(".map"), tmp_path / "x.yaml")
    assert code == 2


def test_check_writes_poses(tmp_path, capsys):
    out = tmp_path / "p.csv"
    assert cli(capsys, "check", "corridor-2", "corridor-2.schedule", "--poses", out)[0] == 0
    rows = list(csv.DictReader(out.read_text().splitlines()))
    inst = load_instance(bundled_path("corridor-2"))
    makespan = validate(inst, load_schedule(bundled_path("corridor-2.schedule"))).metrics.makespan
    assert len(rows) == inst.num_robots * (len(load_schedule(bundled_path("corridor-2.schedule")).actions[0]) + 1)
    assert rows[0]["heading"] in "NESW" and rows[0]["action"] == ""
    placed = [r for r in rows if r["placed"]]
    assert len(placed) == 1 and int(placed[0]["step"]) <= makespan
    js = tmp_path / "p.json"
    assert cli(capsys, "check", "corridor-2", "corridor-2.schedule", "--poses", js)[0] == 0
    data = json.loads(js.read_text())
    assert data["rows"][0]["step"] == 0 and len(data["rows"]) == len(rows)
