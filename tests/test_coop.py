"""Theorem 2's cooperative gadget (``bille gen coop``), alone and attached to Theorem 1's
construction."""
from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from bille.instances import dump_instance, instance_from_text
from bille.instances.generators.coop import LARGE, NO_SPLIT, approaches, attached, demonstration, gadget
from bille.instances.generators.graphs import grid_graph, hamiltonian_path, random_grid_graph
from bille.instances.generators.hampath import bound, search_optimum
from bille.solvers import Schedule, solve, validate
from helpers import manipulations


def _carries_once(inst, schedule) -> bool:
    """Every pick on a cell that holds a tile in the start only, every place on one that holds
    a tile in the goal only: each tile is carried once, straight to its goal."""
    start, goal = inst.start.tiles, inst.goal_tiles
    return all((start[c] and not goal[c]) if what == "pick" else (goal[c] and not start[c])
               for _, _, what, c in manipulations(inst, schedule))


def test_the_gadget_has_the_papers_tasks():
    inst = instance_from_text(dump_instance(gadget()))
    start, goal = inst.start.tiles, inst.goal_tiles
    tiles = [inst.world.xy(c) for c in np.flatnonzero(start & ~goal)]
    places = [inst.world.xy(c) for c in np.flatnonzero(goal & ~start)]
    assert len(tiles) == len(places) == 7 and inst.num_robots == 2
    # six small tasks (a tile two cells from its position) and one large (eight cells)
    small = [(x, y) for x, y in tiles if (x, y + 2) in places]
    assert len(small) == 6
    (large,) = set(tiles) - set(small)
    (target,) = set(places) - {(x, y + 2) for x, y in small}
    assert abs(large[0] - target[0]) + abs(large[1] - target[1]) == LARGE
    assert [r.front for r in inst.robots] == [(large[0], large[1] + 1), (target[0], target[1] + 1)]


@pytest.mark.slow
def test_splitting_the_large_task_beats_every_schedule_that_carries_each_tile_once():
    """The best schedule that carries every tile once, straight to its goal, takes NO_SPLIT
    steps (CP-SAT proves none within NO_SPLIT - 1); the demonstration, which sets the large
    task's tile down half way for the other robot, takes fewer. So every optimal schedule
    splits the large task."""
    inst = gadget()
    alone = solve(inst, "cpsat", single_carry=True, first_horizon=NO_SPLIT, minimize_travel=False)
    assert alone.status == "optimal" and alone.schedule.length == NO_SPLIT
    assert [h["answer"] for h in alone.stats["horizons"]] == ["sat", "unsat"]
    assert validate(inst, alone.schedule).violation is None and _carries_once(inst, alone.schedule)
    shown = Schedule(demonstration())
    report = validate(inst, shown)
    assert report.violation is None
    assert report.metrics.makespan == inst.meta["split_makespan"] == 24 < NO_SPLIT
    assert not _carries_once(inst, shown)
    # the tile is handed over: set down by one robot off its goal, picked up by the other
    moves = manipulations(inst, shown)
    goal_only = inst.goal_tiles & ~inst.start.tiles
    drops = [(t, i, c) for t, i, what, c in moves if what == "place" and not goal_only[c]]
    assert any(j != i and u > t and c == d for t, i, c in drops for u, j, what, d in moves if what == "pick")


@pytest.mark.parametrize("gap", [3, 4])
def test_the_demonstration_is_valid_for_other_gaps(gap):
    inst = gadget(gap)
    report = validate(inst, Schedule(demonstration(gap)))
    assert report.violation is None and report.metrics.makespan == inst.meta["split_makespan"]


def _has_path(g: nx.Graph, start, end) -> bool:
    rest = [v for v in g if v not in (start, end)]
    if start == end:
        return g.number_of_nodes() == 1
    return any(all(g.has_edge(a, b) for a, b in zip((start,) + p, p + (end,))) for p in itertools.permutations(rest))


@pytest.mark.parametrize("points, start, end", [
    ([(0, 0)], None, None), ([(0, 0), (1, 0)], None, None),
    ([(0, 0), (1, 0), (2, 0)], (0, 0), (2, 0)), ([(0, 0), (1, 0), (2, 0)], (1, 0), (2, 0)),
    ([(0, 0), (1, 0), (2, 0)], (0, 0), (1, 0)), ([(0, 0), (1, 0), (1, 1)], (1, 1), (0, 0)),
    ([(0, 0), (1, 0), (1, 1)], (0, 0), (1, 0))])
def test_both_robots_reach_the_gadget_on_time_exactly_when_the_path_exists(points, start, end):
    """Theorem 2's timing, by exhaustive search over each robot's way alone: robot 2's string
    always brings it to its entry at ``arrival``; robot 1 comes as early only along a
    Hamiltonian path from the start vertex to the end vertex."""
    g = grid_graph(points)
    inst = attached(g, 1, start=start, end=end)
    start, end = tuple(inst.meta["start_vertex"]), tuple(inst.meta["end_vertex"])
    exists = _has_path(g, start, end)
    assert (inst.meta["hamiltonian_path"] is not None) == exists
    assert inst.meta["bound"] == inst.meta["arrival"] + len(demonstration()[0])
    arrivals = []
    for way in approaches(g, 1, start=start, end=end):
        found = search_optimum(way, inst.meta["arrival"])
        if found is not None:
            report = validate(way, found)
            assert report.violation is None and report.metrics.makespan == inst.meta["arrival"]
        arrivals.append(found is not None)
    assert arrivals == [exists, True]


@pytest.mark.parametrize("seed", [0, 5])
def test_attached_instances_of_random_graphs_are_valid_and_deterministic(seed):
    g = random_grid_graph(6, seed)
    text = dump_instance(attached(g, 2))
    assert dump_instance(attached(g, 2)) == text
    inst = instance_from_text(text)
    n, ends = g.number_of_nodes(), (tuple(inst.meta["start_vertex"]), tuple(inst.meta["end_vertex"]))
    assert inst.num_robots == 2
    # Theorem 1's task tiles for the graph and for the string, and the gadget's seven
    assert int((inst.start.tiles & ~inst.goal_tiles).sum()) == 4 * n * 2 + 7
    assert inst.meta["arrival"] > bound(n, 2)
    assert (inst.meta["hamiltonian_path"] is None) == (hamiltonian_path(g, *ends) is None)


def test_hamiltonian_paths_between_two_vertices_agree_with_brute_force():
    for seed in range(12):
        g = random_grid_graph(1 + seed % 6, seed)
        for start, end in itertools.product(sorted(g), repeat=2):
            path = hamiltonian_path(g, start, end)
            assert (path is not None) == _has_path(g, start, end)
            if path is not None:
                assert path[0] == start and path[-1] == end and sorted(path) == sorted(g)
                assert all(g.has_edge(a, b) for a, b in zip(path, path[1:]))


def test_gen_coop_on_the_command_line(tmp_path, capsys, cli):
    out, shown = tmp_path / "coop.yaml", tmp_path / "coop.schedule.yaml"
    assert cli(["gen", "coop", "-o", out, "--schedule", shown]) == 0
    assert instance_from_text(out.read_text()).meta["split_makespan"] == 24
    capsys.readouterr()
    assert cli(["check", out, shown]) == 0
    assert "valid: makespan 24" in capsys.readouterr().out
    alone = tmp_path / "split.yaml"  # without -o the instance goes beside the schedule
    assert cli(["gen", "coop", "--schedule", alone]) == 0
    assert f"bille check {tmp_path / 'split.instance.yaml'} {alone}" in capsys.readouterr().err
    assert cli(["check", tmp_path / "split.instance.yaml", alone]) == 0
    (tmp_path / "l.graph").write_text("oo\n.o\n")
    capsys.readouterr()
    assert cli(["gen", "coop", str(tmp_path / "l.graph"), "--search", "--json"]) == 0
    assert '"on_time": true' in capsys.readouterr().out
    assert cli(["gen", "coop", str(tmp_path / "l.graph"), "--start", "0,0", "--end", "1,0", "--search", "--json"]) == 0
    assert '"on_time": false' in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["gen", "coop", "--start", "0,0"], "need a GRAPH"),
    (["gen", "coop", "{tmp}/l.graph", "--schedule", "{tmp}/s.yaml"], "gadget alone"),
    (["gen", "coop", "--gap", "1"], "1 is not in the range"),
    (["gen", "coop", "{tmp}/l.graph", "--end", "1,1"], "has a vertex above it"),
    (["gen", "coop", "{tmp}/l.graph", "--end", "7,7"], "not a vertex"),
    (["gen", "coop", "{tmp}/l.graph", "--end", "y"], "expected X,Y"),
    (["gen", "coop", "{tmp}/split.graph"], "not connected"),
    (["gen", "coop", "{tmp}/l.graph", "--scale", "0"], "0 is not in the range"),
])
def test_bad_coop_input_is_one_line_and_exit_2(tmp_path, rejects, argv, message):
    (tmp_path / "split.graph").write_text("o.o\n")
    (tmp_path / "l.graph").write_text("oo\n.o\n")
    rejects([a.replace("{tmp}", str(tmp_path)) for a in argv], message, tmp_path / "out.yaml")
