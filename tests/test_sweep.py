"""bille sweep: the same results table on local processes and a Dask cluster, resume after a kill,
failures recorded as rows, and the planner comparison as a sweep file."""
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from bille.instances import BilleError, load_instance
from bille.instances.bundled import bundled_path
from bille.solvers import load_schedule, solve, validate
from bille.tools.sweep.commands import run_spec
from bille.tools.sweep.engine import execute
from bille.tools.sweep.results import COLUMNS, TIMING, load_table
from bille.tools.sweep.spec import load_spec

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


def write_spec(tmp_path, text=SPEC, name="small.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def table(rows):
    return sorted(({c: r[c] for c in COLUMNS if c not in TIMING} for r in rows), key=lambda r: r["key"])


@pytest.mark.slow
def test_local_processes_and_a_dask_cluster_give_the_same_table(tmp_path):
    from distributed import Client, LocalCluster

    spec = load_spec(write_spec(tmp_path))
    assert len(spec.runs) == 4 * 3
    _, local = run_spec(spec, tmp_path / "local", jobs=2, quiet=True)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        _, dask = run_spec(spec, tmp_path / "dask", client=client, quiet=True)
    assert table(local) == table(dask)
    assert table(load_table(tmp_path / "local")) == table(local)  # the Parquet table holds the same rows
    for row in local:  # every schedule kept beside the table is valid for its instance
        assert row["status"] in ("optimal", "feasible", "unsolved"), row
        if row["schedule"]:
            inst = next(r for r in spec.runs if r.key == row["key"])
            from bille.instances import instance_from_text

            report = validate(instance_from_text(inst.text), load_schedule(tmp_path / "local" / row["schedule"]))
            assert report.valid and report.metrics.makespan == row["makespan"]
    import csv

    header = next(csv.reader((tmp_path / "local" / "results.csv").read_text().splitlines()))
    assert header == COLUMNS


@pytest.mark.slow
def test_a_killed_sweep_resumes_without_repeating_or_losing_a_run(tmp_path):
    spec_path = write_spec(tmp_path, SPEC.replace("0..2", "0..5"))
    out = tmp_path / "out"
    total = len(load_spec(spec_path).runs)
    proc = subprocess.Popen([sys.executable, "-m", "bille", "sweep", str(spec_path), "--out", str(out), "--jobs", "1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    jsonl = out / "runs.jsonl"
    end = time.time() + 120
    while time.time() < end and (not jsonl.exists() or len(jsonl.read_text().splitlines()) < 3):
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = [json.loads(line) for line in jsonl.read_text().splitlines() if line.endswith("}")]
    assert 3 <= len(before) < total
    done = subprocess.run([sys.executable, "-m", "bille", "sweep", str(spec_path), "--out", str(out)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    rows = [json.loads(line) for line in jsonl.read_text().splitlines()]
    keys = [r["key"] for r in rows]
    assert len(keys) == len(set(keys)) == total  # none repeated, none lost
    assert rows[: len(before)] == before  # the runs recorded before the kill were not run again


def crash(outbox, *args):
    os._exit(3)


@pytest.mark.slow
def test_failures_are_rows_with_their_reason(tmp_path):
    # building lt-4's SAT model takes far more than 50 MB: the run fails, the sweep goes on.
    # CaDiCaL's failed allocation ends its process (std::bad_alloc on stderr); Glucose solves on
    # conflict budgets alone there (no timer thread under so tight a limit: one could hang as it
    # starts) and runs out of memory, in python-sat's wrapper or its own code. The limit is ample
    # (the memory runs out within seconds) so that a loaded machine cannot end a run in time first
    spec = load_spec(write_spec(tmp_path, "time_limit: 90\nmemory_limit: 50\ninstances: [lt-4, crowded-3]\n"
                                          "methods: {sat: {solver: [cadical195, glucose42]}}\n"))
    _, rows = run_spec(spec, tmp_path / "out", jobs=2, quiet=True)
    by = {(r["instance"], json.loads(r["options"])["solver"]): r for r in rows}
    assert len(by) == 4, rows
    assert by["lt-4", "cadical195"]["status"] == "failed" and "bad_alloc" in by["lt-4", "cadical195"]["error"]
    assert by["lt-4", "glucose42"]["status"] == "failed"
    said = by["lt-4", "glucose42"]["error"]
    assert said == "memory limit: more than 50 MB" or "OutOfMemoryException" in said, said
    assert by["crowded-3", "cadical195"]["status"] == by["crowded-3", "glucose42"]["status"] == "optimal"
    crashed = execute(spec.runs[0], 10, None, target=crash)
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
        assert row["status"] == direct.status, label(row)
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
