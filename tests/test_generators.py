"""Generators: valid, deterministic instances; exact Hamiltonian-path decisions."""
from __future__ import annotations

import itertools
import random

import networkx as nx
import numpy as np
import pytest

from bille.instances import InstanceError, dump_instance, instance_from_text, is_connected
from bille.instances.generators.graphs import (grid_graph, hamiltonian_path, parse_graph, random_grid_graph)
from bille.instances.generators.movingai import from_movingai
from bille.instances.generators.bridges import bridges
from bille.instances.generators.random import corridor, crowded, random_reconfiguration
from bille.solvers import solve, validate
from bille.tools.cli import main

GENERATORS = {
    "random": lambda seed: random_reconfiguration(10, 8, 30, 2, 3, seed=seed, tasks=True),
    "random-point": lambda seed: random_reconfiguration(7, 7, 20, 3, 4, seed=seed, moveset="point"),
    "crowded": lambda seed: crowded(6, 4, 3, seed=seed),
    "crowded-S5": lambda seed: crowded(7, 5, 4, seed=seed, moveset="S5"),
    "corridor": lambda seed: corridor(6, 2, seed=seed),
    "corridor-moved": lambda seed: corridor(5, 3, room=4, moved=3, seed=seed),
}
FIXED = {  # generators without a seed
    "bridges": lambda: bridges(tasks=True),
    "bridges-point": lambda: bridges(platforms=3, width=5, height=3, gap=2, bays=(), moved=2, robots=(2, 0, 1),
                                     moveset="point"),
}


@pytest.mark.parametrize("bundled, settings", [
    ("lt-1", {}), ("lt-2", {"gap": 10, "bays": (3, 7)}), ("lt-5", {"width": 5, "robots": (1, 2)}),
    ("lt-8", {"platforms": 3, "width": 5, "gap": 5, "bays": (2,)}),
])
def test_the_bridges_generator_makes_the_load_transfer_maps(bundled, settings):
    from bille.instances import load_instance
    from bille.instances.bundled import bundled_path

    made, shipped = bridges(tasks=True, **settings), load_instance(bundled_path(bundled))
    assert (made.width, made.height, made.moveset.name) == (shipped.width, shipped.height, shipped.moveset.name)
    assert (made.start.tiles == shipped.start.tiles).all() and (made.goal_tiles == shipped.goal_tiles).all()
    assert made.robots == shipped.robots and made.tasks == shipped.tasks


@pytest.mark.parametrize("argv, message", [
    (["--bays", "6"], "bay offset 6 is not on a bridge of 6 columns"),
    (["--robots", "1,1,1"], "3 robot counts for 2 platforms"),
    (["--robots", "0,0"], "at least one in all"),
    (["--moved", "5"], "1 to 4 tiles can move"),
    (["--size", "3x4"], "platforms of at least 4x3 tiles, got 3x4"),
    (["--size", "4by4"], "expected WIDTHxHEIGHT, got '4by4'"),
])
def test_gen_bridges_refuses_numbers_that_make_no_such_map(tmp_path, rejects, argv, message):
    rejects(["gen", "bridges", *argv], message, tmp_path / "b.yaml")


@pytest.mark.parametrize("kind", FIXED)
def test_a_bridges_map_loads_valid_and_a_planner_solves_it(kind):
    inst = instance_from_text(dump_instance(FIXED[kind]()))
    result = solve(inst, "temporal-astar", time_limit=60)
    assert result.schedule is not None and validate(inst, result.schedule).valid


@pytest.mark.parametrize("kind", GENERATORS)
@pytest.mark.parametrize("seed", [0, 1, 7])
def test_generated_instances_load_valid_and_are_deterministic(kind, seed):
    text = dump_instance(GENERATORS[kind](seed))
    assert dump_instance(GENERATORS[kind](seed)) == text
    inst = instance_from_text(text)  # loading checks every validity rule
    assert dump_instance(inst) == text


@pytest.mark.parametrize("kind", GENERATORS)
def test_seeds_differ(kind):
    assert len({dump_instance(GENERATORS[kind](seed)) for seed in range(4)}) > 1


@pytest.mark.parametrize("seed", range(8))
def test_random_reconfiguration_moves_exactly_and_its_tasks_keep_the_tiles_connected(seed):
    inst = random_reconfiguration(9, 9, 28, 2, 5, seed=seed, tasks=True)
    start, goal = inst.start.tiles, inst.goal_tiles
    assert int((start & ~goal).sum()) == int((goal & ~start).sum()) == 5
    tiles = start.copy()
    w = inst.width
    for task in inst.tasks:
        pick, place = task.pick[1] * w + task.pick[0], task.place[1] * w + task.place[0]
        assert tiles[pick] and not tiles[place]
        tiles[pick] = False
        assert is_connected(tiles, w, inst.height)
        tiles[place] = True
        assert is_connected(tiles, w, inst.height)
    assert np.array_equal(tiles, goal)


def test_crowded_goals_are_other_robots_starts():
    inst = crowded(6, 5, 4, seed=3)
    assert [g for g in inst.robot_goals] == [inst.robots[(i + 1) % 4].front for i in range(4)]


def test_corridor_is_one_tile_wide_between_the_rooms():
    inst = corridor(7, 2, room=3)
    t = inst.start.tiles.reshape(inst.height, inst.width)
    hall = t[:, 4 : 4 + 7]
    assert (hall.sum(axis=0) == 1).all()
    result = solve(inst, "mstar", time_limit=60)  # Temporal A* deadlocks head on here, as the paper warns
    assert result.schedule is not None and validate(inst, result.schedule).valid


@pytest.mark.slow
def test_a_generated_reconfiguration_is_solved_exactly():
    inst = random_reconfiguration(6, 5, 10, 1, 1, seed=2)
    for method in ("cpsat", "sat"):
        result = solve(inst, method, time_limit=120)
        assert result.status == "optimal" and validate(inst, result.schedule).valid
    assert solve(inst, "cpsat").metrics.makespan == solve(inst, "bfs", time_limit=120).metrics.makespan


# ---- grid graphs ------------------------------------------------------------------------------

def _brute_force(g: nx.Graph) -> bool:
    return any(all(g.has_edge(a, b) for a, b in zip(p, p[1:])) for p in itertools.permutations(g.nodes))


@pytest.mark.parametrize("seed", range(40))
def test_hamiltonian_path_agrees_with_brute_force(seed):
    g = random_grid_graph(random.Random(seed).randint(2, 7), seed)
    path = hamiltonian_path(g)
    assert (path is not None) == _brute_force(g)
    if path is not None:
        assert sorted(path) == sorted(g.nodes) and all(g.has_edge(a, b) for a, b in zip(path, path[1:]))


@pytest.mark.parametrize("seed", range(10))
def test_hamiltonian_path_from_a_given_start(seed):
    g = random_grid_graph(6, seed)
    for v in g.nodes:
        path = hamiltonian_path(g, start=v)
        expected = any(p[0] == v and all(g.has_edge(a, b) for a, b in zip(p, p[1:]))
                       for p in itertools.permutations(g.nodes))
        assert (path is not None) == expected and (path is None or path[0] == v)


def test_graph_files_in_both_forms():
    drawn = parse_graph("# a T\nooo\n.o.\n")
    listed = parse_graph("0 0\n1 0\n2 0\n1 1\n")
    assert nx.utils.graphs_equal(drawn, listed)
    assert hamiltonian_path(drawn) is None
    assert hamiltonian_path(grid_graph([(x, y) for x in range(3) for y in range(3)])) is not None
    with pytest.raises(InstanceError, match=r"<graph>:2: column 2: unexpected 'x'"):
        parse_graph("oo\nox\n")


# ---- MovingAI -----------------------------------------------------------------------------------

MAP = "type octile\nheight 4\nwidth 6\nmap\n..@...\n..@.T.\n......\n@@....\n"
SCEN = "version 1\n0\tm.map\t6\t4\t0\t0\t5\t3\t8\n0\tm.map\t6\t4\t5\t0\t0\t2\t7\n0\tm.map\t6\t4\t4\t1\t1\t2\t2\n"


def test_movingai_map_and_scenario(tmp_path):
    (tmp_path / "m.map").write_text(MAP)
    (tmp_path / "m.scen").write_text(SCEN)
    inst = from_movingai(tmp_path / "m.map", tmp_path / "m.scen", agents=2)
    assert [r.front for r in inst.robots] == [(0, 0), (5, 0)]
    assert inst.robot_goals == ((5, 3), (0, 2))
    assert inst.moveset.name == "point" and int(inst.start.obstacles.sum()) == 5
    assert inst.collisions == "classic" and inst.meta["agents"] == 2 and inst.meta["scenario"].endswith("m.scen")
    result = solve(inst, "lacam", time_limit=60)
    assert result.status == "optimal" and validate(inst, result.schedule).valid
    bille = from_movingai(tmp_path / "m.map", tmp_path / "m.scen", agents=2, collisions="bille")
    result = solve(bille, "cpsat", time_limit=60)
    assert result.status == "optimal" and validate(bille, result.schedule).valid
    with pytest.raises(InstanceError, match="only 2 agents"):
        from_movingai(tmp_path / "m.map", tmp_path / "m.scen", agents=3)  # the third row starts on a 'T'


# ---- the command line ---------------------------------------------------------------------------

def _run(argv):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    return exc.value.code


def test_gen_writes_a_loadable_instance(tmp_path, capsys):
    out = tmp_path / "r.yaml"
    assert _run(["gen", "random", "--seed", "5", "--tasks", "-o", str(out)]) == 0
    assert dump_instance(instance_from_text(out.read_text())) == out.read_text()
    capsys.readouterr()
    assert _run(["gen", "corridor", "--moved", "2", "--json"]) == 0
    assert '"moved": 2' in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["gen", "graph", "{tmp}/bad.graph"], "unexpected 'x'"),
    (["gen", "graph", "{tmp}/split.graph"], "not connected"),
    (["gen", "random", "--tiles", "10", "--moved", "9"], "cannot move 9 tiles"),
    (["gen", "random", "--tiles", "100", "--width", "5", "--height", "5"], "do not fit"),
    (["gen", "movingai", "{tmp}/m.map", "--agents", "40"], "40 asked"),
])
def test_bad_generator_input_is_one_line_and_exit_2(tmp_path, capsys, argv, message):
    (tmp_path / "bad.graph").write_text("oxo\n")
    (tmp_path / "split.graph").write_text("o.o\n")
    (tmp_path / "m.map").write_text(MAP)
    assert _run([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_gen_json_names_the_file_written_or_none(cli, capsys, tmp_path):
    import json

    assert cli(["gen", "graph", "--vertices", "5", "--json"]) == 0
    said = json.loads(capsys.readouterr().out)
    assert said["written_to"] is None and "path" not in said
    assert cli(["gen", "random", "--json", "-o", tmp_path / "r.yaml"]) == 0
    assert json.loads(capsys.readouterr().out)["written_to"] == str(tmp_path / "r.yaml")


def test_a_shipped_movingai_map_is_named_and_listed(tmp_path):
    from pathlib import Path
    from click.testing import CliRunner
    from bille.tools.cli import cli

    runner = CliRunner()
    made = runner.invoke(cli, ["gen", "movingai", "room-32-32-4", "-k", "5", "-o", str(tmp_path / "r.yaml")])
    assert made.exit_code == 0 and (tmp_path / "r.yaml").exists()
    listed = runner.invoke(cli, ["list", "--maps"])
    assert listed.exit_code == 0 and "room-32-32-4" in listed.output and "random-1.scen" in listed.output
    shipped = Path(__file__).parent.parent / "tools" / "bench" / "movingai" / "room-32-32-4.map"
    too_many = runner.invoke(cli, ["gen", "movingai", str(shipped), "-k", "5000"])
    assert too_many.exit_code != 0 and "room for at most 341 agents" in str(too_many.exception or too_many.output)


def test_a_shipped_map_with_another_scenario_is_read_with_it(tmp_path):
    from click.testing import CliRunner
    from bille.tools.bench.maps import scenario_of, shipped_maps
    from bille.tools.cli import cli

    assert scenario_of(shipped_maps(), "den312d").name == "den312d-dlacam3.scen"
    assert scenario_of(shipped_maps(), "room-32-32-4").name == "room-32-32-4-random-1.scen"
    made = CliRunner().invoke(cli, ["gen", "movingai", "den312d", "-k", "5", "-o", str(tmp_path / "d.yaml")])
    assert made.exit_code == 0 and (tmp_path / "d.yaml").exists()
    from bille.instances.instance import load_instance
    inst = load_instance(tmp_path / "d.yaml")
    assert inst.num_robots == 5 and (inst.width, inst.height) == (65, 81)
