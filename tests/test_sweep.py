"""bille sweep: every method on local processes and a Dask cluster with the same results table,
resume after a kill, Ctrl-C keeps the finished runs, failures recorded as rows and explained in
the report, gaps measured against the best bound of the sweep (as bille gap measures them), and
the planner comparison as a sweep file."""
import json
import os
import re
import signal
import subprocess
import sys
import time

import pytest

from bille.instances import BilleError, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.claim import base_status, status_key
from bille.instances import instance_from_text
from bille.solvers import METHODS, load_schedule, schedule_from_text, solve, validate
from bille.tools.sweep.commands import run_spec
from bille.tools.sweep.engine import execute, run_dask
from bille.tools.sweep.report import summary
from bille.tools.sweep.results import COLUMNS, TIMING, load_table
from bille.tools.sweep.spec import Limits, load_spec

SPEC = """
name: small
time_limit: 20
instances:
  - crowded-3
  - gen: crowded --robots 2 --width 5 --height 3 --seed 0..2
methods:
  temporal-astar: {horizon: [2, 5]}
  astar: {}
"""


# every registered method on a tiny bundled instance that each of them plans (crowded-2: two
# robots trade ends of a 6x3 map; bfs proves its optimum 10 in under a second), cpsat with
# threads too
EVERY = "name: every\ntime_limit: 30\ninstances: [crowded-2]\nmethods:\n" + "".join(
    f"  {m}: {{}}\n" for m in METHODS if m != "cpsat") + "  cpsat: {threads: [1, 2]}\n"
# the methods whose every column repeats from one run to the next (not only the optimum):
# no parallel search, no timing in the search itself
REPEATABLE = ("astar", "mstar", "temporal-astar", "bfs", "sat")


def write_spec(tmp_path, text=SPEC, name="small.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def table(rows):
    """The columns that repeat from one run of a sweep to the next: all but the timings for the
    methods that search the same way every time; the outcome for the others."""
    def columns(r):
        if r["method"] in REPEATABLE:
            return [c for c in COLUMNS if c not in TIMING]
        return ["key", "status", "makespan", "lower_bound", "best_lower_bound", "error"]
    return sorted(({c: r[c] for c in columns(r)} for r in rows), key=lambda r: r["key"])


def test_a_method_that_forks_runs_inside_a_sweep_run(tmp_path):
    # anytime forks its bound search: a run's process may start processes of its own
    run = next(r for r in load_spec(write_spec(tmp_path, EVERY)).runs if r.method == "anytime")
    row = execute(run, Limits(30))
    assert row["status"] == "optimal", row
    schedule = schedule_from_text(row["schedule"])
    report = validate(instance_from_text(run.text), schedule)
    assert report.valid and report.metrics.makespan == row["makespan"] == solve(
        instance_from_text(run.text), "bfs").metrics.makespan


@pytest.mark.slow
def test_every_method_on_local_processes_and_a_dask_cluster_gives_the_same_table(tmp_path):
    from distributed import Client, LocalCluster

    spec = load_spec(write_spec(tmp_path, EVERY))
    assert {r.method for r in spec.runs} == set(METHODS)
    _, local = run_spec(spec, tmp_path / "local", jobs=2, quiet=True)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        _, dask = run_spec(spec, tmp_path / "dask", client=client, quiet=True)
        stopped_on_dask(client, tmp_path)
    assert table(local) == table(dask)
    assert table(load_table(tmp_path / "local")) == table(local)  # the Parquet table holds the same rows
    optimum = {}
    for row in local:
        if row["method"] == "bfs":
            optimum[row["instance_hash"]] = row["makespan"]
    for row in local:  # every run applies and ends; every schedule kept beside the table is valid
        assert base_status(row["status"]) in ("optimal", "feasible", "unsolved"), row
        inst = instance_from_text(next(r for r in spec.runs if r.key == row["key"]).text)
        if row["schedule"]:
            report = validate(inst, load_schedule(tmp_path / "local" / row["schedule"]))
            assert report.valid and report.metrics.makespan == row["makespan"]
        assert row["lower_bound"] <= optimum[row["instance_hash"]]  # checked against brute force
        if row["status"] == "optimal":  # the makespan over every schedule (a restricted optimum says so)
            assert row["makespan"] == optimum[row["instance_hash"]], row
    import csv

    header = next(csv.reader((tmp_path / "local" / "results.csv").read_text().splitlines()))
    assert header == COLUMNS


def stopped_on_dask(client, tmp_path):
    """Interrupted, a sweep on Dask ends the run under way on its worker (anytime on bridge-2,
    300 s, with its forked bound search) and keeps the run finished before."""
    runs = load_spec(write_spec(tmp_path, "time_limit: 300\ninstances: [crowded-2, bridge-2]\n"
                                          "methods: {anytime: {}}\n", "long.yaml")).runs
    got = []

    def on_row(row):
        got.append(row)
        while not any(client.processing().values()):  # the long run has started on a worker
            time.sleep(0.05)
        time.sleep(1.0)  # and forked its bound search
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_dask(runs, Limits(300), client, on_row)
    assert [r["instance"] for r in got] == ["crowded-2"]
    end = time.time() + 60
    while time.time() < end and (any(client.processing().values()) or any(client.run(live_children).values())):
        time.sleep(0.2)
    assert not any(client.processing().values()) and not any(client.run(live_children).values())


def live_children() -> int:
    import multiprocessing

    return len(multiprocessing.active_children())


@pytest.mark.slow
def test_a_killed_sweep_resumes_without_repeating_or_losing_a_run(tmp_path):
    spec_path = write_spec(tmp_path, SPEC.replace("0..2", "0..5"))
    out = tmp_path / "out"
    total = len(load_spec(spec_path).runs)
    mark = f"sweep-{os.getpid()}-{time.time_ns()}"
    proc = subprocess.Popen([sys.executable, "-m", "bille", "sweep", str(spec_path), "--out", str(out), "--jobs", "1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
                            env=dict(os.environ, BILLE_TEST_MARK=mark))
    jsonl = out / "runs.jsonl"
    end = time.time() + 120
    while time.time() < end and (not jsonl.exists() or len(jsonl.read_text().splitlines()) < 3):
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert gone(mark)  # the run under way (a process group of its own) ended with its sweep
    before = [json.loads(line) for line in jsonl.read_text().splitlines() if line.endswith("}")]
    assert 3 <= len(before) < total
    done = subprocess.run([sys.executable, "-m", "bille", "sweep", str(spec_path), "--out", str(out)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    rows = [json.loads(line) for line in jsonl.read_text().splitlines()]
    keys = [r["key"] for r in rows]
    assert len(keys) == len(set(keys)) == total  # none repeated, none lost
    assert rows[: len(before)] == before  # the runs recorded before the kill were not run again


def marked(mark: str) -> list[int]:
    """The live processes whose environment carries ``mark`` (a sweep, its fork server, runs)."""
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as f:
                if f.read().rsplit(b")", 1)[1].split()[0] == b"Z":
                    continue
            with open(f"/proc/{entry}/environ", "rb") as f:
                if f"BILLE_TEST_MARK={mark}".encode() in f.read().split(b"\0"):
                    found.append(int(entry))
        except OSError:
            continue
    return found


def gone(mark: str, within: float = 30.0) -> bool:
    end = time.time() + within
    while marked(mark) and time.time() < end:
        time.sleep(0.1)
    return not marked(mark)


def interrupt(argv, ready, mark: str, timeout: float = 120.0) -> tuple[subprocess.Popen, str, str]:
    """Start ``bille ARGV`` in a session of its own, wait until ``ready(stderr so far)``, then
    send SIGINT to its process group as a terminal's Ctrl-C does; its exit, stdout, stderr."""
    import tempfile

    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen([sys.executable, "-m", "bille", *map(str, argv)], stdout=out, stderr=err,
                                start_new_session=True, env=dict(os.environ, BILLE_TEST_MARK=mark))
        end = time.time() + timeout
        while time.time() < end and proc.poll() is None:
            err.seek(0)
            if ready(err.read()):
                break
            time.sleep(0.05)
        assert proc.poll() is None, "ended before it could be interrupted"
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=60)  # a hang fails here; how soon it stops is not measured
        out.seek(0)
        err.seek(0)
        return proc, out.read(), err.read()


@pytest.mark.slow
def test_ctrl_c_stops_a_sweep_keeping_its_finished_runs(tmp_path):
    # crowded-2 finishes in a second; bridge-2 runs anytime (its bound search forked) for 300 s
    # unless stopped
    spec_path = write_spec(tmp_path, "time_limit: 300\ninstances: [crowded-2, bridge-2]\nmethods: {anytime: {}}\n")
    out, mark = tmp_path / "out", f"ctrl-c-{os.getpid()}-{time.time_ns()}"

    def ready(_):  # the first run recorded; the second one's process and its bound search running
        jsonl = out / "runs.jsonl"
        return jsonl.exists() and jsonl.read_text().count("\n") == 1 and len(marked(mark)) >= 4

    proc, said, _ = interrupt(["sweep", spec_path, "--out", out, "--jobs", "1"], ready, mark)
    assert proc.returncode == 130
    assert "interrupted; 1 of 2 runs recorded" in said
    assert gone(mark)  # nothing left running
    rows = load_table(out)  # the tables are written, with the finished run only
    assert [(r["instance"], r["status"]) for r in rows] == [("crowded-2", "optimal")]
    again = subprocess.run([sys.executable, "-m", "bille", "sweep", "report", str(out), "--no-plots"],
                           capture_output=True, text=True)
    assert again.returncode == 0 and "anytime" in again.stdout


@pytest.mark.slow
def test_ctrl_c_stops_gap_showing_and_writing_the_rows_finished(tmp_path):
    csv_path, mark = tmp_path / "gap.csv", f"gap-{os.getpid()}-{time.time_ns()}"
    proc, said, err = interrupt(["gap", "crowded-2", "bridge-2", "--methods", "mstar,bfs", "--time-limit", 300,
                                 "--csv", csv_path], lambda err: "running bfs on bridge-2" in err, mark)
    assert proc.returncode == 130, err
    assert "interrupted" in err.splitlines()[-1]
    import csv

    rows = list(csv.DictReader(csv_path.read_text().splitlines()))
    done = [(r["instance"], r["method"]) for r in rows if r["status"] != "interrupted"]
    assert done == [("crowded-2", "mstar"), ("crowded-2", "bfs"), ("bridge-2", "mstar")]
    assert rows[1]["makespan"] == rows[0]["lower_bound"] == "10"  # bfs's optimum bounds mstar's row
    assert "bridge-2" in said and "written to" in said
    assert gone(mark)


def test_gaps_are_measured_against_the_best_bound_of_the_sweep_as_gap_measures_them(tmp_path):
    # on corridor-2 mstar finds 13 steps and proves only the static bound 5; bfs proves 13
    from bille.tools import gap

    spec = load_spec(write_spec(tmp_path, "time_limit: 30\ninstances: [corridor-2]\nmethods: {mstar: {}, bfs: {}}\n"))
    _, rows = run_spec(spec, tmp_path / "out", jobs=2, quiet=True)
    by = {r["method"]: r for r in rows}
    assert by["bfs"]["status"] == "optimal" and by["bfs"]["makespan"] == 13
    assert by["mstar"]["lower_bound"] < 13 and by["mstar"]["makespan"] == 13
    assert by["mstar"]["best_lower_bound"] == 13 and by["mstar"]["certified_gap"] == 0.0
    assert load_table(tmp_path / "out") == sorted(rows, key=lambda r: r["key"])
    line = next(line for line in summary(rows) if line.split()[0] == "mstar")
    assert line.split()[6:8] == ["0.0%", "0.0%"]  # median and worst gap
    inst = load_instance(bundled_path("corridor-2"))
    measured = gap.run([inst], gap.parse_configs("mstar,bfs"), 30.0)
    assert [r["certified_gap_percent"] for r in measured] == [0.0, 0.0]


def test_gap_measures_the_heuristics_against_auto_by_default(tmp_path, cli, capsys):
    csv_path = tmp_path / "gap.csv"
    assert cli(["gap", "crowded-2", "--time-limit", 20, "--csv", csv_path, "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert [r["method"] for r in rows] == ["auto", "temporal-astar", "mstar", "astar"]
    optimum = solve(load_instance(bundled_path("crowded-2")), "bfs").metrics.makespan
    assert rows[0]["status"] == "optimal" and rows[0]["makespan"] == optimum
    assert all(r["lower_bound"] == optimum for r in rows)  # auto's proof bounds every row
    from bille.tools.gap import table

    shown = {line.split()[1]: line for line in table(rows, wide=True)[2:]}
    assert "optimal (sum of costs over walking-only schedules)" in shown["mstar"]
    assert "optimal (sum of costs over walking-only schedules)" in shown["astar"]
    narrow = table(rows)  # 120 columns: the restricted optima starred and said below the table
    assert max(len(line) for line in narrow) <= 120
    assert "* mstar: optimal for sum of costs, then makespan, walking only (no pick or place)" in narrow


def test_the_report_says_why_runs_failed(tmp_path):
    from bille.tools.sweep.results import certify

    def row(k, method, status, error=None, makespan=None, lower=None):
        return dict(key=f"h{k}|{method}|{{}}", instance=f"map-{k}", instance_hash=f"h{k}", robots=2, method=method,
                    label=method, status=status, makespan=makespan, lower_bound=lower, time_s=0.1, error=error)

    rows = certify([row(1, "anytime", "failed", "error: AssertionError: daemonic processes are not allowed"),
                    row(2, "anytime", "failed", "error: AssertionError: daemonic processes are not allowed"),
                    row(3, "anytime", "failed", "crashed (signal 9)"),
                    row(1, "astar", "n/a", "instance 'map-1' moves tiles"),
                    row(1, "cpsat", "optimal", makespan=9, lower=9), row(1, "mstar", "feasible", makespan=8, lower=3),
                    row(2, "mstar", "timeout", "time limit")])
    lines = summary(rows)
    table = {line.split()[0]: line.split() for line in lines[2:8] if line.strip()}
    assert table["anytime"][1:6] == ["3", "0", "0%", "3", "0"]  # runs, n/a, success, failed, no schedule
    assert table["astar"][1:6] == ["1", "1", "-", "0", "0"]
    assert table["mstar"][1:6] == ["2", "0", "50%", "0", "1"]  # "success 50 %" beside "failed 0": named below
    assert "  1 x timeout (time limit) (first: mstar on map-2)" in lines
    assert "  2 x error: AssertionError: daemonic processes are not allowed (first: anytime on map-1)" in lines
    assert "  1 x crashed (signal 9) (first: anytime on map-3)" in lines
    assert "  1 x instance 'map-1' moves tiles (first: astar on map-1)" in lines
    assert lines[-1] == ("contradiction: map-1: cpsat proved a lower bound of 9, above the valid schedule of 8 steps "
                         "of mstar")


def test_success_plot_counts_robots_in_whole_ticks(tmp_path, monkeypatch):
    from bille.tools.sweep import report

    ticks = {}

    def keep(fig, path):
        fig.canvas.draw()
        ticks[path.name] = list(fig.axes[0].get_xticks())
        return path

    monkeypatch.setattr(report, "_save", keep)
    rows = [dict(label="astar", robots=n, status="optimal", makespan=5, time_s=0.1, certified_gap=0.0) for n in (2, 3)]
    report.plots(rows, tmp_path)
    assert ticks["success.png"] and all(float(t).is_integer() for t in ticks["success.png"])


def test_sweep_run_help_names_every_shipped_sweep(cli, capsys):
    from bille.tools.sweep.spec import shipped_names

    assert cli(["sweep", "run", "--help"]) == 0
    said = " ".join(capsys.readouterr().out.split())
    assert "load-transfer" in shipped_names()
    for name in shipped_names():
        assert name in said


def crash(outbox, *args):
    os._exit(3)


@pytest.mark.slow
def test_failures_are_rows_with_their_reason(tmp_path):
    # building lt-4's SAT model takes far more than 100 MB (its static bound, with its linear
    # programs, a little less): the run fails, the sweep goes on.
    # CaDiCaL's failed allocation ends its process (std::bad_alloc on stderr); Glucose solves on
    # conflict budgets alone there (no timer thread under so tight a limit: one could hang as it
    # starts) and runs out of memory, in python-sat's wrapper or its own code. The limit is ample
    # (the memory runs out within seconds) so that a loaded machine cannot end a run in time first
    spec = load_spec(write_spec(tmp_path, "time_limit: 90\nmemory_limit: 100\ninstances: [lt-4, crowded-3]\n"
                                          "methods: {sat: {solver: [cadical195, glucose42]}}\n"))
    _, rows = run_spec(spec, tmp_path / "out", jobs=2, quiet=True)
    by = {(r["instance"], json.loads(r["options"])["solver"]): r for r in rows}
    assert len(by) == 4, rows
    assert by["lt-4", "cadical195"]["status"] == "failed" and "bad_alloc" in by["lt-4", "cadical195"]["error"]
    assert by["lt-4", "glucose42"]["status"] == "failed"
    said = by["lt-4", "glucose42"]["error"]
    assert said == "memory limit: more than 100 MB" or "OutOfMemoryException" in said, said
    assert by["crowded-3", "cadical195"]["status"] == by["crowded-3", "glucose42"]["status"] == "optimal"
    said = summary(rows)  # the report says why: each kind of error once, counted, with its first run
    reasons = [line for line in said if re.match(r"  \d+ x ", line)]
    assert sum(int(line.split()[0]) for line in reasons) == 2, said
    assert any(re.match(r"  [12] x crashed \(signal 6\): .*(bad_alloc|OutOfMemoryException).* \(first: "
                        r"sat:solver=(cadical195|glucose42) on lt-4\)$", line) for line in reasons), said
    crashed = execute(spec.runs[0], Limits(10), target=crash)
    assert crashed["status"] == "failed" and crashed["error"] == "crashed (exit code 3)"


@pytest.mark.parametrize("text, message", [
    ("instances: [crowded-3]\nmethods: {magic: {}}", "unknown method 'magic'"),
    ("instances: [crowded-3]\nmethods: {temporal-astar: {horizon: [0]}}", "horizon expects a number of at least 1"),
    ("instances: [nowhere.yaml]\nmethods: {astar: {}}", "matches no file"),
    ("instances: [{gen: 'random --moved x'}]\nmethods: {astar: {}}", "'x' is not a valid integer"),
    ("instances: [crowded-3]\nmethods: {astar: {}}\ntimelimit: 3", "unknown key 'timelimit'"),
])
def test_bad_sweep_files_name_the_file_and_the_entry(tmp_path, text, message):
    with pytest.raises(BilleError, match=message) as exc:
        load_spec(write_spec(tmp_path, text, "bad.yaml"))
    assert str(exc.value).startswith(str(tmp_path / "bad.yaml"))


def test_a_sweep_file_without_methods_runs_auto_as_bille_solve_does(tmp_path):
    spec = load_spec(write_spec(tmp_path, "instances: [crowded-2, compare-2]\n", "plain.yaml"))
    assert [(r.instance, r.method, r.options) for r in spec.runs] == [("crowded-2", "auto", ()),
                                                                      ("compare-2", "auto", ())]
    for text in ("instances: [crowded-2]\nmethods: {}\n", "instances: [crowded-2]\nmethods:\n"):
        with pytest.raises(BilleError, match="methods: expected a mapping"):  # given, but empty
            load_spec(write_spec(tmp_path, text, "empty.yaml"))


def test_the_planner_comparison_as_a_sweep_file_matches_direct_solves(tmp_path):
    from bille.tools.bench.planners import label, run_grid

    rows = run_grid(10.0, 2, maps=["compare-2"], movesets=["S7"], progress=False)
    assert len(rows) == 3 + 3 + 9 + 2
    inst = load_instance(bundled_path("compare-2"))
    for row in rows:
        if row["method"] == "lacam" and row["improve"]:
            continue  # improving for a time: not repeatable
        options = {k: row[k] for k in ("epsilon", "horizon", "improve") if row[k] is not None}
        if "epsilon" in options:
            options["epsilon"] = float(options["epsilon"])
        direct = solve(inst, row["method"], time_limit=10.0, **options)
        assert row["status"] == status_key(direct.status, direct.claim), label(row)
        assert row["makespan"] == (direct.metrics.makespan if direct.metrics else None), label(row)


def test_the_load_transfer_experiment_as_a_sweep_file_matches_direct_solves():
    from bille.tools.bench.transfer import _run, run_maps

    instances = [load_instance(bundled_path(name)) for name in ("lt-4", "lt-7")]
    rows = run_maps(instances, 10, 5, 60.0)
    for inst, row in zip(instances, rows):
        for tag, transfer in (("off", False), ("on", True)):
            direct = _run(inst, transfer, 10, 5, 60.0)
            assert row[f"steps_{tag}"] == (direct.metrics.makespan if direct.metrics else None), (inst.name, tag)
            assert row[f"traveled_{tag}"] == (direct.metrics.tiles_traveled if direct.metrics else None)
        assert row["relays"] == direct.stats.get("relays", 0) and row["tasks"] == direct.stats.get("jobs")


def test_the_load_transfer_experiment_on_random_instances_certifies_by_cpsat(monkeypatch):
    """bench load-transfer --random with --exact-limit: the loop's schedules and CP-SAT's optimum
    on a tiny random instance, one row per size (a local name once hid the call that runs CP-SAT)."""
    from bille.tools.bench import transfer

    monkeypatch.setattr(transfer, "SIZES", ((1, 1),))
    lines = list(transfer.random_report(1, 5, 5, 10.0, 20.0, "temporal-astar"))
    row = lines[-1].replace("|", " ").split()  # moved, robots, solved off, on, mean steps off, on, optimal, gaps, tasks
    assert row[:4] == ["1", "1", "1/1", "1/1"] and row[6] == "1", lines[-1]
    assert float(row[7]) >= 0 and float(row[8]) >= 0  # no schedule shorter than the optimum


def test_a_finished_sweep_run_again_says_none_was_run(cli, capsys, tmp_path):
    spec = tmp_path / "tiny.yaml"
    spec.write_text("name: tiny\ninstances: [crowded-2]\nmethods: {bfs: {}}\ntime_limit: 20\n")
    out = tmp_path / "results"
    assert cli(["sweep", spec, "--out", out, "--jobs", "1"]) == 0
    assert "(1 run now;" in capsys.readouterr().out
    assert cli(["sweep", spec, "--out", out, "--jobs", "1"]) == 0
    assert "none run again: every run was recorded before" in capsys.readouterr().out
