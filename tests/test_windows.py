"""The neighbourhood search of anytime: free windows prove, kept windows only shorten."""

from bille.instances.run import Budget
from bille.instances.schedule import Schedule
from bille.solvers import solve, validate
from bille.solvers.anytime.bracket import Bracket
from bille.solvers.incumbent import from_schedule
from bille.solvers.anytime.windows import Windows
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
    return Windows(inst, bracket, "minisat22", 6, 30.0, True, Budget(60), kept=kept)


def test_a_kept_window_that_cannot_shorten_proves_no_bound():
    inst, best = _relay()
    bracket = Bracket(lower=1, best=best)
    search = _search(inst, bracket, kept=True)
    assert search.shorten(best, 0, best.makespan, Budget(30)) == UNSAT
    assert bracket.lower == 1 and "proved_bound" not in search.counts  # the optimum is 3, not 6


def test_the_free_window_over_the_same_schedule_finds_the_optimum_and_proves_it():
    inst, best = _relay()
    bracket = Bracket(lower=1, best=best)
    search = _search(inst, bracket, kept=False)
    assert search.shorten(best, 0, best.makespan, Budget(30)) == SAT
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
    assert search.shorten(best, 0, best.makespan, Budget(30)) == SAT
    assert bracket.best.makespan == 4 and bracket.lower == 1
    assert validate(inst, Schedule.from_ids(inst, bracket.best.ids)).valid


class _Child:
    """The part of a background bound search that :class:`Ahead` reads: its horizon, the seconds
    of the horizons it refuted, and restarts (``bracket``: where proofs made elsewhere land)."""

    def __init__(self, k, seconds, bracket=None):
        self.k, self.seconds, self.restarts, self.bracket = k, seconds, 0, bracket

    def catch_up(self):
        if self.k < self.bracket.lower:
            self.restarts += 1


def test_a_horizon_decided_ahead_of_the_bound_search():
    from bille.solvers.anytime.rise import Ahead

    # one point robot four cells from its goal: the optimum is 4, horizons 1-3 are infeasible
    inst = make(".....\nTTTTT\n.....", [{"at": [0, 1]}], moveset="point", robot_goals=[[4, 1]])
    best = from_schedule(inst, sched("east east west east east east"), "detour")
    bracket = Bracket(lower=2, best=best)
    child = _Child(2, {0: 0.001, 1: 0.001}, bracket)  # refuted horizons 0 and 1, now on 2
    ahead = Ahead(inst, "cpsat", bracket, child, Budget(60))
    assert ahead.pick()[0] == 5  # the highest below the best schedule's 6 steps
    ahead.run(*ahead.pick())
    assert bracket.best.makespan <= 5 and validate(inst, Schedule.from_ids(inst, bracket.best.ids)).valid
    assert bracket.lower == 2 and child.restarts == 0  # a satisfiable horizon proves nothing
    h, expected = ahead.pick()
    assert h < bracket.best.makespan and h not in (5,)
    while (pick := ahead.pick()) is not None:
        ahead.run(*pick)
    assert bracket.lower == 4 == bracket.best.makespan and child.restarts >= 1  # 3 refuted: 4 is optimal
    assert [h for h, answer, _ in ahead.tried if answer == UNSAT] == [3]


def test_no_horizon_is_decided_ahead_before_two_are_refuted():
    from bille.solvers.anytime.rise import Ahead

    inst = make(".....\nTTTTT\n.....", [{"at": [0, 1]}], moveset="point", robot_goals=[[4, 1]])
    bracket = Bracket(lower=2, best=from_schedule(inst, sched("east east west east east east"), "detour"))
    assert Ahead(inst, "cpsat", bracket, _Child(2, {1: 0.001}), Budget(60)).pick() is None
    # a horizon expected to take longer than the time left is not tried
    slow = _Child(2, {0: 50.0, 1: 100.0})
    assert Ahead(inst, "cpsat", bracket, slow, Budget(60)).pick() is None
