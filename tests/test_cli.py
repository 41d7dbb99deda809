"""The bille command: exit codes, JSON output, and one clear line for bad input."""
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from bille.instances import load_instance
from bille.instances.bundled import bundled_names, bundled_path
from bille.solvers import load_schedule, validate
from bille.tools.cli import main

DATA = Path(__file__).parent / "data"
CASES = yaml.safe_load((DATA / "cases.yaml").read_text())


def run(capsys, *argv):
    with pytest.raises(SystemExit) as info:
        main(list(argv))
    out, err = capsys.readouterr()
    return info.value.code, out, err


@pytest.mark.parametrize("case", CASES, ids=[f"{c['schedule']}" for c in CASES])
def test_check_agrees_with_the_rules(case, capsys):
    inst, sched = str(DATA / case["instance"]), str(DATA / case["schedule"])
    code, out, err = run(capsys, "check", inst, sched, "--json")
    assert code == case["exit"], err
    if code == 2:
        assert out == "" and err.count("\n") == 1 and "Traceback" not in err
        return
    verdict = json.loads(out)
    assert set(verdict) == {"valid", "violation", "metrics"}
    report = validate(load_instance(inst), load_schedule(sched))
    assert verdict == report.to_json()
    if case["exit"] == 0:
        assert verdict["valid"] and verdict["violation"] is None
        goals = any(c >= 0 for c in load_instance(inst).goal_cells)  # sum of costs where robots have goals
        assert set(verdict["metrics"]) == {"makespan", "tiles_traveled", "waits", "picks", "places"} | (
            {"sum_of_costs"} if goals else set())
    else:
        v = verdict["violation"]
        assert not verdict["valid"]
        assert (v["step"], v["rule"], v["robot"], v["cells"]) == (case["step"], case["rule"], case["robot"], case["cells"])


@pytest.mark.parametrize("name", bundled_names())
def test_check_accepts_every_bundled_schedule_by_name(name, capsys):
    code, out, _ = run(capsys, "check", name, f"{name}.schedule")
    assert code == 0 and out.startswith("valid: makespan")


def test_check_text_names_the_violation(capsys):
    code, out, _ = run(capsys, "check", str(DATA / "line.yaml"), str(DATA / "line.collision.yaml"))
    assert code == 1
    assert out.strip() == "invalid: step 2, robot 0, rule collision: robots 0 and 1 both need (3, 1)"


def test_show_draws_robots_and_reports_validity(capsys):
    code, out, _ = run(capsys, "show", "corridor-2")
    assert code == 0
    assert "10x4 grid" in out and "instance: valid" in out
    assert ".TaATT*Bb." in out  # robot A heading east, robot B heading west carrying a tile


def test_show_marks_an_invalid_instance(tmp_path, capsys):
    text = (DATA / "line.yaml").read_text().replace("TTTTTT", "TT.TTT")
    (tmp_path / "split.yaml").write_text(text)
    code, out, _ = run(capsys, "show", str(tmp_path / "split.yaml"))
    assert code == 1 and "INVALID" in out and "not 4-connected" in out


def test_list_names_the_bundled_instances(capsys):
    code, out, _ = run(capsys, "list")
    assert code == 0 and all(name in out for name in bundled_names())


def test_solve_writes_a_valid_schedule(tmp_path, capsys):
    out_path = tmp_path / "s.yaml"
    code, out, _ = run(capsys, "solve", "crowded-2", "--method", "bfs", "-o", str(out_path), "--json")
    result = json.loads(out)
    assert code == 0 and result["status"] == "optimal" and result["metrics"]["makespan"] == 10
    assert validate(load_instance(bundled_path("crowded-2")), load_schedule(out_path)).valid


def test_solve_says_why_an_instance_is_infeasible(tmp_path, capsys):
    from bille.instances import save_instance
    from helpers import make

    walled = make("TT#..\nTT#..", [{"at": [0, 0]}], goal="..#TT\n..#TT", moveset="point")
    save_instance(walled, tmp_path / "walled.yaml")
    code, out, _ = run(capsys, "solve", str(tmp_path / "walled.yaml"), "--method", "anytime", "--time-limit", "5")
    assert code == 1 and "anytime: infeasible" in out
    reason = next(line for line in out.splitlines() if line.startswith("reason: "))
    assert "no robot can ever place a tile on (3, 0)" in reason, out


@pytest.mark.parametrize("argv", [
    ["check", "corridor-2"],
    ["frobnicate"],
    ["solve", "corridor-2", "--time-limit", "0"],
    ["solve", "corridor-2", "--method", "magic"],
    ["show", "no-such-instance"],
])
def test_usage_errors_are_one_line_and_exit_2(argv, capsys):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err


def test_the_installed_console_script(tmp_path):
    exe = shutil.which("bille") or str(Path(sys.executable).parent / "bille")
    version = subprocess.run([exe, "--version"], capture_output=True, text=True)
    assert version.returncode == 0 and version.stdout.startswith("bille ")
    bad = subprocess.run([exe, "check", str(DATA / "ragged.instance.yaml"), "x"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.strip() == f"bille: error: {DATA / 'ragged.instance.yaml'}:3: grid: row 1 has 2 cells, expected 3 like row 0 (the grid must be a rectangle)"


@pytest.mark.slow
def test_gap_reports_the_heuristics_against_the_optimum(tmp_path, capsys):
    out_csv = tmp_path / "gap.csv"
    code, out, _ = run(capsys, "gap", "compare-2", "corridor-2", "--methods", "temporal-astar,cpsat",
                       "--time-limit", "60", "--csv", str(out_csv), "--json")
    assert code == 0
    rows = json.loads(out)["rows"]
    by = {(r["instance"], r["method"]): r for r in rows}
    assert by[("compare-2", "cpsat")]["status"] == "optimal" and by[("compare-2", "cpsat")]["gap_percent"] == 0.0
    ta = by[("compare-2", "temporal-astar")]
    assert ta["gap_percent"] == 100.0 * (ta["makespan"] - 10) / 10
    assert by[("corridor-2", "cpsat")]["makespan"] == 13
    loop = by[("corridor-2", "temporal-astar")]  # the reconfiguration loop: never below the optimum
    assert loop["status"] == "feasible" and loop["makespan"] >= 13
    lines = out_csv.read_text().splitlines()
    assert lines[0].startswith("instance,method,status") and len(lines) == 1 + len(rows)


def test_gap_rejects_an_unknown_method(capsys):
    code, out, err = run(capsys, "gap", "--methods", "temporal-astar,magic")
    assert code == 2 and out == "" and "magic" in err


def test_gap_reads_a_repeated_methods_option_as_one_list(tmp_path, capsys):
    code, out, _ = run(capsys, "gap", "crowded-3", "--methods", "temporal-astar:H=10", "--methods", "sat",
                       "--csv", str(tmp_path / "g.csv"), "--json")
    assert code == 0
    rows = {r["method"]: r for r in json.loads(out)["rows"]}
    assert set(rows) == {"temporal-astar:H=10", "sat"}
    assert rows["sat"]["status"] == "optimal" and rows["sat"]["makespan"] == 4


def test_solve_exact_json(capsys, tmp_path):
    code, out, _ = run(capsys, "solve", "crowded-3", "--method", "sat", "--json", "-o", str(tmp_path / "s.yaml"))
    result = json.loads(out)
    assert code == 0 and set(result) == {"method", "status", "metrics", "lower_bound", "time_s", "claim",
                                           "failure", "stats", "schedule"} and result["failure"] is None
    assert result["status"] == "optimal" and result["metrics"]["makespan"] == result["lower_bound"] == 4
    assert validate(load_instance(bundled_path("crowded-3")), load_schedule(tmp_path / "s.yaml")).valid


def test_python_dash_m_bille_and_the_version():
    import bille
    import bille.solvers

    assert bille.__version__ and bille.__version__[0].isdigit()
    done = subprocess.run([sys.executable, "-m", "bille", "--version"], capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.strip() == f"bille {bille.__version__}"
    public = set(bille.solvers.__all__)
    assert {"solve", "validate", "METHODS"} <= public and not public & {"time", "inspect", "annotations"}


def test_methods_lists_every_method_and_what_it_proves(cli, capsys):
    from bille.solvers import METHODS

    assert cli(["methods"]) == 0
    out = capsys.readouterr().out
    for name in METHODS:
        assert f"\n{name}: " in "\n" + out
    assert out.count("  proves: ") == len(METHODS)


def test_option_help_lists_a_methods_options_without_solving(cli, capsys):
    assert cli(["solve", "no-such-instance", "-m", "cbs", "-O", "help"]) == 0
    out = capsys.readouterr().out
    assert "w           suboptimality: the sum of costs found is at most w times optimal" in out
    assert "float, default 1.0 (>= 1)" in out and "float or none, default 60.0 (> 0 s)" in out
    assert cli(["methods", "sat"]) == 0
    assert "solver" in capsys.readouterr().out
    assert cli(["methods", "slove"]) == 2


def test_every_option_of_every_method_says_what_it_does(cli, capsys):
    from bille.solvers import METHODS

    for method in METHODS:
        assert cli(["methods", method]) == 0
        lines = capsys.readouterr().out.splitlines()
        names = [row[0] for row in METHODS[method].options().rows()]
        for name in names:  # the option's line: its name, then a description of some words
            line = next(line for line in lines if line.strip().split(" ")[0] == name)
            assert len(line.split(name, 1)[1].split()) >= 3, (method, line)


def test_one_option_given_twice_is_refused_naming_both(rejects, cli, capsys):
    rejects(["solve", "compare-4", "-m", "temporal-astar", "-H", "3", "-O", "horizon=10"],
            "temporal-astar: option horizon is given twice: -H/--horizon 3 and -O horizon=10")
    rejects(["solve", "compare-4", "-m", "temporal-astar", "-O", "H=3", "-O", "horizon=10"],
            "option horizon is given twice: -O H=3 and -O horizon=10")
    rejects(["solve", "compare-4", "-m", "cbs", "--time-limit", "3", "-O", "time_limit=4"],
            "option time_limit is given twice")
    rejects(["gap", "compare-4", "--methods", "temporal-astar:H=10,horizon=3"],
            "option horizon is given twice: H=10 and horizon=3")


def test_an_alias_is_the_option_itself(cli, capsys):
    runs = []
    for argv in (["-O", "H=8"], ["-H", "8"], ["-O", "horizon=8"]):
        assert cli(["solve", "compare-4", "-m", "temporal-astar", "--json", *argv]) == 0
        runs.append(json.loads(capsys.readouterr().out))
    assert runs[0]["stats"]["horizon"] == 8
    assert runs[0]["schedule"] == runs[1]["schedule"] == runs[2]["schedule"]


def test_an_option_without_effect_on_the_instance_is_refused(rejects):
    rejects(["solve", "compare-4", "-m", "temporal-astar", "-O", "load_transfer=true"],
            "temporal-astar: option load_transfer works in the reconfiguration loop only, and compare-4 moves no tiles")
    rejects(["solve", "compare-4", "-m", "lacam", "--load-transfer", "--d-tr", "3"],
            "lacam: option load_transfer, d_tr works in the reconfiguration loop only")
    rejects(["solve", "lt-4", "-m", "lacam", "-O", "objective=sum-of-loss"],
            "lacam: option objective is for path planning")


@pytest.mark.parametrize("method", ["cbs", "lacam", "bfs", "temporal-astar"])
def test_the_log_holds_the_runs_events(cli, capsys, tmp_path, method):
    log = tmp_path / "run.log"
    capped = ["-O", "max_steps=3"] if method == "bfs" else []  # the whole search takes minutes here
    assert cli(["solve", "compare-4", "-m", method, "--json", "--log", log, *capped]) == (1 if capped else 0)
    result = json.loads(capsys.readouterr().out)
    events = [json.loads(line) for line in log.read_text().splitlines()]
    assert any(e["event"] == "progress" for e in events)
    assert all(e["event"] in ("schedule", "bound", "progress") for e in events)
    assert [e["t"] for e in events] == sorted(e["t"] for e in events)
    found = [e["makespan"] for e in events if e["event"] == "schedule"]
    assert found == [] if result["metrics"] is None else found[-1] == result["metrics"]["makespan"]
    bounds = [e["lower"] for e in events if e["event"] == "bound"]
    assert all(b <= (result["lower_bound"] or 0) for b in bounds)


def test_a_refused_run_leaves_no_log(rejects, tmp_path):
    log = tmp_path / "run.log"
    rejects(["solve", "compare-4", "-m", "temporal-astar", "-O", "load_transfer=true", "--log", log], "load_transfer")
    assert not log.exists()


def test_a_deadlock_says_what_to_try(cli, capsys):
    assert cli(["solve", "point-4", "-m", "temporal-astar"]) == 1
    out = capsys.readouterr().out
    assert "failure: deadlock:" in out and "try -m auto or -m lacam" in out


def test_a_mistyped_bundled_name_gets_a_suggestion(cli, capsys):
    assert cli(["show", "lt4"]) == 2
    assert "lt4: no such file or bundled name; did you mean 'lt-4'?" in capsys.readouterr().err


def test_tiles_traveled_say_when_they_were_not_minimized(cli, capsys):
    assert cli(["solve", "corridor-2", "-m", "cpsat", "-O", "minimize_travel=false"]) == 0
    assert "tiles traveled 15 (not minimized)" in capsys.readouterr().out
    assert cli(["solve", "corridor-2", "-m", "cpsat"]) == 0
    out = capsys.readouterr().out
    assert "tiles traveled" in out and "not minimized" not in out


def test_every_error_line_starts_the_same_way(cli, capsys):
    for argv in (["solve", "lt-4", "-m", "foo"], ["slove"], ["show", "no-such-file"], ["solve", "lt-4", "-O", "x"]):
        assert cli(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("bille: error: ") and len(err.strip().splitlines()) == 1, err


def test_one_letter_means_one_thing_and_no_design_file_is_cited():
    """-m is the method wherever it appears (gen hampath's robots are -r); the code and docs cite
    the rules where users read them (docs/), not a design file outside the repository."""
    import subprocess
    from pathlib import Path

    import click

    from bille.tools.cli import cli

    stack = [(cli, "bille")]
    while stack:
        cmd, path = stack.pop()
        for p in cmd.params:
            if "-m" in getattr(p, "opts", []):
                assert p.name == "method", f"{path}: -m is --{p.name}"
        if isinstance(cmd, click.Group):
            sub = click.Context(cmd)
            stack += [(cmd.get_command(sub, n), f"{path} {n}") for n in cmd.list_commands(sub)]
    root = Path(__file__).resolve().parents[1]
    tracked = subprocess.run(["git", "ls-files", "*.py", "*.md"], cwd=root, capture_output=True, text=True).stdout.split()
    assert not [f for f in tracked if "DESIGN §" in (root / f).read_text(encoding="utf-8") and f != "tests/test_cli.py"]


def test_an_option_in_exponent_notation_is_a_number():
    # YAML reads 1e3 as text: "-O w=1e3" was refused as "not a finite number"
    from bille.tools.solve_commands import _parse_options
    read = {name: value for _, name, value in _parse_options(["w=1e3", "epsilon=2", "name=keep", "x=1.5"])}
    assert read == {"w": 1000.0, "epsilon": 2, "name": "keep", "x": 1.5}


def test_methods_options_as_json(cli, capsys):
    # -O help --json printed text
    assert cli(["solve", "point-4", "-m", "bfs", "-O", "help", "--json"]) == 0
    told = json.loads(capsys.readouterr().out)
    assert told["method"] == "bfs" and "cells" in [o["name"] for o in told["options"]]


def test_a_flag_looked_for_in_the_wrong_place_says_where_it_lives(cli, capsys):
    assert cli(["gap", "--jobs", "2"]) == 2
    assert "runs side by side are bille sweep's (--jobs)" in capsys.readouterr().err
    assert cli(["solve", "point-4", "--seed", "3"]) == 2
    assert "-O seed=N" in capsys.readouterr().err
    assert cli(["list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert "point-4" in [i["name"] for i in listed["instances"]] and "room-32-32-4" in listed["maps"]


def test_gap_csv_never_reads_a_bare_optimal_above_the_proved_optimum(cli, capsys, tmp_path, monkeypatch):
    # M* and A* prove the least sum of costs over walking-only schedules (14 on point-4), not the
    # makespan over every schedule (10): their status said "optimal" all the same
    import csv
    monkeypatch.chdir(tmp_path)
    assert cli(["gap", "point-4", "--methods", "cpsat,mstar", "--time-limit", "30"]) == 0
    rows = list(csv.DictReader((tmp_path / "gap.csv").read_text().splitlines()))
    proved = min(int(r["makespan"]) for r in rows if r["status"] == "optimal")
    assert all(int(r["makespan"]) == proved for r in rows if r["status"] == "optimal")
    assert {r["status"] for r in rows if r["method"] == "mstar"} == {"optimal-sum-of-costs-walking-only"}


@pytest.mark.parametrize("argv, missing, extra", [
    (["run", "lt-4", "lt-4.schedule"], "paho", "execute"),
    (["sweep", "run", "small", "--scheduler", "tcp://127.0.0.1:1"], "distributed", "sweep")])
def test_a_command_without_its_optional_dependency_says_which_extra_installs_it(tmp_path, argv, missing, extra):
    # the sweep's Dask back end and the execution layer are extras (pyproject.toml): without them
    # the command says what to install, exits 2 and writes nothing
    code = (f"import sys; sys.modules[{missing!r}] = None\n"
            f"from bille.tools.cli import main\nmain({argv!r})")
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"pip install 'bille[{extra}]'" in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
