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
        assert rows[0] == "version 1" and rows[1].split("\t")[4:] == ["0", "0", "4", "2", "6.00000000"]
        assert rows[1].split("\t")[0] == "1"  # bucket = floor(optimal / 4)


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


# ---- formats that round-trip --------------------------------------------------------------------


def test_a_schedule_converts_with_its_instance_in_any_format(mapf, tmp_path, capsys):
    inst, path = mapf
    save_schedule(solve(inst, "lacam", time_limit=10).schedule, tmp_path / "plan.yaml")
    for fmt in ("p.mrp.yaml", "p.scen"):
        assert cli(capsys, "convert", path, tmp_path / fmt)[0] == 0
    outs = []
    for k, given in enumerate((path, tmp_path / "p.mrp.yaml", tmp_path / "p.scen")):
        code, _, err = cli(capsys, "convert", tmp_path / "plan.yaml", tmp_path / f"plan{k}.mrp.yaml", "--instance", given)
        assert code == 0, err
        outs.append((tmp_path / f"plan{k}.mrp.yaml").read_text())
        code, _, err = cli(capsys, "convert", tmp_path / f"plan{k}.mrp.yaml", tmp_path / f"back{k}.yaml",
                           "--instance", given)
        assert code == 0, err
        assert validate(inst, load_schedule(tmp_path / f"back{k}.yaml")).valid
    assert outs[0] == outs[1] == outs[2]


def test_scenarios_carry_the_octile_optimum_and_its_bucket(tmp_path, capsys):
    from bille.instances import save_instance
    from bille.instances.generators.movingai import from_movingai

    # a 9x9 block: (0, 0) to (8, 8) is eight diagonal steps; round the hole no corner is cut
    inst = make("\n".join(["TTTTTTTTT", "TTTTTT.TT"] + ["TTTTTTTTT"] * 7),
                [{"at": [0, 0]}, {"at": [5, 1]}], moveset="point", robot_goals=[[8, 8], [7, 1]], collisions="classic")
    save_instance(inst, tmp_path / "o.yaml")
    assert cli(capsys, "convert", tmp_path / "o.yaml", tmp_path / "o.scen")[0] == 0
    rows = [r.split("\t") for r in (tmp_path / "o.scen").read_text().splitlines()[1:]]
    assert rows[0][0] == "2" and rows[0][8] == f"{8 * 2 ** 0.5:.8f}"   # 11.31: bucket 2
    assert rows[1][0] == "1" and rows[1][8] == "4.00000000"  # (5, 1) to (7, 1) round the hole: 2.83 cut
    back = from_movingai(tmp_path / "o.map", tmp_path / "o.scen", agents=None)
    assert back.start_state.poses == inst.start_state.poses and list(back.goal_cells) == list(inst.goal_cells)
    # the earlier export (bucket 0, a whole number of 4-connected steps) reads the same
    old = "version 1\n" + "".join("\t".join(["0", "o.map", "9", "9", *r[4:8], "16"]) + "\n" for r in rows)
    (tmp_path / "old.scen").write_text(old)
    again = from_movingai(tmp_path / "o.map", tmp_path / "old.scen", agents=None)
    assert again.start_state.poses == back.start_state.poses


def test_libmultirobotplanning_output_has_statistics_and_paths_that_end_at_the_last_move(tmp_path, capsys):
    import yaml

    from bille.instances import save_instance
    from bille.instances.schedule import Schedule

    inst = make("TTTTT\nTTTTT", [{"at": [0, 0]}, {"at": [0, 1]}], moveset="point", robot_goals=[[1, 0], [4, 1]],
                collisions="classic")
    save_instance(inst, tmp_path / "i.yaml")
    save_schedule(Schedule((("east", "wait", "wait", "wait", "wait"), ("east", "east", "east", "east", "wait")),
                           meta={"time_s": 0.25, "expansions": 12}), tmp_path / "s.yaml")
    assert cli(capsys, "convert", tmp_path / "s.yaml", tmp_path / "s.mrp.yaml", "--instance", tmp_path / "i.yaml")[0] == 0
    data = yaml.safe_load((tmp_path / "s.mrp.yaml").read_text())
    assert data["statistics"] == {"cost": 5, "makespan": 4, "runtime": 0.25, "highLevelExpanded": 12}
    assert [e["t"] for e in data["schedule"]["agent0"]] == [0, 1]  # not padded to the makespan
    assert [e["t"] for e in data["schedule"]["agent1"]] == [0, 1, 2, 3, 4]
    assert cli(capsys, "convert", tmp_path / "s.mrp.yaml", tmp_path / "b.yaml", "--instance", tmp_path / "i.yaml")[0] == 0
    back = load_schedule(tmp_path / "b.yaml")
    assert back.actions == (("east", "wait", "wait", "wait"), ("east", "east", "east", "east"))


# ---- garbage is refused, never rounded ----------------------------------------------------------

MRP = """map:
  dimensions: [5, 3]
  obstacles: [[1, 1], [3, 1]]
agents:
  - name: agent0
    start: [0, 0]
    goal: [4, 2]
  - name: agent1
    start: [4, 2]
    goal: [0, 0]
"""


@pytest.mark.parametrize("old, new, message", [
    ("start: [0, 0]", "start: [0.5, 0]", "i.mrp.yaml:6: agents[0].start: expected a pair of integers [x, y]"),
    ("start: [0, 0]", "start: [true, 0]", "agents[0].start: expected a pair of integers"),
    ("name: agent1", "name: agent0", "i.mrp.yaml:8: agents[1].name: agent name 'agent0' is given twice"),
    ("[[1, 1], [3, 1]]", "[[1, 1], [1, 1]]", "map.obstacles[1]: (1, 1) is listed twice"),
    ("dimensions: [5, 3]", "dimensions: [100000000, 100000000]", "a 100000000x100000000 grid needs about"),
    ("dimensions: [5, 3]", "dimensions: [5, 3]\n  dimensions: [5, 3]", "duplicate key 'dimensions'"),
    ("    goal: [0, 0]", "    goal: [0, 0]\n    speed: 3", "agents[1].speed: unknown field"),
])
def test_libmultirobotplanning_instances_are_read_exactly(tmp_path, rejects, old, new, message):
    (tmp_path / "i.mrp.yaml").write_text(MRP.replace(old, new))
    rejects(["convert", tmp_path / "i.mrp.yaml", tmp_path / "o.yaml"], message)
    assert not (tmp_path / "o.yaml").exists()


PLAN = """schedule:
  agent0:
    - {x: 0, y: 0, t: 0}
    - {x: 1, y: 0, t: 1}
  agent1:
    - {x: 4, y: 2, t: 0}
    - {x: 3, y: 2, t: 1}
"""


@pytest.mark.parametrize("old, new, message", [
    ("{x: 1, y: 0, t: 1}", "{x: 1, y: 0, t: -1}", "p.mrp.yaml:4: schedule.agent0[1].t: time -1 does not come after"),
    ("{x: 0, y: 0, t: 0}\n    - {x: 1, y: 0, t: 1}", "{x: 1, y: 0, t: 1}\n    - {x: 0, y: 0, t: 0}",
     "schedule.agent0[0]: the path starts at (1, 0) at time 1; agent 'agent0' starts at (0, 0)"),
    ("{x: 1, y: 0, t: 1}", "{x: 1, y: 0, t: 0}", "time 0 does not come after time 0"),
    ("agent1:", "bob:", "schedule.bob: agent 'bob' is not an agent of instance"),
    ("{x: 3, y: 2, t: 1}", "{x: 3, y: 1.5, t: 1}", "schedule.agent1[1].y: expected a whole number, got 1.5"),
    ("{x: 3, y: 2, t: 1}", "{x: 3, y: true, t: 1}", "schedule.agent1[1].y: expected a whole number, got True"),
    ("{x: 3, y: 2, t: 1}", "{x: 3, y: 2, t: 100000000000}", "2 robots x 100000000000 steps need about"),
    ("{x: 1, y: 0, t: 1}", "{x: 2, y: 0, t: 1}", "schedule.agent0[1]: from (0, 0) at time 0 to (2, 0) at time 1"),
    ("  agent1:\n    - {x: 4, y: 2, t: 0}\n    - {x: 3, y: 2, t: 1}\n", "", "no path for agent 'agent1'"),
])
def test_libmultirobotplanning_schedules_are_read_exactly(tmp_path, rejects, old, new, message):
    (tmp_path / "i.mrp.yaml").write_text(MRP)
    assert PLAN.replace(old, new) != PLAN
    (tmp_path / "p.mrp.yaml").write_text(PLAN.replace(old, new))
    rejects(["convert", tmp_path / "p.mrp.yaml", tmp_path / "o.yaml", "--instance", tmp_path / "i.mrp.yaml"], message)
    assert not (tmp_path / "o.yaml").exists()


def test_agent_names_of_the_instance_are_kept(tmp_path, capsys):
    (tmp_path / "i.mrp.yaml").write_text(MRP.replace("agent0", "alice").replace("agent1", "bob"))
    (tmp_path / "p.mrp.yaml").write_text(PLAN.replace("agent0", "alice").replace("agent1", "bob"))
    code, _, err = cli(capsys, "convert", tmp_path / "p.mrp.yaml", tmp_path / "p.yaml", "--instance", tmp_path / "i.mrp.yaml")
    assert code == 0, err
    assert cli(capsys, "convert", tmp_path / "p.yaml", tmp_path / "q.mrp.yaml", "--instance", tmp_path / "i.mrp.yaml")[0] == 0
    assert list(yaml_load(tmp_path / "q.mrp.yaml")["schedule"]) == ["alice", "bob"]


def test_a_schedule_keyed_by_index_is_read_in_the_instance_order_and_says_so(tmp_path, capsys):
    # libMultiRobotPlanning's cbs writes agent0, agent1, ... whatever the instance calls them
    (tmp_path / "i.mrp.yaml").write_text(MRP.replace("agent0", "bob").replace("agent1", "alice"))
    (tmp_path / "p.mrp.yaml").write_text(PLAN)
    code, out, err = cli(capsys, "convert", tmp_path / "p.mrp.yaml", tmp_path / "p.yaml", "--instance",
                         tmp_path / "i.mrp.yaml")
    assert code == 0, err
    assert "keyed by index" in out and "(bob, alice)" in out
    assert load_schedule(tmp_path / "p.yaml").actions == (("east",), ("west",))  # bob is agent0


def yaml_load(path):
    import yaml

    return yaml.safe_load(path.read_text())


MAP = "type octile\nheight 3\nwidth 5\nmap\n.....\n.@.@.\n.....\n"


@pytest.mark.parametrize("row, message", [
    ("0\tm.map\t5\t3\t0\t0\t4\t2", "s.scen:2: expected 9 fields"),
    ("0\tm.map\t5\t3\t0\t0\t4\t2\t6\t7", "s.scen:2: expected 9 fields"),
    ("0\tm.map\t6\t3\t0\t0\t4\t2\t6", "s.scen:2: the row says the map is 6x3, the map is 5x3"),
    ("0\tm.map\t5\t3\t0.5\t0\t4\t2\t6", "s.scen:2: the bucket, width, height and coordinates must be whole numbers"),
    ("0\tm.map\t5\t3\t0\t0\t4\t2\tnan", "s.scen:2: expected a bucket of at least 0 and a finite length"),
    ("-1\tm.map\t5\t3\t0\t0\t4\t2\t6", "s.scen:2: expected a bucket of at least 0"),
])
def test_scenario_rows_are_read_exactly(tmp_path, rejects, row, message):
    (tmp_path / "m.map").write_text(MAP)
    (tmp_path / "s.scen").write_text("version 1\n" + row + "\n")
    rejects(["convert", tmp_path / "s.scen", tmp_path / "o.yaml"], message)


def test_a_scenario_that_is_not_text_is_one_line(tmp_path, rejects):
    (tmp_path / "m.map").write_text(MAP)
    (tmp_path / "s.scen").write_bytes(b"version 1\n0\tm.map\t5\t3\t0\t0\t4\t2\t6\xff\xfe\n")
    rejects(["convert", tmp_path / "s.scen", tmp_path / "o.yaml"], "s.scen: not a text file")
    rejects(["convert", tmp_path / "s.scen", tmp_path / "o.yaml", "--map", tmp_path / "m.map"], "not a text file")


def test_a_libmultirobotplanning_map_in_two_parts_is_kept_as_it_is(tmp_path):
    """Free cells in two parts (as in 24 of its 8x8 benchmark instances): each agent stays in its
    own; a goal in the other part is infeasible, proved."""
    from bille.instances.interop import from_mrp

    data = {"map": {"dimensions": [5, 2], "obstacles": [[2, 0], [2, 1]]},
            "agents": [{"name": "a", "start": [0, 0], "goal": [1, 1]}, {"name": "b", "start": [4, 0], "goal": [3, 1]}]}
    inst = from_mrp(data, "two-parts")
    assert int(inst.start.tiles.sum()) == 8
    result = solve(inst, "cbs")
    assert result.status == "optimal" and validate(inst, result.schedule).valid
    assert result.stats["sum_of_costs"] == 4
    data["agents"][1]["goal"] = [0, 1]
    assert solve(from_mrp(data, "apart"), "cbs").status == "infeasible"


def test_a_schedule_keyed_by_the_instance_names_is_read_by_name_even_when_they_look_like_indices(tmp_path, capsys):
    (tmp_path / "i.mrp.yaml").write_text(MRP.replace("agent0", "agentX").replace("agent1", "agent0")
                                         .replace("agentX", "agent1"))
    (tmp_path / "p.mrp.yaml").write_text(PLAN.replace("agent0", "agentX").replace("agent1", "agent0")
                                         .replace("agentX", "agent1"))
    code, out, err = cli(capsys, "convert", tmp_path / "p.mrp.yaml", tmp_path / "p.yaml", "--instance",
                         tmp_path / "i.mrp.yaml")
    assert code == 0, err
    assert "keyed by index" not in out


@pytest.mark.parametrize("target", ["out.mrp.yaml", "out.scen", "plain-named.yaml"])
def test_solve_and_check_read_other_formats_directly(mapf, tmp_path, capsys, target):
    inst, path = mapf
    written = tmp_path / ("out.mrp.yaml" if target == "plain-named.yaml" else target)
    assert cli(capsys, "convert", path, written)[0] == 0
    if target == "plain-named.yaml":  # libMultiRobotPlanning YAML under a plain name: told by its fields
        written = written.rename(tmp_path / target)
    code, out, _ = cli(capsys, "solve", written, "-m", "cbs", "-o", tmp_path / "s.yaml")
    assert code == 0 and out.startswith("cbs: optimal (sum of costs)")
    soc = solve(inst, "cbs").stats["sum_of_costs"]
    assert f"sum of costs {soc}," in out
    assert cli(capsys, "check", written, tmp_path / "s.yaml")[0] == 0
    assert validate(inst, load_schedule(tmp_path / "s.yaml")).valid


def test_a_bound_proved_short_of_the_optimum_is_printed_with_the_schedule(mapf, capsys, tmp_path):
    inst, path = mapf
    code, out, _ = cli(capsys, "solve", path, "-m", "cbs", "-O", "w=3", "-O", "heuristic=none")
    assert code == 0 and out.startswith("cbs: feasible")
    proved = int(out.split("sum of costs >= ")[1].split(" ")[0])
    shown = int(out.split("sum of costs ")[1].split(",")[0])
    assert proved <= solve(inst, "cbs").stats["sum_of_costs"] <= shown <= 3 * proved


def test_an_instance_under_the_bille_rule_is_not_written_as_classic_mapf(tmp_path, capsys):
    # read back, point-4 came as collisions: classic, a different problem (optimum 9 against 10)
    for target in ("p4.mrp.yaml", "p4.scen"):
        code, _, err = cli(capsys, "convert", "point-4", tmp_path / target)
        assert code == 2 and "Bill-E collision rule" in err and not (tmp_path / target).exists()


def test_agents_sharing_a_goal_are_named_in_the_file(tmp_path, capsys):
    # the error named robot_goals[1], a field of no file, and no file
    path = tmp_path / "shared.mrp.yaml"
    path.write_text("map: {dimensions: [4, 4], obstacles: []}\nagents:\n  - {name: a, start: [0, 0], goal: [3, 3]}\n"
                    "  - {name: b, start: [1, 0], goal: [3, 3]}\n")
    code, _, err = cli(capsys, "solve", path, "-m", "cbs")
    assert code == 2 and "shared.mrp.yaml:4: agents[1].goal: (3, 3) is also the goal of agent a" in err
