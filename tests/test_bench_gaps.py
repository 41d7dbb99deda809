"""bille bench gaps: one anytime run per instance, and what proved each end of its gap."""
from click.testing import CliRunner

from bille.tools.bench.gaps import _proved_by
from bille.tools.cli import cli


def test_bench_gaps_prints_a_row_per_instance():
    out = CliRunner().invoke(cli, ["bench", "gaps", "--time-limit", "20", "--maps", "corridor-2"])
    assert out.exit_code == 0, out.output
    row = next(line for line in out.output.splitlines()
               if line.strip().startswith("corridor-2") and not line.endswith("..."))
    assert row.split()[-1] == "optimal" and "0.0%" in row


def test_bench_gaps_refuses_an_unknown_instance_before_any_work():
    out = CliRunner().invoke(cli, ["bench", "gaps", "--maps", "corridor-2,no-such-map"])
    assert out.exit_code != 0 and "no-such-map" in str(out.exception or out.output)


def test_what_proved_the_bound():
    stats = {"windows": {"proved_bound": 23}, "ahead": [[18, "unsat", 20.0]], "scaffold": [[25.1, 15]]}
    assert _proved_by(stats, 14, 14) == "static"
    assert _proved_by(stats, 23, 14) == "window"
    assert _proved_by(stats, 19, 14) == "ahead"
    assert _proved_by(stats, 15, 14) == "scaffold"
    assert _proved_by(stats, 17, 14) == "rise"


def test_bench_gaps_class_exact_finds_the_class_optimum_of_the_brute_force(tmp_path):
    from bille.instances import save_instance
    from refsearch import class_optimum
    from test_soundness import MANY

    # the optimum (6) sets a tile down outside the start and the goal; without scaffold it takes 8
    inst = next(i for i in MANY if i.name == "tiny-10102")
    best, _ = class_optimum(inst, "no-scaffold")
    path = tmp_path / "t.yaml"
    save_instance(inst, path)
    out = CliRunner().invoke(cli, ["bench", "gaps", "--time-limit", "20", "--maps", str(path), "--class-exact", "30"])
    assert out.exit_code == 0, out.output
    row = next(line for line in out.output.splitlines() if line.strip().startswith(inst.name)).split()
    assert best == 8 and row[-4:-1] == ["8", "8", "optimal"], row


def test_class_exact_below_a_schedule_of_the_class_finds_the_optimum_without_scaffold():
    # two 4x3 platforms, a bridge of two tiles, one tile to carry: the best schedule without
    # scaffold takes 10 steps (the brute force restricted to the class agrees, after 2 million
    # states: too slow for a test). From the loop's schedule of the class (14), the search capped
    # at 13 finds it and proves it
    from bille.instances.generators.bridges import bridges
    from bille.solvers import solve, validate
    from bille.tools.bench.gaps import _class_exact

    inst = bridges(width=4, height=3, gap=2, bays=(), moved=1)
    loop = solve(inst, "temporal-astar", bound=True, time_limit=60)
    assert validate(inst, loop.schedule).valid and "no-scaffold" in loop.stats["classes"]
    assert loop.metrics.makespan > 10 >= loop.stats["class_bounds"]["no-scaffold"]["lower_bound"]
    got = _class_exact(inst, loop, 300)
    assert (got["lower"], got["best"], got["optimal"]) == (10, 10, True), got
