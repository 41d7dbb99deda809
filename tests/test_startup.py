"""Commands that do not solve start fast: they import no solver library (docs/decisions.md, "The solve() contract").

The commands run one after another in one fresh interpreter, which records after each the
modules it has loaded by then (so a heavy import is blamed on the first command that made it).
"""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("ortools", "pysat", "rerun", "matplotlib", "dask", "distributed", "scipy")
PROBE = """
import json, sys
from bille.tools.cli import main
loaded = []
for argv in json.loads(sys.argv[1]):
    try:
        main(argv)
    except SystemExit:
        pass
    loaded.append(sorted(sys.modules))
sys.__stdout__.write("\\n" + json.dumps(loaded) + "\\n")
"""


def test_light_commands_import_no_solver_library(tmp_path):
    commands = [["--help"], ["list"], ["show", "point-4"], ["check", "point-4", "point-4.schedule"],
                ["solve", "--help"], ["convert", "point-4", str(tmp_path / "p4.yaml")]]
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(commands)], capture_output=True, text=True)
    loaded = json.loads(done.stdout.strip().splitlines()[-1])
    assert (tmp_path / "p4.yaml").exists()  # the commands ran
    for argv, modules in zip(commands, loaded):
        heavy = sorted(m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY))
        assert not heavy, f"bille {' '.join(argv)} imported {heavy}"


def test_a_tiny_solve_without_a_bound_imports_no_solver_library():
    # a method that uses no LP and no compiled code leaves scipy and numba unloaded on a tiny
    # instance (its start-up was 4x importing numpy, click, yaml and rich; now under 2x)
    commands = [["solve", "crowded-2", "-m", "cbs"], ["solve", "crowded-2", "-m", "temporal-astar"],
                ["solve", "crowded-2", "-m", "lacam", "-O", "improve=0"]]
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(commands)], capture_output=True, text=True)
    loaded = json.loads(done.stdout.strip().splitlines()[-1])
    assert done.stdout.count(" in 0.") + done.stdout.count(" in 1.") == 3  # the solves ran and said so
    for argv, modules in zip(commands, loaded):
        heavy = sorted(m for m in modules if any(m == h or m.startswith(h + ".") for h in (*HEAVY, "numba")))
        assert not heavy, f"bille {' '.join(argv)} imported {heavy}"
        assert "bille.instances.interop" not in modules  # a bille file needs no reader of other formats
    loop = loaded[1]  # temporal-astar: the loop loads the other motion layers only to run with them
    assert "bille.heuristics.loop.reconfigure" in loop
    assert "bille.heuristics.lacam" not in loop and "bille.heuristics.mstar" not in loop


def test_a_method_is_imported_when_it_is_first_used():
    code = ("import sys; from bille.solvers import METHODS; record = METHODS['cpsat']; "
            "before = 'bille.solvers.exact' in sys.modules; names = list(METHODS); plan = record.plan(); "
            "print(before, 'cpsat' in names, 'bille.solvers.exact' in sys.modules, plan.__name__)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["False", "True", "True", "plan_cpsat"]


def test_the_import_graph_of_a_command():
    from bille.tools.bench.importgraph import graph

    g = graph(["show", "point-4"])
    assert "bille.tools.cli" in g["modules"] and "bille.instances.grid" in g["modules"]
    assert "bille.solvers.exact" not in g["modules"]
    assert ("bille.tools.files_commands", "bille.tools.render") in g["edges"]  # loaded by the command it runs
    assert all(a in g["modules"] and b in g["modules"] for a, b in g["edges"])
    assert all((a, b) in g["edges"] and (b, a) in g["edges"] for a, b in g["both_ways"])


def test_a_bille_folder_earlier_on_the_path_does_not_hide_the_installed_package(tmp_path):
    # Python run from the repository's root meets its bille/ folder first; a non-editable install
    # holds the layers in site-packages/bille (here: a second folder, without site-packages)
    from pathlib import Path

    top = (Path(__file__).resolve().parent.parent / "bille" / "__init__.py").read_text()
    first, installed = tmp_path / "root" / "bille", tmp_path / "site" / "bille"
    for folder in (first, installed / "instances"):
        folder.mkdir(parents=True)
    (first / "__init__.py").write_text(top)
    (installed / "__init__.py").write_text(top)
    (installed / "instances" / "__init__.py").write_text("FOUND = True\n")
    code = (f"import sys; sys.path[:0] = [{str(first.parent)!r}, {str(installed.parent)!r}]; "
            "import bille.instances; print(bille.instances.FOUND)")
    done = subprocess.run([sys.executable, "-S", "-c", code], capture_output=True, text=True)
    assert done.stdout.strip() == "True", done.stderr


@pytest.mark.slow
def test_bille_warm_runs_each_compiled_part():
    from click.testing import CliRunner

    from bille.tools.cli import cli

    done = CliRunner().invoke(cli, ["warm"])
    assert done.exit_code == 0, done.output
    lines = done.output.splitlines()
    assert [line.split(":")[0] for line in lines] == ["the exact joint search (bfs)", "LaCAM*'s generator and SUO table",
                                                      "conflict-based search's low level"]
    assert all(line.endswith(" s") for line in lines)
