"""Hostile input: every kind is answered by one line on stderr and exit 2, within seconds and
without exhausting memory; nothing half-written."""
from __future__ import annotations

import json

import pytest

from bille.instances.bundled import bundled_path

LAUGHS = "\n".join(
    [f'{k}: &{k} [{", ".join(["*" + p] * 9) if p else ", ".join(["lol"] * 9)}]'
     for k, p in zip("abcdefghi", [None, *"abcdefgh"])])


@pytest.mark.parametrize("where", ["top", "meta", "schedule"])
def test_yaml_aliases_are_refused_before_they_expand(tmp_path, rejects, where):
    instance = tmp_path / "i.yaml"
    schedule = tmp_path / "s.yaml"
    text = bundled_path("corridor-2").read_text()
    sched = bundled_path("corridor-2.schedule").read_text()
    if where == "top":
        text = LAUGHS + "\n" + text
    elif where == "meta":
        text += "meta:\n" + "".join("  " + line + "\n" for line in LAUGHS.splitlines())
    else:
        sched = LAUGHS + "\n" + sched
    instance.write_text(text)
    schedule.write_text(sched)
    rejects(["check", instance, schedule], "YAML aliases")
    if where != "schedule":
        for argv in (["show", instance], ["solve", instance, "-m", "bfs"], ["plan-sequence", instance],
                     ["gap", instance, "--methods", "bfs", "--csv", tmp_path / "g.csv"]):
            rejects(argv, "YAML aliases")
        assert not (tmp_path / "g.csv").exists()


def test_a_grid_too_large_for_memory_is_refused_before_allocating(tmp_path, rejects, monkeypatch):
    monkeypatch.setenv("BILLE_MEMORY_GIB", "0.001")
    path = tmp_path / "big.yaml"
    path.write_text("name: big\nmoveset: S7\ngrid: |\n" + "".join("  " + "T" * 60 + "\n" for _ in range(60))
                    + "robots: [{front: [1, 0], back: [0, 0]}]\n")
    for argv in (["check", path, bundled_path("corridor-2.schedule")], ["solve", path, "-m", "bfs"],
                 ["view", path, "--png", tmp_path / "x.png"]):
        rejects(argv, "a 60x60 grid needs about")
    assert not (tmp_path / "x.png").exists()


def test_a_long_one_row_grid_is_refused_with_the_real_budget(tmp_path, rejects):
    path = tmp_path / "wide.yaml"
    path.write_text("name: wide\nmoveset: S7\ngrid: |\n  " + "T" * 3_000_000 + "\nrobots: [{front: [1, 0], back: [0, 0]}]\n")
    rejects(["solve", path, "-m", "bfs"], "a 3000000x1 grid needs about")


@pytest.mark.parametrize("argv", [
    ["gen", "random", "--width", "100000", "--height", "100000"],
    ["gen", "crowded", "--width", "100000", "--height", "100000", "--robots", "2"],
    ["gen", "corridor", "--room", "100000"],
    ["gen", "hampath", "--vertices", "8", "-s", "100000"],
])
def test_generators_refuse_sizes_that_cannot_fit(tmp_path, rejects, argv):
    rejects(argv, "grid needs about", tmp_path / "g.yaml")


def test_too_many_robots_for_the_planners_tables(tmp_path, rejects, monkeypatch):
    # 60 point robots on a 12x12 block: the grid's tables fit a budget their distance tables do not
    from bille.heuristics.joint import table_bytes
    from bille.instances.generators.random import crowded
    from bille.instances import save_instance
    from bille.instances.limits import GIB, table_bytes as grid_bytes

    inst = crowded(12, 12, 60, holes=0.0, moveset="point")
    path = tmp_path / "many.yaml"
    save_instance(inst, path)
    grid, tables = grid_bytes(inst.moveset, 12, 12), table_bytes(inst)
    assert grid < tables
    monkeypatch.setenv("BILLE_MEMORY_GIB", str((grid + tables) / 2 / GIB))
    for method in ("temporal-astar", "astar", "mstar"):
        rejects(["solve", path, "-m", method], "of distance tables")


@pytest.mark.parametrize("argv, message", [
    (["-m", "cpsat", "-O", "max_makespan=abc"], "option max_makespan expects a whole number"),
    (["-m", "cpsat", "-O", "threads=abc"], "option threads expects a whole number"),
    (["-m", "cpsat", "-O", "time_limit=abc"], "option time_limit expects a finite number"),
    (["-m", "bfs", "-O", "time_limit=nan"], "option time_limit expects a finite number"),
    (["-m", "mstar", "-O", "epsilon=[1,2]"], "option epsilon expects a finite number"),
    (["-m", "sat", "-O", "solver=nosuchsolver"], "unknown solver 'nosuchsolver'"),
    (["-m", "anytime", "-O", "solver=nosuchsolver"], "unknown solver 'nosuchsolver' (expected one of: cpsat,"),
    (["-m", "cpsat", "--time-limit", "nan"], "option time_limit expects a finite number"),
    (["-m", "cpsat", "--time-limit", "inf"], "option time_limit expects a finite number"),
    (["-m", "mstar", "--epsilon", "nan"], "option epsilon expects a finite number"),
    (["-m", "cpsat", "-O", "prune=maybe"], "option prune expects true or false"),
    (["-m", "cpsat", "-O", "nosuch=1"], "unknown option 'nosuch'"),
    (["-m", "temporal-astar", "-O", "horizon=0"], "option horizon expects a number of at least 1"),
])
def test_bad_options_are_one_line(rejects, argv, message):
    rejects(["solve", "corridor-2", *argv], message)


def test_gap_without_methods_is_bad_input(tmp_path, rejects):
    rejects(["gap", "point-4", "--methods", ",,,", "--csv", tmp_path / "g.csv"], "no method named")
    assert not (tmp_path / "g.csv").exists()


@pytest.mark.parametrize("methods, message", [
    (["mstar", "mstar"], "'mstar' is named twice"),
    (["mstar:epsilon=2", "H=3"], "option 'H=3' comes before any method"),
])
def test_gap_reads_each_methods_option_on_its_own(tmp_path, rejects, methods, message):
    argv = ["gap", "point-4", "--csv", tmp_path / "g.csv"]
    for m in methods:
        argv += ["--methods", m]
    rejects(argv, message)
    assert not (tmp_path / "g.csv").exists()


@pytest.mark.parametrize("option", ["--resume", "--secrets"])
def test_binary_files_are_named_not_decoded(tmp_path, rejects, option):
    blob = tmp_path / "blob.bin"
    blob.write_bytes(bytes(range(256)) * 4)
    argv = ["run", "--resume", blob] if option == "--resume" else \
        ["run", "lt-4", "lt-4.schedule", "--robots", "left,right", "--secrets", blob]
    rejects(argv, "not UTF-8 text")


def test_crowded_gives_up_at_once_when_the_robots_cannot_fit(tmp_path, rejects):
    rejects(["gen", "crowded", "--width", "100", "--height", "100", "--robots", "5000", "--moveset", "point"],
            "no crowded 100x100 map with 5000 robots", tmp_path / "c.yaml")


SWEEP = "instances: [crowded-3]\nmethods: {temporal-astar: {}}\n"


@pytest.mark.parametrize("text, message", [
    ("name: ../../../esc3\n" + SWEEP, "name: '../../../esc3' is not a safe file name"),
    ("name: /tmp/abs\n" + SWEEP, "name: '/tmp/abs' is not a safe file name"),
    ('name: "a\\0b"\n' + SWEEP, "is not a safe file name"),
    ("name: ..\n" + SWEEP, "name: '..' is not a safe file name"),
    ("name: [x]\n" + SWEEP, "name: ['x'] is not a safe file name"),
    (SWEEP + "methods: {mstar: {}}\n", "s.yaml:3: duplicate key 'methods'"),
    ("instances: [crowded-3, lt-4, crowded-3]\nmethods: {mstar: {}}\n",
     "instances[2]: 'crowded-3' is the same instance as 'crowded-3'"),
    ("instances: [crowded-3]\nmethods: {temporal-astar: {horizon: [2, 5, 2]}}\n",
     "methods.temporal-astar: the options {'horizon': 2} are listed twice"),
    ("instances: [{gen: 'random --seed 0..100000000'}]\nmethods: {mstar: {}}\n",
     "100000001 instances x 1 method configurations make 100000001 runs, more than max_runs 10000"),
    ("instances: [{gen: 'random --seed 0..3'}]\nmax_runs: 7\nmethods: {mstar: {}, astar: {}}\n",
     "4 instances x 2 method configurations make 8 runs, more than max_runs 7"),
    ("instances: [crowded-3]\nmethods: {temporal-astar: {horizon: [1, 2, 3, 4], epsilon: [1, 2, 3]}}\nmax_runs: 10\n",
     "methods.temporal-astar: 12 option combinations, more than max_runs allows"),
    ("instances: [{gen: 'random --seed 5..3'}]\nmethods: {mstar: {}}\n", "--seed 5..3: an empty range"),
    ("instances: [crowded-3]\nmethods: {mstar: {}}\nmax_runs: 0\n", "max_runs: expected a positive whole number"),
])
def test_bad_sweep_files_are_refused_before_anything_runs(tmp_path, rejects, monkeypatch, text, message):
    monkeypatch.chdir(tmp_path)
    spec = tmp_path / "s.yaml"
    spec.write_text(text)
    rejects(["sweep", spec], message)
    assert [p.name for p in tmp_path.iterdir()] == ["s.yaml"]


def test_max_runs_allows_more(tmp_path):
    from bille.tools.sweep.spec import load_spec

    spec = tmp_path / "s.yaml"
    spec.write_text("instances: [{gen: 'random --seed 0..3'}]\nmax_runs: 8\nmethods: {mstar: {}, astar: {}}\n")
    assert len(load_spec(spec).runs) == 8


@pytest.mark.parametrize("argv, message", [
    (["gen", "graph", "--vertices", "1000000000"], "1000000000 vertices, more than the 1600"),
    (["gen", "hampath", "--vertices", "1000000000"], "1000000000 vertices, more than the 1600"),
    (["gen", "coop", "--vertices", "1000000000"], "1000000000 vertices, more than the 1600"),
    (["gen", "hampath", "--vertices", "3", "--scale", "1000000000"], "the reduction's construction: a 7x2000000021 grid"),
    (["gen", "coop", "--vertices", "30", "--scale", "100000"], "the reduction's construction: a"),
    (["gen", "coop", "--gap", "1000000000"], "the cooperative gadget: a 2000000017x3 grid needs about"),
    (["gen", "coop", "--vertices", "3", "--scale", "100000"], "gen coop: a "),
    (["gen", "corridor", "--room", "2", "--moved", "1", "--robots", "1"], "1 robot does not fit two 2x2 rooms"),
    (["gen", "bridges", "--gap", "1000000000"], "gen bridges: a 1000000011x6 grid needs about"),
    (["gen", "bridges", "--size", "4x1000000"], "gen bridges: a 17x1000002 grid needs about"),
])
def test_generators_check_sizes_before_building(tmp_path, rejects, argv, message):
    # each of these ran for a minute or more, or out of memory
    rejects(argv, message, tmp_path / "g.yaml")


def test_a_large_graph_file_is_refused_before_it_is_searched(tmp_path, rejects):
    graph = tmp_path / "g.txt"
    graph.write_text(("o" * 45 + "\n") * 45)
    rejects(["gen", "graph", graph], "2025 vertices, more than the 1600")


def test_the_hamiltonian_path_search_has_a_step_budget(tmp_path, rejects, monkeypatch):
    from bille.instances.generators import graphs

    monkeypatch.setattr(graphs, "MAX_WORK", 5 * 36)
    graph = tmp_path / "g.txt"
    graph.write_text(("o" * 6 + "\n") * 6)
    rejects(["gen", "graph", graph], "Hamiltonian path is undecided after 5 steps")


def test_the_hamiltonian_path_search_needs_no_deep_stack(tmp_path, cli, capsys):
    # a path 1,200 vertices long: the recursive search ran out of stack (so did a 32x32 grid graph)
    graph = tmp_path / "g.txt"
    graph.write_text("o" * 1200 + "\n")
    assert cli(["gen", "graph", graph, "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)["hamiltonian_path"]) == 1200


@pytest.mark.parametrize("call, message", [
    ("graph --vertices 1000000000", "unknown generator 'graph'"),
    ("hampath --vertices 1000000000", "1000000000 vertices, more than the 1600"),
    ("coop --gap 1000000000", "the cooperative gadget: a 2000000017x3 grid"),
])
def test_generators_in_sweeps_check_sizes_first(tmp_path, rejects, monkeypatch, call, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.yaml").write_text(f"instances: [{{gen: '{call}'}}]\nmethods: {{mstar: {{}}}}\n")
    rejects(["sweep", tmp_path / "s.yaml"], message)


def _point_crowd(width: int, height: int, every: int):
    from bille.instances import instance_from_text

    rows = "".join("  " + "T" * width + "\n" for _ in range(height))
    cells = [(x, y) for y in range(height) for x in range(0, width, 2)][::every]
    robots = "".join(f"  - {{at: [{x}, {y}]}}\n" for x, y in cells)
    goals = ", ".join(f"[{x + 1}, {y}]" for x, y in cells)
    return instance_from_text(f"name: crowd\nmoveset: point\ngrid: |\n{rows}robots:\n{robots}robot_goals: [{goals}]\n")


def test_temporal_astar_per_robot_memory_stays_within_what_the_size_check_counts():
    # 4,000 point robots on a 200x40 grid ran out of a 3 GB address space: every robot copied the
    # pose graph's feet table. The memory one more robot costs must stay within the 40 bytes per
    # pose that the distance-table check counts before it lets a problem in.
    import tracemalloc

    from bille.heuristics.joint import table_bytes
    from bille.solvers import solve, validate

    def peak(inst) -> int:
        tracemalloc.start()
        result = solve(inst, "temporal-astar")
        size = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert result.status == "feasible" and validate(inst, result.schedule).valid
        return size

    few, many = _point_crowd(30, 12, 4), _point_crowd(30, 12, 1)
    peak(many)  # caches warm
    extra = peak(many) - peak(few)
    assert extra <= 1.5 * (table_bytes(many) - table_bytes(few))


# ---- found by the fuzzers (tests/test_fuzz_readers.py) ------------------------------------------


def test_a_value_with_a_line_break_is_quoted_on_one_line(tmp_path, rejects):
    path = tmp_path / "i.yaml"
    path.write_text(bundled_path("corridor-2").read_text().replace("moveset: S7", 'moveset: "S7\\nTTT"'))
    rejects(["show", path], "unknown moveset 'S7\\nTTT'")


def test_a_signature_that_is_not_hex_is_refused_not_compared():
    import json

    from bille.tools.execute.protocol import Gate, Sealer

    msg = json.loads(Sealer("r1", b"k").seal("connection", {"nonce": "n" * 8, "connectionState": "ONLINE"}))
    msg["signature"] = "\x80" + msg["signature"][1:]
    out = Gate({"r1": b"k"}).admit("r1", "connection", json.dumps(msg).encode())
    assert out.reason == "bad signature"


def test_a_signed_order_naming_a_cell_outside_the_grid_fails_the_step():
    from test_fuzz_readers import INITIALIZE, NONCE, SECRET, _Client

    from bille.tools.execute.broker import BrokerURL
    from bille.tools.execute.protocol import Sealer
    from bille.tools.execute.robot import SimRobot

    robot = SimRobot("r1", BrokerURL("127.0.0.1", 1), SECRET)
    robot.client, robot.nonce = _Client(), NONCE
    robot.handle("bille/v1/default/r1/instantActions", INITIALIZE)
    steps = [{"sequenceId": 13, "action": "place", "released": True, "structure": {"picked": [], "placed": [[0, 13]]}}]
    order = Sealer("r1", SECRET, session="1" * 16).seal("order", {"nonce": NONCE, "orderId": "f" * 16,
                                                                   "orderUpdateId": 1, "steps": steps})
    robot.handle("bille/v1/default/r1/order", order)
    assert robot.last_step == 12 and robot.errors[0]["errorType"] == "structureMismatch"
    assert "[0, 13], outside the 10x4 grid" in robot.errors[0]["errorDescription"]


def test_a_movingai_map_of_negative_width_is_refused(tmp_path, rejects):
    (tmp_path / "m.map").write_text("type octile\nheight 3\nwidth -1\nmap\n.....\n")
    (tmp_path / "m.scen").write_text("version 1\n0\tm.map\t5\t3\t0\t0\t4\t2\t6\n")
    rejects(["convert", tmp_path / "m.scen", tmp_path / "o.yaml"], "expected a positive height and width")


def test_a_sweep_named_by_its_file_gets_a_safe_folder_name(tmp_path):
    from bille.tools.sweep.spec import load_spec

    spec = tmp_path / "my sweep (2).yaml"
    spec.write_text(SWEEP)
    assert load_spec(spec).name == "my_sweep__2_"


def test_a_random_structure_grows_in_time_linear_in_its_tiles(monkeypatch):
    # each new tile was drawn from a list rebuilt from all tiles so far: 6,000 tiles took 43 s.
    # Counted without a clock: the neighbourhoods looked at, once per tile now.
    import random as rnd

    from bille.instances.generators import random as gen

    looked = []
    real = gen._around
    monkeypatch.setattr(gen, "_around", lambda c, w, h: looked.append(c) or real(c, w, h))
    tiles = gen._polyomino(60, 60, 1500, rnd.Random(0))
    assert int(tiles.sum()) == 1500 and len(looked) == 1500
