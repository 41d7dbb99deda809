"""bille bench gaps: one anytime run per instance, and what proved each end of its gap."""
import pytest
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
    stats = {"windows": {"proved_bound": 23}, "ahead": [[18, "unsat", 20.0]]}
    assert _proved_by(stats, 14, 14) == "static"
    assert _proved_by(stats, 23, 14) == "window"
    assert _proved_by(stats, 19, 14) == "ahead"
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


@pytest.mark.slow
def test_bench_gaps_class_exact_below_anytime_schedule_finds_the_optimum_without_scaffold(tmp_path):
    # lt-1 with one tile: the best schedule without scaffold takes 16 steps (the exact search
    # proves 15 has none); whatever anytime finds in 5 s, capped below it the search ends there
    from bille.instances import save_instance
    from bille.instances.generators.bridges import bridges

    path = tmp_path / "one.yaml"
    save_instance(bridges(moved=1), path)
    out = CliRunner().invoke(cli, ["bench", "gaps", "--time-limit", "5", "--maps", str(path), "--class-exact", "300"])
    assert out.exit_code == 0, out.output
    row = next(line for line in out.output.splitlines() if line.strip().startswith("bridges-")).split()
    assert row[-4:-1] == ["16", "16", "optimal"], row
