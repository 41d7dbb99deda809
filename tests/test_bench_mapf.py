"""`bille bench mapf` from a fresh clone: the MovingAI maps it uses ship with the package, other
folders come with --maps, and every schedule it reports is valid."""
import pytest

from bille.instances.generators.movingai import from_movingai
from bille.solvers import solve, validate
from bille.tools.bench.mapf import MAPS, map_names, sum_of_costs
from bille.tools.bench.maps import SCENARIO, shipped_maps
from bille.tools.cli import main


def run(capsys, *argv):
    with pytest.raises(SystemExit) as info:
        main(list(argv))
    out, err = capsys.readouterr()
    return info.value.code, out, err


def test_the_default_maps_ship_with_their_scenarios_and_source():
    folder = shipped_maps()
    assert set(MAPS) <= set(map_names(folder))
    readme = (folder / "README.md").read_text()
    assert "movingai.com" in readme and "Licence" in readme
    for name in MAPS:  # every shipped scenario reads, its agents on passable cells of its map
        inst = from_movingai(folder / f"{name}.map", folder / f"{name}{SCENARIO}", agents=20)
        assert inst.num_robots == 20 and name in readme


def test_bench_mapf_runs_on_the_shipped_maps(capsys):
    code, out, err = run(capsys, "bench", "mapf", "--names", "room-32-32-4", "--agents", "5")
    assert code == 0 and "room-32-32-4" in out and "feasible" in out, err
    inst = from_movingai(shipped_maps() / "room-32-32-4.map", shipped_maps() / f"room-32-32-4{SCENARIO}", agents=5)
    result = solve(inst, "lacam", improve=0.0)
    assert validate(inst, result.schedule).valid and sum_of_costs(inst, result.schedule) > 0


def test_bench_mapf_reads_another_folder_and_names_what_is_missing(capsys, tmp_path):
    for suffix in (".map", SCENARIO):
        (tmp_path / f"mine{suffix}").write_bytes((shipped_maps() / f"random-32-32-10{suffix}").read_bytes())
    code, out, _ = run(capsys, "bench", "mapf", "--maps", str(tmp_path), "--agents", "3")
    assert code == 0 and "mine" in out
    code, out, err = run(capsys, "bench", "mapf", "--maps", str(tmp_path), "--names", "nowhere", "--agents", "3")
    assert code == 2 and out == "" and "nowhere" in err and "Traceback" not in err


def test_peer_schedules_are_checked_by_the_validator():
    from bille.tools.bench.peers import checked, peers_table

    inst = from_movingai(shipped_maps() / "room-32-32-4.map", shipped_maps() / f"room-32-32-4{SCENARIO}", agents=2)
    result = solve(inst, "lacam", improve=0.0)
    from bille.instances.schedule import bind

    plan = [[tuple(r.front) for r in inst.robots]]
    poses = list(inst.start_state.poses)
    for t in range(result.schedule.length):  # bille's own schedule as a peer's cells per step
        for i, row in enumerate(bind(inst, result.schedule)):
            poses[i] = int(inst.world.graphs[i].succ[poses[i], row[t]])
        plan.append([(int(inst.world.graphs[i].feet[p, 0]) % inst.width, int(inst.world.graphs[i].feet[p, 0]) // inst.width)
                     for i, p in enumerate(poses)])
    good = checked(inst, plan)
    assert good == {"status": "feasible", "soc": sum_of_costs(inst, result.schedule)}
    teleport = [plan[0], plan[-1]]  # every robot jumps to its goal in one step
    assert checked(inst, teleport)["status"] == "invalid"
    clash = [plan[0], [plan[0][0], plan[0][0]]]  # robot 1 jumps onto robot 0
    assert checked(inst, clash)["status"] == "invalid"
    assert checked(inst, [plan[0][::-1]] + plan[1:])["status"] == "other agents"
    rows = [dict(map="room", agents=2, status="feasible", time_s=1.0, first_s=1.0, scatter_s=0.25, soc=good["soc"],
                 peers={"lacam3": {"status": "feasible", "time_s": 0.5, "soc": good["soc"]}})]
    lines = peers_table(rows, ["lacam3"])
    assert "2.00x" in lines[2] and "1.000" in lines[2] and "25 %" in lines[2] and "bille 2, lacam3 2" in lines[-2]


def test_bench_scale_measures_lacam_against_the_static_bound(capsys):
    from bille.tools.bench.scale import scale_instance, scale_rows

    inst = scale_instance(16, 6, 0.15, seed=1)
    assert inst.num_robots == 6 and int(inst.start.obstacles.sum()) == int(0.15 * 256)
    (row,) = scale_rows(16, [6], [0.15], seed=1, temporal_steps=2)
    assert row["valid"] and row["bound"] <= row["makespan"] and row["temporal_ms"] is not None
    result = solve(inst, "lacam", improve=0.0)
    assert validate(inst, result.schedule).valid
    code, out, err = run(capsys, "bench", "scale", "--size", "16", "--robots", "4", "--obstacles", "10")
    assert code == 0 and "lower bound" in out, err
    code, _, err = run(capsys, "bench", "scale", "--obstacles", "60")
    assert code == 2 and "below 50" in err


def goals_all_standable(inst) -> bool:
    """Every robot can stand at its goal cell (front foot) at once: a matching of robots to back
    feet that are no robot's goal cell, each in a goal pose the robot can walk to."""
    import networkx as nx

    from bille.instances.walking import UNREACHABLE, walk_for

    tiles = inst.start.tiles
    walk = walk_for(inst.world.graphs[0], tiles)
    goal_cells = {inst.start.cell(*g) for g in inst.robot_goals if g is not None}
    graph = nx.Graph()
    robots = []
    for r, (pose, goal) in enumerate(zip(inst.start_state.poses, inst.robot_goals)):
        if goal is None:
            continue
        robots.append(("robot", r))
        reach = walk.from_pose(pose)
        for g in walk.goal_poses(inst.start.cell(*goal)).tolist():
            back = int(walk.graph.feet[g, 1])
            if reach[g] < UNREACHABLE and back not in goal_cells:
                graph.add_edge(("robot", r), ("cell", back))
    if len(graph.nodes) == 0:
        return not robots
    matching = nx.bipartite.maximum_matching(graph, top_nodes=[n for n in graph if n[0] == "robot"])
    return all(r in matching for r in robots)


@pytest.mark.parametrize("seed", range(4))
def test_bench_scale_goals_leave_room_for_every_robot(seed):
    from bille.tools.bench.scale import scale_instance

    inst = scale_instance(16, 50, 0.2, seed)  # a robot per four free cells
    assert sum(g is not None for g in inst.robot_goals) == 50
    assert goals_all_standable(inst)


def test_bench_mapf_optimal_compares_the_exact_methods_with_a_table_and_csv(capsys, tmp_path):
    import csv

    out = tmp_path / "opt.csv"
    code, text, err = run(capsys, "bench", "mapf", "--optimal", "--names", "room-32-32-4", "--agents", "3",
                          "--time-limit", "5", "--csv", str(out))
    assert code == 0, err
    rows = list(csv.DictReader(out.read_text().splitlines()))
    by = {r["method"]: r for r in rows}
    assert set(by) == {"cbs", "basic CBS", "joint A*"}
    assert by["cbs"]["status"] == "optimal" and by["cbs"]["sum_of_costs"] == by["basic CBS"]["sum_of_costs"]
    inst = from_movingai(shipped_maps() / "room-32-32-4.map", shipped_maps() / f"room-32-32-4{SCENARIO}", agents=3)
    result = solve(inst, "cbs")
    assert validate(inst, result.schedule).valid and str(result.stats["sum_of_costs"]) == by["cbs"]["sum_of_costs"]
    if by["joint A*"]["status"] == "optimal":
        assert by["joint A*"]["sum_of_costs"] == by["cbs"]["sum_of_costs"]


def test_the_sum_of_costs_in_the_metrics_is_the_benchmarks_and_cbss():
    from bille.heuristics.cbs import plan as cbs
    from bille.instances import load_instance
    from bille.instances.bundled import bundled_path
    from bille.solvers import load_schedule

    inst = from_movingai(shipped_maps() / "room-32-32-4.map", shipped_maps() / f"room-32-32-4{SCENARIO}", agents=8)
    found = cbs(inst)
    report = validate(inst, found.schedule)
    assert report.valid
    assert found.status == "optimal" and report.metrics.sum_of_costs > 0
    assert report.metrics.sum_of_costs == sum_of_costs(inst, found.schedule) == found.stats["sum_of_costs"]
    lt = load_instance(bundled_path("lt-1"))  # no robot has a goal cell: no sum of costs
    assert not any(c >= 0 for c in lt.goal_cells)
    shipped = validate(lt, load_schedule(str(bundled_path("lt-1")).replace(".yaml", ".schedule.yaml")))
    assert shipped.valid and "sum_of_costs" not in shipped.metrics.to_json()


FAKE_LACAM3 = """#!{python}
import sys
args = dict(zip(sys.argv[1::2], sys.argv[2::2]))
open(args["-o"], "w").write("solved=1\\ncomp_time=7\\ncomp_time_initial_solution=7\\nsolution=\\n0:(0,0),\\n")
open({marker!r}, "w").write(args["-N"])
"""


def test_bench_mapf_runs_a_peer_named_by_its_path(capsys, tmp_path):
    # --against lacam3 PATH runs that program on the same agents and checks what it returns with
    # the validator: this stand-in answers with one robot at (0, 0), which the check refuses
    import sys

    fake, marker = tmp_path / "main", tmp_path / "ran"
    fake.write_text(FAKE_LACAM3.format(python=sys.executable, marker=str(marker)))
    fake.chmod(0o755)
    code, out, err = run(capsys, "bench", "mapf", "--names", "room-32-32-4", "--agents", "3",
                         "--against", "lacam3", str(fake))
    assert code == 0 and marker.read_text() == "3", err
    assert "lacam3 [s]" in out and "other agents" in out and "geometric mean" not in out
    code, out, err = run(capsys, "bench", "mapf", "--names", "room-32-32-4", "--agents", "3",
                         "--against", "pypibt", str(tmp_path))
    assert code == 2 and out == "" and "not pypibt's repository folder" in err and "Traceback" not in err


FAKE_CBSH2 = """#!{python}
# a stand-in for CBSH2-RTC: its command line and its CSV, the optimum taken from bille's cbs (+ offset)
import sys
from bille.instances.generators.movingai import from_movingai
from bille.solvers import solve
args = dict(zip(sys.argv[1::2], sys.argv[2::2]))
result = solve(from_movingai(args["-m"], args["-a"], agents=int(args["-k"])), "cbs")
cost = result.stats["sum_of_costs"] + {offset}
open(args["-o"], "w").write("runtime,#high-level expanded,solution cost,min f value,preprocessing runtime,solver name\\n"
                            f"0.25,3,{{cost}},{{cost}},0.25,WDG+R+C+T+BP with AStar\\n")
"""


@pytest.mark.parametrize("offset", [0, 1])
def test_bench_peers_sets_bille_beside_an_optimal_peer(capsys, tmp_path, offset):
    import sys

    fake = tmp_path / "cbs"
    fake.write_text(FAKE_CBSH2.format(python=sys.executable, offset=offset))
    fake.chmod(0o755)
    code, out, err = run(capsys, "bench", "peers", "--cbsh2-rtc", str(fake), "--optimal-rows",
                         "room-32-32-4:2,3", "--time-limit", "10")
    assert code == 0, err
    assert "room-32-32-4 2 agents: bille" in err and "cbsh2-rtc [s]" in out
    assert "geometric mean time ratio" in out and "over 2 rows both solved" in out
    assert ("DIFFERENT COST" in out) == (offset == 1)  # a peer's optimum that differs from bille's is flagged


def test_bench_peers_refuses_what_it_cannot_run(capsys, tmp_path):
    code, out, err = run(capsys, "bench", "peers")
    assert code == 2 and "name at least one peer's program" in err and out == ""
    script = tmp_path / "cbs"
    script.write_text("not a program")
    code, out, err = run(capsys, "bench", "peers", "--cbsh2-rtc", str(script))
    assert code == 2 and "not an executable program" in err
    script.chmod(0o755)
    code, out, err = run(capsys, "bench", "peers", "--cbsh2-rtc", str(script), "--optimal-rows", "nowhere:3")
    assert code == 2 and "nowhere: no NAME.map" in err
    code, out, err = run(capsys, "bench", "peers", "--cbsh2-rtc", str(script), "--optimal-rows", "room-32-32-4:x")
    assert code == 2 and "must be whole numbers" in err
