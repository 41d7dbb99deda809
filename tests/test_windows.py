"""The neighbourhood search of anytime: free windows prove, kept windows only shorten."""
import time

from bille.instances.schedule import Schedule
from bille.solvers import solve, validate
from bille.solvers.bracket import Bracket
from bille.solvers.incumbent import from_schedule
from bille.solvers.windows import Windows
from bille.encodings import SAT, UNSAT
from helpers import make, sched
from test_exact import SHORTER_BY_RELAY


def _relay():
    """Two point robots, a tile carried across: optimum 3 with a hand-over, 6 without one (and
    so 6 among the schedules that keep the structure)."""
    inst = make(SHORTER_BY_RELAY["grid"], SHORTER_BY_RELAY["robots"], goal=SHORTER_BY_RELAY["goal"], moveset="point")
    kept = solve(inst, "cpsat", keep_structure=True)
    assert kept.status == "optimal" and kept.metrics.makespan == 6
    return inst, from_schedule(inst, kept.schedule, "kept")


def _search(inst, bracket, kept: bool) -> Windows:
    return Windows(inst, bracket, "minisat22", 6, 30.0, True, time.perf_counter() + 60, kept=kept)


def test_a_kept_window_that_cannot_shorten_proves_no_bound():
    inst, best = _relay()
    bracket = Bracket(lower=1, best=best)
    search = _search(inst, bracket, kept=True)
    assert search.shorten(best, 0, best.makespan, time.perf_counter() + 30) == UNSAT
    assert bracket.lower == 1 and "proved_bound" not in search.counts  # the optimum is 3, not 6


def test_the_free_window_over_the_same_schedule_finds_the_optimum_and_proves_it():
    inst, best = _relay()
    bracket = Bracket(lower=1, best=best)
    search = _search(inst, bracket, kept=False)
    assert search.shorten(best, 0, best.makespan, time.perf_counter() + 30) == SAT
    assert bracket.best.makespan == 3 == bracket.lower == search.counts["proved_bound"]
    assert validate(inst, solve(inst, "bfs").schedule).metrics.makespan == 3


def test_kept_windows_shorten_where_they_can():
    # a schedule with a detour in the middle: the kept search's window cuts it out, and the
    # spliced schedule stays valid
    inst = make(".....\nTTTTT\n.....", [{"at": [0, 1]}], moveset="point", robot_goals=[[4, 1]])
    best = from_schedule(inst, sched("east east west east east east"), "detour")
    assert best.makespan == 6
    bracket = Bracket(lower=1, best=best)
    search = _search(inst, bracket, kept=True)
    assert search.shorten(best, 0, best.makespan, time.perf_counter() + 30) == SAT
    assert bracket.best.makespan == 4 and bracket.lower == 1
    assert validate(inst, Schedule.from_ids(inst, bracket.best.ids)).valid
