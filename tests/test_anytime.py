"""Anytime certified solving, incumbents, honest statuses and the gap report, against the
brute-force search on tiny instances."""
import dataclasses
import json
import multiprocessing
import threading
import time

import numpy as np
import pytest

from bille.instances import OptionError, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.failure import Failure
from bille.instances.moveset import Kind
from bille.instances.run import Budget
from bille.instances.schedule import Schedule, bind, save_schedule
from bille.solvers import solve, validate
from bille.solvers.anytime import method as anytime
from bille.solvers.bfs import Options as BfsOptions
from bille.solvers.bfs import plan as bfs
from helpers import make, sched
from tinyworlds import tiny_instances

OPTIMA = {}
for _inst in tiny_instances(16, first_seed=500, max_robots=2):
    _ref = bfs(_inst, BfsOptions(max_states=20_000, engine="python"))
    if _ref.status == "optimal" and len(OPTIMA) < 6:
        OPTIMA[_inst] = _ref.lower_bound  # the brute force's proved optimum
SOLVABLE = list(OPTIMA)


def _monotone(stats, optimum):
    spans = [m for _, m in stats["improvements"]]
    lowers = [b for _, b in stats["lower_bounds"]]
    assert spans == sorted(spans, reverse=True) and len(set(spans)) == len(spans)
    assert lowers == sorted(lowers) and all(b <= optimum for b in lowers)


def test_tiny_instances_are_solvable():
    assert len(SOLVABLE) >= 5


@pytest.mark.parametrize("bound_solver", ["cpsat", "cadical195"])
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("k", range(3))
def test_anytime_proves_the_brute_force_optimum(k, parallel, bound_solver):
    inst = SOLVABLE[k + (3 if parallel else 0)]
    optimum = OPTIMA[inst]
    seen = []
    result = solve(inst, "anytime", time_limit=60, parallel=parallel, bound_solver=bound_solver,
                   progress=seen.append)
    assert result.status == "optimal", result.stats
    assert validate(inst, result.schedule).valid
    assert result.metrics.makespan == result.lower_bound == optimum
    _monotone(result.stats, optimum)
    assert seen and all(e["lower"] <= optimum for e in seen)


def test_subscribers_hear_every_schedule_and_bound_and_a_bad_one_is_refused():
    inst = SOLVABLE[5]
    schedules, bounds = [], []
    result = solve(inst, "anytime", time_limit=60, parallel=False, on_schedule=schedules.append,
                   on_bound=bounds.append)
    assert result.status == "optimal" and validate(inst, result.schedule).valid
    assert [found.makespan for found in schedules] == [m for _, m in result.stats["improvements"]]
    assert bounds == [b for _, b in result.stats["lower_bounds"]] and bounds[-1] == OPTIMA[inst]
    for found in schedules:
        assert validate(inst, Schedule.from_ids(inst, found.ids)).metrics.makespan == found.makespan
    with pytest.raises(OptionError, match="on_bound must be a function"):
        solve(inst, "anytime", on_bound=3)


@pytest.mark.parametrize("solver", ["minisat22", "cpsat"])
@pytest.mark.parametrize("k", range(3))
def test_the_whole_schedules_window_proves_the_optimum_without_the_bound_search(monkeypatch, k, solver):
    """With the bound search switched off, only the windows can raise the bound: the window that
    spans the whole schedule is the exact search from the start to the goal, so the shortest
    schedule it proves (or its proof that none is shorter) is the optimum."""
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)
    below = [inst for inst in SOLVABLE if anytime.lower_bound(inst).lower < OPTIMA[inst]]
    inst = below[k]
    optimum = OPTIMA[inst]
    result = solve(inst, "anytime", time_limit=30, parallel=False, solver=solver)
    assert validate(inst, result.schedule).valid
    assert result.status == "optimal" and result.metrics.makespan == result.lower_bound == optimum
    assert result.stats["windows"]["proved_bound"] == optimum
    _monotone(result.stats, optimum)


def _solve_and_send(inst, outbox):
    try:
        result = solve(inst, "anytime", time_limit=60)
        outbox.send(("done", result.status, result.stats.get("bound_search"), bind(inst, result.schedule).tolist()))
    except BaseException as e:  # what went wrong, for the test to show
        outbox.send(("error", repr(e), None, None))


def test_in_a_daemonic_process_the_two_searches_take_turns():
    """A daemonic process (a pool's worker, a sweep's run) may not start a child: the bound
    search then takes turns with the rest, and says so."""
    import multiprocessing

    inst = SOLVABLE[3]
    fork = multiprocessing.get_context("fork")
    inbox, outbox = fork.Pipe(duplex=False)
    worker = fork.Process(target=_solve_and_send, args=(inst, outbox), daemon=True)
    worker.start()
    assert inbox.poll(120), "the daemonic process sent nothing"
    kind, status, how, ids = inbox.recv()
    worker.join()
    assert kind == "done", status
    assert status == "optimal" and how == "in turns: a daemonic process cannot start a child"
    schedule = Schedule.from_ids(inst, np.array(ids, dtype=np.int64))
    assert validate(inst, schedule).metrics.makespan == OPTIMA[inst]
    assert solve(inst, "anytime", time_limit=60).stats["bound_search"] == "child process"


def _stop(found):
    raise KeyboardInterrupt


@pytest.mark.parametrize("parallel", [False, True])
def test_interrupted_keeps_the_best_schedule_and_bound_and_leaves_no_child(parallel):
    """Ctrl-C, here raised by a subscriber at the first schedule: the run ends ``interrupted``
    with that schedule and the static bound, and its child process is gone."""
    import multiprocessing

    inst = SOLVABLE[5]  # the heuristics' first schedule, 8 steps, is optimal; the static bound is 5
    result = solve(inst, "anytime", time_limit=120, parallel=parallel, on_schedule=_stop)
    assert result.status == "interrupted"
    assert validate(inst, result.schedule).metrics.makespan == result.stats["first"]["makespan"] == OPTIMA[inst]
    # the static bound, or what the child proved and sent before the Ctrl-C (read before it is closed)
    assert anytime.lower_bound(inst).lower <= result.lower_bound <= OPTIMA[inst]
    assert result.stats["bound_search"] == ("child process" if parallel else "in turns: parallel is off")
    assert not multiprocessing.active_children()


def _padded(inst, schedule, waits):
    """The schedule with ``waits`` joint waits inserted after its first step."""
    ids = bind(inst, schedule)
    wait = [int(np.flatnonzero(g.kind == Kind.WAIT)[0]) for g in inst.world.graphs]
    pad = np.array([wait] * waits, dtype=np.int64).T
    return Schedule.from_ids(inst, np.concatenate([ids[:, :1], pad, ids[:, 1:]], axis=1))


@pytest.mark.parametrize("solver", ["minisat22", "cpsat"])
def test_the_whole_schedules_window_proves_the_shortest_schedule_it_finds(monkeypatch, solver):
    """A padded optimal schedule, one window over all of it: the call that finds the optimum also
    proves that nothing is shorter, so one window closes the run."""
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)
    inst = next(inst for inst in SOLVABLE if anytime.lower_bound(inst).lower < OPTIMA[inst])
    optimal = solve(inst, "sat", minimize_travel=False)
    padded = _padded(inst, optimal.schedule, 3)
    result = solve(inst, "anytime", time_limit=30, parallel=False, incumbent=padded, solver=solver, window=64)
    assert result.status == "optimal" and result.lower_bound == result.metrics.makespan == OPTIMA[inst]
    assert validate(inst, result.schedule).valid
    assert result.stats["windows"]["tried"] == 1 and result.stats["windows"]["shortened"] == 1
    assert result.stats["windows"]["proved_bound"] == OPTIMA[inst]


@pytest.mark.parametrize("solver", ["minisat22", "cpsat"])
def test_a_whole_window_shortened_to_one_step_proves_it(monkeypatch, solver):
    """A part of one step is the shortest there is: the window over the whole schedule proves
    the bound 1 with either kind of solver."""
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)
    inst = make("TTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[1, 0]])
    late = sched("wait east")
    result = solve(inst, "anytime", time_limit=30, parallel=False, incumbent=late, solver=solver, window=64)
    assert result.status == "optimal" and result.metrics.makespan == result.lower_bound == 1
    assert validate(inst, result.schedule).valid
    assert result.stats["windows"]["proved_bound"] == 1


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["minisat22", "glucose42", "cpsat"])
def test_the_windows_shorten_a_padded_schedule_to_the_optimum(monkeypatch, solver):
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)  # no bound search: windows only
    inst = load_instance(bundled_path("corridor-2"))
    optimal = solve(inst, "sat", minimize_travel=False)
    padded = _padded(inst, optimal.schedule, 5)
    assert validate(inst, padded).metrics.makespan == optimal.metrics.makespan + 5
    # the run ends when a window proves the optimum (1-3 s here); the limit is far above that
    result = solve(inst, "anytime", time_limit=120, parallel=False, incumbent=padded, solver=solver,
                   keep_class=False)
    assert result.status in ("optimal", "feasible")
    assert validate(inst, result.schedule).valid
    assert result.metrics.makespan == optimal.metrics.makespan
    # the free windows or, after a slice in which they shortened nothing, the kept ones
    shortened = result.stats["windows"]["shortened"] + result.stats["kept_windows"]["shortened"]
    assert shortened >= 1 and result.stats["first"]["method"] == "given"
    _monotone(result.stats, optimal.metrics.makespan)


def test_an_impossible_instance_is_infeasible_with_no_bound():
    from helpers import make

    walled = make("TT#..\nTT#..", [{"at": [0, 0]}], goal="..#TT\n..#TT", moveset="point")
    result = solve(walled, "anytime", time_limit=5)
    assert result.status == "infeasible" and result.schedule is None and result.lower_bound is None


def test_with_no_schedule_from_the_heuristics_the_complete_planner_gives_one(monkeypatch):
    monkeypatch.setattr(anytime, "first_schedule", lambda *args, **kw: None)
    monkeypatch.setattr(anytime, "fewer_robots", lambda *args, **kw: None)
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)  # no bound search
    inst = SOLVABLE[0]
    result = solve(inst, "anytime", time_limit=2, parallel=False)
    assert result.stats["first"]["method"] in ("lacam", "lacam-states"), result.stats
    assert validate(inst, result.schedule).valid
    assert result.metrics.makespan >= OPTIMA[inst]
    _monotone(result.stats, result.stats["first"]["makespan"])


def _late_runs(monkeypatch, needs: dict) -> list:
    """``incumbent._run`` faked: run ``name`` gives reconfig-30's bundled schedule when it has at
    least ``needs[name]`` seconds (None: it gives up at once), else runs out of time, between the
    loop's steps except for "one step" (a joint plan not found in time). Returns the log of
    (name, seconds) calls."""
    from bille.instances.result import Result
    from bille.instances.schedule import load_schedule
    from bille.solvers import incumbent

    sched = load_schedule(bundled_path("reconfig-30.schedule"))
    calls = []

    def run(instance, how, budget, improve):
        limit = round(budget.left(), 1)
        calls.append((how, limit))
        if needs[how] is None:
            return Result(how, "unsolved", failure=Failure("stuck", "deadlock"))
        if limit >= needs[how]:
            return Result(how, "feasible", sched)
        return Result(how, "timeout", failure=Failure("time-limit", "time limit") if how != "one step"
                      else Failure("stuck", "no joint plan"))

    monkeypatch.setattr(incumbent, "_run", run)
    return calls


def test_runs_cut_short_are_retried_with_twice_the_time(monkeypatch):
    from bille.solvers.incumbent import retry

    inst = load_instance(bundled_path("reconfig-30"))
    calls = _late_runs(monkeypatch, {"slow": 1.5, "stuck": None, "never": 1e9, "one step": 1e9})
    cut = [(name, name, 0.5) for name in ("never", "stuck", "one step", "slow")]
    found = retry(inst, cut, budget=Budget(30.0))
    assert found is not None and found.method == "slow"
    assert calls == [("never", 1.0), ("stuck", 1.0), ("one step", 1.0), ("slow", 1.0), ("never", 2.0),
                     ("slow", 2.0)]
    assert validate(inst, Schedule.from_ids(inst, found.ids)).valid
    assert retry(inst, [("never", "never", 0.5)], budget=Budget(1.0)) is None  # the budget bounds it


def test_a_first_run_cut_short_gives_the_first_schedule_with_more_time(monkeypatch):
    calls = _late_runs(monkeypatch, {"late": 2.0})

    def first(instance, budget, improve=True, cut=None):
        cut.append(("late", "late", 1.0))

    monkeypatch.setattr(anytime, "first_schedule", first)
    monkeypatch.setattr(anytime, "fewer_robots", lambda *args, **kw: None)
    monkeypatch.setattr(anytime, "complete_search", lambda *args, **kw: pytest.fail("not needed"))
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)  # no bound search
    inst = load_instance(bundled_path("reconfig-30"))
    # a time limit far above the seconds the retry needs, and the run stopped at its first schedule
    result = solve(inst, "anytime", time_limit=60, parallel=False, keep_class=False, on_schedule=_stop)
    assert result.stats["first"]["method"] == "late" and calls == [("late", 2.0)]
    assert result.status == "interrupted" and validate(inst, result.schedule).valid


@pytest.mark.slow
def test_with_no_schedule_from_every_robot_the_loop_with_fewer_gives_one(monkeypatch):
    monkeypatch.setattr(anytime, "first_schedule", lambda *args, **kw: None)
    monkeypatch.setattr(anytime.Rise, "step", lambda self, until: None)  # no bound search
    monkeypatch.setattr(anytime, "complete_search", lambda *args, **kw: pytest.fail("not needed"))
    inst = load_instance(bundled_path("reconfig-30"))
    result = solve(inst, "anytime", time_limit=5, parallel=False, keep_class=False)
    assert "+robots" in result.stats["first"]["method"], result.stats
    assert validate(inst, result.schedule).valid
    _monotone(result.stats, result.stats["first"]["makespan"])


@pytest.mark.slow
def test_an_instance_the_complete_planner_exhausts_is_infeasible():
    # no static proof on these: the search over whole states runs out of states, as the brute force
    from bille.solvers.bounds import lower_bound
    from test_lacam import TINY_RECONFIGURATION, brute_force

    hard = [i for i in TINY_RECONFIGURATION if not lower_bound(i).impossible
            and brute_force(i.name).status == "infeasible"][:3]
    assert len(hard) == 3
    for inst in hard:
        result = solve(inst, "anytime", time_limit=30)
        assert result.status == "infeasible" and result.schedule is None and result.lower_bound is None
        assert result.stats["reason"] == "the complete planner exhausted the reachable states"


class _Ticks:
    """A clock that moves on 10 ms each time it is read: M* runs out of 50 ms after a few
    expansions, on any machine and under any load."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        self.now += 0.01
        return self.now


def test_gave_up_and_out_of_time_are_told_apart():
    from bille.instances.run import Budget

    deadlock = solve(load_instance(bundled_path("crowded-2")), "temporal-astar", time_limit=60,
                     budget=Budget(clock=_Ticks()))
    assert deadlock.status == "unsolved" and deadlock.failure.text == "deadlock"  # before its time limit
    late = solve(load_instance(bundled_path("compare-6")), "mstar", time_limit=0.05, bound=True,
                 budget=Budget(clock=_Ticks()))
    assert late.status == "timeout" and late.schedule is None and late.lower_bound is not None


def test_gap_takes_options_a_schedule_file_and_keeps_a_timeouts_bound(tmp_path, capsys):
    # M* needs about 0.5 s on compare-6 (the real clock: the command line makes its own budget),
    # ten times its limit here
    from bille.tools.cli import main

    inst = load_instance(bundled_path("compare-3"))
    mine = tmp_path / "mine.yaml"
    save_schedule(solve(inst, "temporal-astar").schedule, mine)
    out_csv = tmp_path / "gap.csv"
    with pytest.raises(SystemExit) as done:
        main(["gap", "compare-3", "compare-6", "--methods", "temporal-astar:H=2,epsilon=2,mstar:time_limit=0.05",
              "--schedule", str(mine), "--csv", str(out_csv), "--json"])
    assert done.value.code == 0
    rows = {(r["instance"], r["method"]): r for r in json.loads(capsys.readouterr().out)["rows"]}
    assert set(rows) == {(i, m) for i in ("compare-3", "compare-6")
                         for m in ("temporal-astar:H=2,epsilon=2", "mstar:time_limit=0.05")} | {("compare-3", "mine")}
    late = rows["compare-6", "mstar:time_limit=0.05"]
    assert late["status"] == "timeout" and late["makespan"] is None
    assert late["own_lower_bound"] is not None and late["lower_bound"] >= late["own_lower_bound"]
    given = rows["compare-3", "mine"]
    lower = given["lower_bound"]
    assert given["status"] == "given" and lower <= given["makespan"]
    assert given["certified_gap_percent"] == round(100 * (given["makespan"] - lower) / lower, 1)
    header = out_csv.read_text().splitlines()[0].split(",")
    assert header[:6] == ["instance", "method", "status", "makespan", "own_lower_bound", "lower_bound"]
    assert "certified_gap_percent" in header


def test_gap_shows_a_bound_from_the_metadata_as_a_claim_not_a_proof():
    from bille.tools.gap import Config, run

    inst = load_instance(bundled_path("compare-3"))
    optimum = solve(inst, "sat").metrics.makespan
    inst = dataclasses.replace(inst, meta={"optimum": optimum})
    rows = run([inst], [Config("temporal-astar", "temporal-astar")], 60)
    assert f"the file's optimum {optimum}, not proved here" in rows[0]["note"]
    proved = solve(inst, "temporal-astar", bound=True).lower_bound  # the run's own proof only
    assert rows[0]["lower_bound"] == proved and rows[0]["gap_percent"] is None


def test_a_window_may_end_with_interchangeable_robots_in_each_others_places():
    # two point robots on a one-row strip cannot pass each other: a window that must end with
    # them exchanged is infeasible, unless they may take each other's roles (then waiting does)
    from bille.encodings.backend import open_backend
    from bille.encodings.ends import roles_taken
    from bille.encodings.model import Options, build

    inst = make("TTTT", [{"at": [0, 0]}, {"at": [3, 0]}], moveset="point")
    start = inst.start_state
    exchanged = dataclasses.replace(start, poses=start.poses[::-1])
    for swap, answer in ((False, False), (True, True)):
        model = build(inst, 3, Options(), end=exchanged, swap=swap)
        with open_backend("cadical195", model, inst) as backend:
            outcome = backend.solve()
        assert outcome.status == ("sat" if answer else "unsat")
        if answer:
            assert roles_taken(model, outcome.value, 2) == [1, 0]
    with_goals = make("TTTT", [{"at": [0, 0]}, {"at": [3, 0]}], moveset="point", robot_goals=[[0, 0], None])
    model = build(with_goals, 3, Options(), end=exchanged, swap=True)  # a robot with a goal keeps its role
    with open_backend("cadical195", model, with_goals) as backend:
        assert backend.solve().status == "unsat"


@pytest.mark.slow
def test_compaction_moves_actions_into_waits_and_keeps_the_schedule_valid():
    from bille.solvers.compact import compact
    from test_lacam import TINY_RECONFIGURATION, brute_force

    inst = load_instance(bundled_path("corridor-2"))
    optimal = solve(inst, "sat", minimize_travel=False)
    late = bind(inst, _padded(inst, optimal.schedule, 4))  # four joint waits after the first step
    back = compact(inst, late)
    assert validate(inst, Schedule.from_ids(inst, back)).valid
    assert back.shape[1] == optimal.metrics.makespan
    for tiny in TINY_RECONFIGURATION[:12]:  # schedules full of waits from the whole-state search
        found = solve(tiny, "lacam", time_limit=10, improve=0.0)
        if found.schedule is None:
            continue
        squeezed = compact(tiny, bind(tiny, found.schedule))
        report = validate(tiny, Schedule.from_ids(tiny, squeezed))
        assert report.valid and brute_force(tiny.name).metrics.makespan <= squeezed.shape[1] <= found.metrics.makespan


def test_the_scaffold_scenarios_taken_further_raise_the_bound_in_a_child():
    # static bound 3 on this instance; the scaffold search, its least scenario's program split
    # by robot, proves 4, the brute force's optimum
    from bille.solvers.anytime.bracket import Bracket
    from bille.solvers.anytime.rise import Scaffold
    from bille.solvers.bounds import lower_bound

    inst = tiny_instances(1, first_seed=10_003, max_robots=2)[0]
    bounds = lower_bound(inst)
    assert bounds.lower == 3 and bounds.scaffold is not None
    bracket = Bracket(bounds.lower)
    scaffold = Scaffold(bounds.scaffold, bracket, Budget().child(60), 60)
    scaffold.run()
    assert bracket.lower == 4 == bfs(inst, BfsOptions(max_states=20_000, engine="python")).lower_bound
    assert [value for _, value in scaffold.proved] == [4] and not scaffold.pending


class _Stuck:
    """A search that proves one value and then never returns, as an integer program may."""

    def advance(self, budget, split=False, on_value=None):
        on_value(7)
        while True:
            time.sleep(1)


@pytest.mark.parametrize("how", ["time", "cancel"])
def test_the_scaffold_child_is_stopped_and_what_it_proved_is_kept(how):
    from bille.solvers.anytime.bracket import Bracket
    from bille.solvers.anytime.rise import Scaffold

    budget = Budget().child(1.0 if how == "time" else 600)
    bracket = Bracket(5)
    scaffold = Scaffold(_Stuck(), bracket, budget, 600)
    if how == "cancel":  # as Ctrl-C does
        threading.Timer(0.5, budget.cancel).start()
    scaffold.run()
    assert bracket.lower == 7 and scaffold.proved[0][1] == 7
    assert not multiprocessing.active_children()  # stopped, not left running
