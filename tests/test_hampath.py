"""Theorem 1's reduction (``bille gen hampath``) and Corollary 1's copies."""
from __future__ import annotations

import itertools

import networkx as nx
import pytest

from bille.instances import dump_instance, instance_from_text
from bille.instances.generators.graphs import grid_graph, hamiltonian_path, random_grid_graph
from bille.instances.generators.hampath import T_G, bound, reduction, search_optimum
from bille.solvers import Schedule, solve, validate

PATH3 = [(0, 0), (1, 0), (2, 0)]
BEND3 = [(0, 0), (1, 0), (1, 1)]
STAR = [(0, 0), (1, 0), (2, 0), (1, 1)]      # no Hamiltonian path at all
SQUARE = [(0, 0), (1, 0), (0, 1), (1, 1)]


def _has_path_from(g: nx.Graph, start) -> bool:
    """Brute force: some ordering of the vertices that starts at ``start`` is a path."""
    rest = [v for v in g if v != start]
    return any(all(g.has_edge(a, b) for a, b in zip((start,) + p, p)) for p in itertools.permutations(rest))


def _optimum_is_bound(inst) -> bool:
    """Whether the exhaustive search finds a schedule within the bound; a schedule found is
    validated and must take exactly the bound (the search is breadth-first: nothing shorter)."""
    found = search_optimum(inst, inst.meta["bound"])
    if found is None:
        return False
    report = validate(inst, found)
    assert report.violation is None
    assert report.metrics.makespan == found.length == inst.meta["bound"]
    return True


@pytest.mark.parametrize("scale", [1, 2])
@pytest.mark.parametrize("points, start", [
    ([(0, 0)], None), ([(0, 0), (1, 0)], None), (PATH3, None), (PATH3, (1, 0)), (BEND3, None), (BEND3, (1, 0)),
    (STAR, (0, 0)), (STAR, (1, 0)), (SQUARE, None)])
def test_the_optimum_is_the_bound_exactly_when_a_hamiltonian_path_starts_at_the_robot(points, start, scale):
    g = grid_graph(points)
    inst = reduction(g, scale, start=start)
    first = inst.meta["start_vertex"]
    assert inst.meta["bound"] == (scale + 7) * (len(points) - 1) + T_G * len(points)
    exists = _has_path_from(g, tuple(first))
    assert (inst.meta["hamiltonian_path_from_start"] is not None) == exists
    assert _optimum_is_bound(inst) == exists


@pytest.mark.slow
def test_without_a_path_the_optimum_is_above_the_bound_by_the_detour():
    # the middle of three in a row: the robot must come back through its start vertex
    inst = reduction(grid_graph(PATH3), 1, start=(1, 0))
    found = search_optimum(inst, inst.meta["bound"] + 8)
    assert found is not None and validate(inst, found).violation is None
    assert found.length == inst.meta["bound"] + 4


@pytest.mark.slow
def test_the_gadget_takes_t_g_steps_under_the_full_rules():
    """The search above only picks and places task cells; the exact solver, which may pick and
    place any tile, agrees on one gadget: t_g steps from the robot's corner."""
    inst = reduction(grid_graph([(0, 0)]), 1)
    result = solve(inst, "cpsat", threads=2, minimize_travel=False)  # 6 s; CaDiCaL takes 38
    assert result.status == "optimal" and result.schedule.length == T_G
    assert validate(inst, result.schedule).violation is None


@pytest.mark.parametrize("seed", [0, 3])
def test_reductions_of_random_graphs_are_valid_and_deterministic(seed):
    g = random_grid_graph(6, seed)
    text = dump_instance(reduction(g, 2))
    assert dump_instance(reduction(g, 2)) == text
    inst = instance_from_text(text)
    n = g.number_of_nodes()
    assert inst.meta["bound"] == bound(n, 2) and inst.meta["t_g"] == T_G
    assert int(inst.start.tiles.sum()) == int(inst.goal_tiles.sum())
    assert int((inst.start.tiles & ~inst.goal_tiles).sum()) == 4 * n          # four task tiles per gadget
    assert (inst.meta["hamiltonian_path_from_start"] is None) == (hamiltonian_path(g, start=tuple(
        inst.meta["start_vertex"])) is None)


def test_corollary_copies_run_the_one_robot_schedule_side_by_side():
    g = grid_graph(BEND3)
    one = reduction(g, 1)
    many = reduction(g, 1, robots=3)
    assert many.num_robots == 3 and many.meta["bound"] == one.meta["bound"]
    # copies are farther apart than the bound: no robot can help another copy in time
    xs = sorted(r.front[0] for r in many.robots)
    assert all(b - a > many.meta["bound"] for a, b in zip(xs, xs[1:]))
    found = search_optimum(one, one.meta["bound"])
    report = validate(many, Schedule(found.actions * 3))
    assert report.violation is None and report.metrics.makespan == many.meta["bound"]


def test_biped_movesets_are_allowed_without_a_bound():
    inst = instance_from_text(dump_instance(reduction(grid_graph(BEND3), 1, moveset="S7")))
    assert inst.moveset.name == "S7" and inst.meta["bound"] is None and "point" in inst.meta["note"]


def test_gen_hampath_on_the_command_line(tmp_path, capsys, cli):
    (tmp_path / "l.graph").write_text("oo\n.o\n")
    out = tmp_path / "l.yaml"
    assert cli(["gen", "hampath", str(tmp_path / "l.graph"), "--scale", "2", "-o", str(out)]) == 0
    assert instance_from_text(out.read_text()).meta["bound"] == bound(3, 2)
    capsys.readouterr()
    assert cli(["gen", "hampath", str(tmp_path / "l.graph"), "--start", "1,0", "--search", "--json"]) == 0
    captured = capsys.readouterr()
    assert '"optimal_is_bound": false' in captured.out
    assert f"no schedule within the bound {bound(3, 1)}" in captured.err  # from the middle: no path


def test_gen_hampath_search_prints_the_verdict_and_writes_the_witness(tmp_path, capsys, cli):
    (tmp_path / "l.graph").write_text("oo\n.o\n")
    out, witness = tmp_path / "l.yaml", tmp_path / "l.schedule.yaml"
    assert cli(["gen", "hampath", str(tmp_path / "l.graph"), "--search", "-o", str(out),
                "--schedule", str(witness)]) == 0
    err = capsys.readouterr().err
    inst = instance_from_text(out.read_text())
    assert inst.meta["optimum"] == inst.meta["bound"] == bound(3, 1) and f"optimal makespan {bound(3, 1)}" in err
    from bille.instances.schedule import load_schedule
    from bille.solvers import validate

    report = validate(inst, load_schedule(witness))
    assert report.valid and report.metrics.makespan == inst.meta["optimum"]


@pytest.mark.parametrize("argv, message", [
    (["gen", "hampath", "{tmp}/split.graph"], "not connected"),
    (["gen", "hampath", "{tmp}/bad.graph"], "unexpected 'x'"),
    (["gen", "hampath", "{tmp}/l.graph", "--scale", "0"], "0 is not in the range"),
    (["gen", "hampath", "{tmp}/l.graph", "--start", "7,7"], "not a vertex"),
    (["gen", "hampath", "{tmp}/l.graph", "--start", "x"], "expected X,Y"),
    (["gen", "hampath", "{tmp}/l.graph", "-r", "2", "--search"], "one robot"),
    (["gen", "hampath", "{tmp}/l.graph", "--schedule", "{tmp}/s.yaml"], "--schedule needs --search"),
])
def test_bad_hampath_input_is_one_line_and_exit_2(tmp_path, rejects, argv, message):
    (tmp_path / "split.graph").write_text("o.o\n")
    (tmp_path / "bad.graph").write_text("oxo\n")
    (tmp_path / "l.graph").write_text("oo\n.o\n")
    rejects([a.replace("{tmp}", str(tmp_path)) for a in argv], message, tmp_path / "out.yaml")


def test_an_edge_list_and_a_networkx_graph_are_grid_graphs_or_refused():
    import networkx as nx

    from bille.instances import InstanceError
    from bille.instances.generators.graphs import parse_graph

    g = parse_graph("# an L\n0 0 1 0\n1 0 1 1\n")
    assert sorted(g.nodes) == [(0, 0), (1, 0), (1, 1)] and g.number_of_edges() == 2
    with pytest.raises(InstanceError, match=r"<graph>:2: the edge \(0, 0\)-\(2, 0\) joins points at distance 2"):
        parse_graph("0 0 1 0\n0 0 2 0\n")
    with pytest.raises(InstanceError, match=r"\(0, 0\) and \(0, 1\) are at distance 1 but not joined"):
        parse_graph("0 0 1 0\n1 0 1 1\n1 1 0 1\n")  # a square missing one side: not induced
    with pytest.raises(InstanceError, match="vertex 0 is not an"):
        reduction(nx.path_graph(3), 1)
    inst = reduction(nx.grid_2d_graph(2, 2), 1)
    assert inst.meta["edges"] == 4 and inst.meta["graph"] == "oo\noo\n"
