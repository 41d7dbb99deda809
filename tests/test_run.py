"""The run context: a budget on a fake clock, cancelled from another thread or by Ctrl-C (random
moments: tests/test_interrupts.py)."""
import os
import signal
import threading

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.run import Budget, Events, Run
from bille.solvers import solve, validate


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_a_budget_reads_its_clock_and_its_parts_end_with_it():
    clock = Clock()
    run = Budget(10, clock=clock)
    part = run.child(4)
    half = run.share(0.5)
    assert run.left() == 10 and part.left() == 4 and half.left() == 5
    clock.now = 4.0
    assert part.expired() and not half.expired() and not run.expired() and run.elapsed() == 4
    assert run.child(100).left() == 6  # never past the parent's end
    clock.now = 10.0
    assert run.expired() and half.expired() and run.left() == 0.0


def test_a_budget_without_a_limit_never_expires_until_cancelled():
    clock = Clock()
    run = Budget(clock=clock)
    part = run.child()
    clock.now = 1e9
    assert not run.expired() and run.seconds() is None and run.share(0.5).seconds() is None
    part.cancel()  # any part cancels the whole run
    assert run.cancelled and run.expired() and run.left() == 0.0 and run.child(5).expired()


def test_events_go_to_whoever_listens():
    told = []
    events = Events(on_bound=told.append)
    events.bound(3)
    events.schedule("ignored")  # no listener: nothing happens
    events.progress({"lower": 3})
    assert told == [3] and Run.limited(1.0).budget.seconds() <= 1.0


def test_a_budget_cancelled_from_another_thread_ends_the_solve_with_what_it_found():
    inst = load_instance(bundled_path("lt-1"))
    budget = Budget()
    found = []

    def cancel_after_first(schedule):
        found.append(schedule)
        threading.Timer(0.3, budget.cancel).start()

    result = solve(inst, "anytime", time_limit=120, budget=budget, on_schedule=cancel_after_first)
    assert result.status == "interrupted" and found
    assert validate(inst, result.schedule).valid and result.lower_bound <= result.metrics.makespan
    assert "improvements" in result.stats  # anytime ended as at its time limit, with its statistics


def test_a_second_ctrl_c_unwinds_to_solve_which_keeps_what_was_told(monkeypatch):
    from bille.instances.result import Result
    from bille.solvers import METHODS

    def spin(instance, options=None, run=None):
        run.events.bound(5)
        os.kill(os.getpid(), signal.SIGINT)  # cancels the run
        assert run.budget.cancelled
        os.kill(os.getpid(), signal.SIGINT)  # unwinds from here
        return Result("spin", "timeout", lower_bound=5, stats={"returned": True})

    monkeypatch.setitem(METHODS, "temporal-astar", spin)
    result = solve(load_instance(bundled_path("point-4")), "temporal-astar")
    assert result.status == "interrupted" and "returned" not in result.stats and result.lower_bound == 5


def test_looking_a_method_up_by_name_imports_nothing():
    import subprocess
    import sys

    code = ("import sys; from bille.solvers import METHODS; assert 'anytime' in METHODS; "
            "print('bille.solvers.anytime' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout.strip() == "False"
