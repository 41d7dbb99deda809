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
    stats = {"windows": {"proved_bound": 23}, "ahead": [[18, "unsat", 20.0]]}
    assert _proved_by(stats, 14, 14) == "static"
    assert _proved_by(stats, 23, 14) == "window"
    assert _proved_by(stats, 19, 14) == "ahead"
    assert _proved_by(stats, 17, 14) == "rise"
