"""The contract of ``solve()`` and ``bille solve`` (docs/decisions.md, "The solve() contract"):
the time limit covers the whole
call, the static bound is computed only where it is used or asked for, a schedule is validated
and named once, Ctrl-C ends with status ``interrupted`` and exit 130, progress from the start."""
from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from bille import solvers
from bille.instances import InstanceError, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.failure import Failure
from bille.instances.moveset import Moveset
from bille.instances.result import Result
from bille.instances.run import Budget
from bille.solvers import METHODS, Schedule, bind, load_schedule, solve, validate
from bille.solvers.bounds import Bounds, lower_bound


class FakeClock:
    """A clock moved on by hand, for the budget given to ``solve()``."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def clock():
    return FakeClock()


@pytest.fixture
def slow_bound(monkeypatch, clock):
    """The static bound replaced by one that takes ``seconds[0]`` on the fake clock; ``asked``
    records the seconds left in the budget each call was given."""
    asked, seconds = [], [7.0]

    def lower_bound(instance, *, budget=None):
        asked.append(budget.seconds())
        clock.now += seconds[0]
        return Bounds(3, {"slow part": 3}, [])

    import bille.solvers.bounds.classes  # noqa: F401  (imported first, it keeps the real bound for the class bounds)
    monkeypatch.setattr("bille.solvers.bounds.lower_bound", lower_bound)
    return asked, seconds


def spy_method(clock, seen, spends=0.0):
    """A method that takes the bound (as exact and anytime do), records what it was given and
    spends ``spends`` seconds on the fake clock."""
    def plan(instance, options=None, run=None, *, bounds=None) -> Result:
        seen.append((run.budget.seconds(), None if bounds is None else bounds.lower))
        clock.now += spends
        return Result("spy", "timeout", lower_bound=None)
    return plan


def spy_heuristic(clock, seen, spends=0.0):
    """A method that does not take the bound (as the heuristics)."""
    def plan(instance, options=None, run=None) -> Result:
        seen.append(run.budget.seconds())
        clock.now += spends
        return Result("spy", "unsolved", failure=Failure("stuck", "deadlock"))
    return plan


POINT4 = load_instance(bundled_path("point-4"))


def test_a_method_that_uses_the_bound_gets_the_time_it_left(monkeypatch, clock, slow_bound):
    asked, _ = slow_bound
    seen = []
    monkeypatch.setitem(METHODS, "anytime", spy_method(clock, seen, spends=2.0))
    result = solve(POINT4, "anytime", time_limit=10, budget=Budget(clock=clock))
    assert asked == [10.0] and seen == [(3.0, 3)]  # 7 s of bound, 3 s left for the method
    assert result.time_s == 9.0 and result.lower_bound == 3 and result.stats["bound_s"] == 7.0


def test_a_bound_that_takes_the_whole_limit_leaves_the_method_out(monkeypatch, clock, slow_bound):
    _, seconds = slow_bound
    seconds[0] = 12.0
    seen = []
    monkeypatch.setitem(METHODS, "anytime", spy_method(clock, seen))
    result = solve(POINT4, "anytime", time_limit=10, budget=Budget(clock=clock))
    assert seen == [] and result.status == "timeout" and result.lower_bound == 3
    assert "lower bound" in result.failure.text


def test_the_default_time_limit_of_a_method_counts_too(monkeypatch, clock, slow_bound):
    seen = []
    monkeypatch.setitem(METHODS, "anytime", spy_method(clock, seen))
    solve(POINT4, "anytime", budget=Budget(clock=clock))
    assert seen == [(53.0, 3)]  # the method's default 60 s, less the 7 s of the bound


def test_a_heuristic_computes_no_bound_unless_asked(monkeypatch, clock, slow_bound):
    asked, _ = slow_bound
    seen = []
    monkeypatch.setitem(METHODS, "temporal-astar", spy_heuristic(clock, seen, spends=4.0))
    plain = solve(POINT4, "temporal-astar", time_limit=10, budget=Budget(clock=clock))
    assert asked == [] and seen == [10] and plain.lower_bound is None and "bound_parts" not in plain.stats
    asked_for = solve(POINT4, "temporal-astar", time_limit=10, bound=True, budget=Budget(clock=clock))
    assert seen == [10, 10]  # the same time for the method: the bound comes after it
    assert asked == [6.0] and asked_for.lower_bound == 3 and asked_for.stats["bound_parts"] == {"slow part": 3}


def test_past_its_time_the_bound_leaves_out_its_linear_program():
    from bille.solvers.bounds import lower_bound

    inst = load_instance(bundled_path("lt-1"))
    full, cut = lower_bound(inst), lower_bound(inst, budget=Budget(0))
    assert full.parts["routing (LP)"] is not None and cut.parts["routing (LP)"] is None
    programs = ("routing (LP)", "scaffold scenarios (LP)")
    assert cut.parts["scaffold scenarios (LP)"] is None
    assert cut.lower == max(v for k, v in full.parts.items() if k not in programs) <= full.lower


def test_the_cli_says_when_no_bound_was_computed(cli, capsys):
    assert cli(["solve", "point-4", "-m", "astar"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("astar: optimal (sum of costs over walking-only schedules) in ") and "no makespan lower bound computed (--bound" in out
    assert cli(["solve", "point-4", "-m", "astar", "--bound"]) == 0
    out = capsys.readouterr().out
    assert "makespan lower bound 4" in out and "no makespan lower bound" not in out


def test_a_schedule_is_named_once_and_validated_once(monkeypatch):
    inst = load_instance(bundled_path("corridor-2"))
    ids = bind(inst, load_schedule(bundled_path("corridor-2.schedule")))
    built = Schedule.from_ids(inst, ids)

    def unread(self):
        raise AssertionError("the names were read again")

    with monkeypatch.context() as names:
        names.setattr(Moveset, "index", property(unread))
        assert np.array_equal(bind(inst, built), ids)  # the ids it was built from, no names read
    calls = []
    real = solvers.validate
    monkeypatch.setattr(solvers, "validate", lambda i, s: calls.append(s) or real(i, s))
    result = solve(inst, "temporal-astar")
    assert calls == [result.schedule] and result.status == "feasible"


# ---- Ctrl-C and progress, as a terminal sends and shows them --------------------------------

SPY = """
import functools, sys
from bille.solvers import METHODS
from bille.tools.cli import main

real = METHODS["bfs"]

@functools.wraps(real)
def running(*args, **kwargs):
    print("running", flush=True)
    return real(*args, **kwargs)

METHODS["bfs"] = running
main(sys.argv[1:])
"""


def test_ctrl_c_ends_a_solve_as_interrupted_with_exit_130(tmp_path):
    out = tmp_path / "s.yaml"
    # its own process group, sent SIGINT as a terminal sends Ctrl-C, once the method runs
    child = subprocess.Popen([sys.executable, "-c", SPY, "solve", "lt-1", "-m", "bfs", "-o", str(out), "--json"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        assert child.stdout.readline().strip() == "running"
        os.killpg(child.pid, signal.SIGINT)
        stdout, stderr = child.communicate(timeout=60)
    finally:
        if child.poll() is None:
            os.killpg(child.pid, signal.SIGKILL)
    assert child.returncode == 130, stderr
    result = json.loads(stdout)
    assert result["status"] == "interrupted" and result["metrics"] is None and "Traceback" not in stderr
    assert not out.exists()  # nothing found, nothing written


def test_an_interrupted_method_keeps_what_it_found(monkeypatch, cli, capsys, tmp_path):
    inst = load_instance(bundled_path("corridor-2"))
    found = solve(inst, "temporal-astar")

    def stopped(instance, options=None, run=None, *, bounds=None) -> Result:
        return Result("anytime", "interrupted", found.schedule, lower_bound=bounds.lower + 1)

    monkeypatch.setitem(METHODS, "anytime", stopped)
    out = tmp_path / "s.yaml"
    assert cli(["solve", "corridor-2", "-m", "anytime", "-o", out]) == 130
    text = capsys.readouterr().out
    assert text.startswith("anytime: interrupted in ") and f"makespan {found.metrics.makespan}," in text
    assert "makespan lower bound 6" in text and validate(inst, load_schedule(out)).valid


def _read_until(fd, needle: bytes, seconds: float) -> bytes:
    seen, end = b"", time.monotonic() + seconds
    while needle not in seen and time.monotonic() < end:
        if select.select([fd], [], [], 0.5)[0]:
            try:
                seen += os.read(fd, 4096)
            except OSError:
                break
    return seen


@pytest.mark.parametrize("as_json", [False, True])
def test_a_long_solve_shows_progress_from_the_start_on_a_terminal_only(as_json):
    import pty

    master, slave = pty.openpty()
    # on a terminal, a time limit far above the bound's (16, its programs included) and Ctrl-C once
    # the line shows it; with --json, nothing to wait for: the solve runs to its limit
    limit = "2" if as_json else "300"
    argv = ["solve", "bridge-2", "-m", "cpsat", "--time-limit", limit] + (["--json"] if as_json else [])
    child = subprocess.Popen([sys.executable, "-m", "bille", *argv], stdout=subprocess.PIPE, stderr=slave,
                             env=dict(os.environ, TERM="xterm", COLUMNS="120"), start_new_session=True)
    os.close(slave)
    try:
        shown = _read_until(master, b"makespan lower bound 16", 60)
        if not as_json:
            os.killpg(child.pid, signal.SIGINT)
        stdout, _ = child.communicate(timeout=60)
        shown += _read_until(master, b"\0", 0.5)
    finally:
        os.close(master)
        if child.poll() is None:
            os.killpg(child.pid, signal.SIGKILL)
    if as_json:
        assert shown == b"" and json.loads(stdout)["method"] == "cpsat"
    else:  # the bound is shown before the search's first horizon is decided
        assert b"cpsat: makespan lower bound 16, best schedule none yet" in shown


def test_a_benchmark_stops_with_the_solve_that_was_stopped(monkeypatch, cli, capsys):
    solved = []

    def fake(inst, method, **options):
        if inst.name == "crowded-2":
            return Result(method, "interrupted")
        solved.append((inst.name, method))
        return Result(method, "timeout", lower_bound=5)

    monkeypatch.setattr("bille.tools.bench.anytime.solve", fake)
    assert cli(["bench", "anytime", "--maps", "corridor-2,crowded-2,point-4", "--time-limit", "1"]) == 130
    out, err = capsys.readouterr()
    assert solved == [("corridor-2", "temporal-astar"), ("corridor-2", "anytime")]  # point-4 never started
    assert "corridor-2" in out and "crowded-2" not in out and "interrupted; 1 of 3 maps measured" in err


def test_an_interrupt_let_through_keeps_what_the_method_told(monkeypatch):
    inst = load_instance(bundled_path("corridor-2"))
    found = solve(inst, "temporal-astar")
    told = []

    class Found:  # as anytime tells a schedule: its action ids
        ids = bind(inst, found.schedule)

    def stopped(instance, options=None, run=None, *, bounds=None) -> Result:
        run.events.bound(bounds.lower + 2)
        run.events.schedule(Found())
        run.events.bound(bounds.lower + 1)  # a lower one changes nothing
        raise KeyboardInterrupt

    monkeypatch.setitem(METHODS, "anytime", stopped)
    result = solve(inst, "anytime", on_schedule=lambda f: told.append(f.ids.shape))
    assert result.status == "interrupted" and result.schedule.actions == found.schedule.actions
    assert result.metrics == found.metrics and result.lower_bound == lower_bound(inst).lower + 2
    assert told == [Found.ids.shape]  # a callback given to solve() is called too


def test_gap_shows_a_bound_from_the_file_as_a_claim_and_never_certifies_with_it(cli, capsys, tmp_path):
    import json

    from bille.instances import dump_instance

    inst = load_instance(bundled_path("crowded-2"))
    edited = tmp_path / "edited.yaml"
    edited.write_text(dump_instance(inst) + "meta: {lower_bound: 99}\n")
    assert cli(["gap", edited, "--methods", "bfs", "--time-limit", "30", "--csv", tmp_path / "g.csv", "--json"]) == 0
    (row,) = json.loads(capsys.readouterr().out)["rows"]
    assert row["status"] == "optimal" and row["lower_bound"] == row["makespan"] < 99  # the run's own proof
    assert row["certified_gap_percent"] == 0.0
    assert "the file's lower_bound 99 is wrong" in row["note"]


def test_solve_takes_a_bundled_name_or_says_what_it_takes():
    # an AttributeError deep inside before
    assert solve("compare-4", "cbs").status == "optimal"
    with pytest.raises(TypeError, match="takes an Instance, a file's path or a bundled name, not int"):
        solve(3, "cbs")
    with pytest.raises(InstanceError, match="no such file or bundled name"):
        solve("no-such-map", "cbs")
