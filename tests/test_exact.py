"""Exact solvers: both back ends agree with breadth-first search on tiny instances."""
import pytest

from bille.instances import OptionError, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.run import Budget
from bille.instances.schedule import Schedule, bind
from bille.solvers import solve, validate
from bille.solvers.bounds import lower_bound
from helpers import make, manipulations
from test_soundness import reference
from tinyworlds import tiny_instances

TINY = {
    "point-walk": lambda: make("TTTT\nT..T\nTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[3, 2]]),
    "point-pass": lambda: make("TTTTT\n..T..", [{"at": [0, 0]}, {"at": [4, 0]}], moveset="point",
                               robot_goals=[[4, 0], [0, 0]]),
    "point-move-tile": lambda: make("TTT.\n....", [{"at": [1, 0]}], goal="TT..\n.T..", moveset="point"),
    "s5-move-tile": lambda: make(".....\nTTTT.\nTTTT.\n.....", [{"front": [1, 2], "back": [0, 2]}],
                                 goal=".....\n.TTTT\nTTTT.\n.....", moveset="S5"),
    "s7-carry-place": lambda: make("....\nTTT.\n....", [{"front": [1, 1], "back": [0, 1], "carrying": True}],
                                   goal="....\nTTTT\n....", moveset="S7"),
    "s7-two-robots": lambda: make("TTTT\nTTTT", [{"front": [1, 0], "back": [0, 0]}, {"front": [2, 1], "back": [3, 1]}],
                                  robot_goals=[[3, 0], [0, 1]]),
    # cooperation: the tile at (4, 0) must go to (0, 0), but in the one-tile corridor the robots
    # can never pass each other: robot 1 can reach the tile, only robot 0 the place
    "handover": lambda: make("....T\nTTTTT", [{"at": [1, 1]}, {"at": [3, 1]}], goal="T....\nTTTTT",
                             moveset="point", robot_goals=[[1, 1], [3, 1]]),
}


@pytest.fixture(scope="module")
def optimum():
    cache = {}

    def get(name):
        if name not in cache:
            result = solve(TINY[name](), "bfs", time_limit=300)
            assert result.status == "optimal"
            cache[name] = result.metrics.makespan
        return cache[name]

    return get


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in ("handover", "point-pass") else n
                                  for n in TINY])
@pytest.mark.parametrize("method", ["cpsat", "cpsat-lanes", "sat"])
@pytest.mark.parametrize("connectivity", ["lazy", "eager", "cuts"])
def test_exact_makespan_equals_breadth_first_search(name, method, connectivity, optimum):
    # cpsat-lanes: two workers, two horizons side by side
    inst = TINY[name]()
    threads = {"threads": 2} if method == "cpsat-lanes" else {}
    result = solve(inst, method.split("-")[0], connectivity=connectivity, time_limit=120, **threads)
    assert all(h["answer"] in ("sat", "unsat", "stopped") for h in result.stats["horizons"])
    assert result.status == "optimal", result.stats
    assert validate(inst, result.schedule).valid
    assert result.metrics.makespan == result.lower_bound == optimum(name)


def test_cooperation_is_needed_and_found():
    inst = TINY["handover"]()
    result = solve(inst, "cpsat", time_limit=120)
    assert result.status == "optimal"
    # robot 0 cannot stay out of it: it picks or places the tile, or climbs onto a tile placed
    # for it so that robot 1 can pass
    steps = result.schedule.actions[0]
    assert any(a.startswith(("pick", "place", "north")) for a in steps)


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_single_carry_leaves_out_the_hand_over(method, optimum):
    from bille.encodings.backend import open_backend
    from bille.encodings.model import Options, build
    from bille.encodings.solution import decode

    # carried once, straight from its start to its goal, the tile could not get past a robot
    inst = TINY["handover"]()
    capped = solve(inst, method, single_carry=True, max_makespan=16)
    assert capped.status == "unsolved" and capped.claim.lower == 17
    assert "single-carry" in capped.failure.text
    # no bound for the instance: a schedule with a hand-over is shorter (one of 16 steps, from
    # the model of all schedules; the brute force's optimum, 12, costs seconds)
    model = build(inst, 16, Options())
    with open_backend("glucose42", model, inst) as backend:
        outcome = backend.solve()
    shorter = validate(inst, Schedule.from_ids(inst, decode(model, inst, outcome.value))).metrics.makespan
    assert capped.lower_bound == lower_bound(inst).lower <= shorter < 17
    plain = TINY["point-move-tile"]()
    result = solve(plain, method, single_carry=True)
    assert result.status == "optimal" and result.metrics.makespan == optimum("point-move-tile")
    assert result.claim.spelled == "single_carry" and validate(plain, result.schedule).valid


# the best single-carry schedule takes 6 steps; the optimum, 3, takes a tile out of the
# structure and puts the carried one in its place
SHORTER_BY_RELAY = dict(grid=".....\nTTTTT\n.TTTT", robots=[{"at": [3, 1]}, {"at": [1, 2]}],
                        goal=".T...\nTTTTT\n.TTT.", moveset="point")


@pytest.mark.parametrize("restriction", ["single_carry", "keep_structure"])
@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_a_restricted_proof_is_no_bound_for_the_instance(method, restriction):
    from bille.tools.gap import parse_configs, run

    inst = make(SHORTER_BY_RELAY["grid"], SHORTER_BY_RELAY["robots"], goal=SHORTER_BY_RELAY["goal"],
                moveset="point")
    best = solve(inst, "bfs", time_limit=60)
    assert best.status == "optimal" and best.metrics.makespan == 3
    restricted = solve(inst, method, **{restriction: True})
    assert restricted.status == "optimal" and restricted.metrics.makespan == 6
    assert restricted.claim.lower == 6 and restricted.claim.spelled == restriction
    assert restricted.lower_bound <= best.metrics.makespan
    assert validate(inst, restricted.schedule).valid
    with pytest.raises(OptionError, match=restriction):  # the optimum would cap the restricted search
        solve(inst, method, incumbent=best.schedule, **{restriction: True})
    # in the gap report the restricted optimum certifies nothing: the optimum is the plain search's
    rows = {r["method"]: r for r in run([inst], parse_configs(f"{method}:{restriction}=true,{method}"), 60)}
    assert rows[method]["status"] == "optimal" and rows[method]["makespan"] == 3
    assert all(r["lower_bound"] == 3 and r["best"] == 3 for r in rows.values())
    assert rows[f"{method}:{restriction}=true"]["gap_percent"] == 100.0


def _keeps_structure(inst, schedule) -> bool:
    differ = inst.start.tiles != inst.goal_tiles
    return all(differ[c] for _, _, _, c in manipulations(inst, schedule))


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_keeping_the_structure_is_optimal_where_brute_force_keeps_it(method):
    # the restricted optimum lies between the optimum and the single-carry optimum, and equals the
    # optimum wherever the brute-force search's optimal schedule keeps the structure itself
    kept = 0
    for inst in tiny_instances(12, 400):
        best = reference(inst)
        if best.status != "optimal":
            continue
        got = solve(inst, method, keep_structure=True, max_makespan=best.lower_bound + 10, time_limit=60)
        assert got.lower_bound <= best.lower_bound, inst.name  # the instance's bound only
        if _keeps_structure(inst, best.schedule):
            kept += 1
            assert got.status == "optimal" and got.metrics.makespan == best.lower_bound, inst.name
        if got.schedule is not None:
            assert validate(inst, got.schedule).valid and _keeps_structure(inst, got.schedule), inst.name
            assert got.metrics.makespan >= best.lower_bound, inst.name
            carried = solve(inst, method, single_carry=True, max_makespan=got.metrics.makespan, time_limit=60)
            assert carried.schedule is None or carried.metrics.makespan >= got.metrics.makespan, inst.name
    assert kept >= 3


@pytest.mark.slow
@pytest.mark.parametrize("first", [1, 4, 12])
def test_a_first_horizon_above_or_below_finds_the_same_optimum(first, optimum):
    for name in ("point-move-tile", "handover"):
        inst = TINY[name]()
        result = solve(inst, "cpsat", first_horizon=first)
        assert result.status == "optimal" and validate(inst, result.schedule).valid
        assert result.metrics.makespan == result.lower_bound == optimum(name)


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_travel_is_minimized_at_the_optimal_makespan(method):
    inst = TINY["s7-two-robots"]()
    plain = solve(inst, method, minimize_travel=False)
    best = solve(inst, method)
    assert best.metrics.makespan == plain.metrics.makespan
    assert best.metrics.tiles_traveled <= plain.metrics.tiles_traveled
    assert best.stats["tiles_traveled_optimal"]
    other = "sat" if method == "cpsat" else "cpsat"
    assert solve(inst, other).metrics.tiles_traveled == best.metrics.tiles_traveled


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_an_obstacle_wall_is_infeasible(method):
    # the tiles must move to the other side of a wall no robot can reach around
    inst = make("TT#..\nTT#..", [{"at": [0, 0]}], goal="..#TT\n..#TT", moveset="point")
    assert lower_bound(inst).impossible
    result = solve(inst, method, time_limit=60)
    assert result.status == "infeasible" and result.schedule is None


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_no_schedule_within_the_horizon_cap_is_no_proof(method, monkeypatch):
    # an S5 robot on three tiles cannot turn around (breadth-first search proves it); the
    # encodings prove every horizon up to the cap infeasible, which bounds the makespan from
    # below but does not prove that no longer schedule exists
    from bille.solvers import incumbent

    inst = make("TTT\n...", [{"front": [1, 0], "back": [0, 0]}], moveset="S5", robot_goals=[[0, 0]])
    assert solve(inst, "bfs").status == "infeasible"
    assert solve(inst, method, max_makespan=8, time_limit=120).status == "infeasible"  # the complete planner's proof
    monkeypatch.setattr(incumbent, "complete_search", lambda *args: (None, False))  # as if it ran out of time
    for threads in ({}, {"threads": 2}) if method == "cpsat" else ({},):
        result = solve(inst, method, max_makespan=8, time_limit=120, **threads)
        assert result.status == "unsolved" and "horizon cap 8" in result.failure.text
        assert result.lower_bound == 9 and result.schedule is None


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_a_timeout_returns_the_bound_not_a_crash(method):
    inst = load_instance(bundled_path("bridge-2"))
    quick = lower_bound(inst, budget=Budget(0))  # 10 without the programs (16 with them)
    for threads in ({}, {"threads": 2}) if method == "cpsat" else ({},):
        result = solve(inst, method, time_limit=1.0, **threads)
        assert result.status in ("timeout", "feasible", "optimal")
        parts = result.stats["bound_parts"]  # the programs' parts left out, or cut short, past the second
        assert result.lower_bound >= max(quick.lower, *(v for v in parts.values() if v is not None))
        if result.status == "timeout":
            assert result.schedule is None
        else:
            assert validate(inst, result.schedule).valid and result.lower_bound <= result.metrics.makespan


@pytest.mark.parametrize("method", ["cpsat", "sat"])
@pytest.mark.parametrize("name", ["compare-5", "bridge-2"])
def test_a_timeout_returns_the_incumbent(method, name, monkeypatch):
    from bille.encodings.backend import Backend, Outcome
    from bille.encodings.cnf import SatBackend

    # the solver runs out of time at its first call, whatever the machine's speed
    monkeypatch.setattr(Backend, "solve", lambda self, *a, **k: Outcome("unknown"))
    monkeypatch.setattr(SatBackend, "solve", lambda self, *a, **k: Outcome("unknown"))
    inst = load_instance(bundled_path(name))
    result = solve(inst, method, time_limit=600)
    assert result.status == "feasible"
    assert validate(inst, result.schedule).valid
    # a heuristic's schedule, whichever of the portfolio ends first in the time share (its name
    # says what ran: "mstar", "lacam+transfer", "temporal-astar+derived", ...)
    assert result.stats["incumbent"]["method"].split("+")[0] in ("lacam", "temporal-astar", "mstar")
    assert result.metrics.makespan == result.stats["incumbent"]["makespan"]
    assert lower_bound(inst).lower <= result.lower_bound <= result.metrics.makespan


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_an_optimal_incumbent_is_proved_and_a_bad_one_refused(method, optimum):
    inst = TINY["s7-two-robots"]()
    best = solve(inst, "bfs", time_limit=300)
    result = solve(inst, method, incumbent=best.schedule)
    assert result.status == "optimal" and result.stats["incumbent"]["method"] == "given"
    assert result.metrics.makespan == result.lower_bound == optimum("s7-two-robots")
    assert validate(inst, result.schedule).valid
    bad = Schedule.from_ids(inst, bind(inst, best.schedule)[:, :1])
    with pytest.raises(OptionError, match="incumbent schedule is not valid"):
        solve(inst, method, incumbent=bad)


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_bad_options_are_rejected(method):
    inst = TINY["point-walk"]()
    with pytest.raises(OptionError, match="below the makespan lower bound"):
        solve(inst, method, max_makespan=1)
    with pytest.raises(OptionError, match="time_limit"):
        solve(inst, method, time_limit=0)
    with pytest.raises(OptionError, match="connectivity"):
        solve(inst, method, connectivity="magic")


@pytest.mark.slow
def test_pruning_cuts_the_model_and_keeps_the_answer():
    from bille.encodings.model import Options, build

    inst = load_instance(bundled_path("corridor-2"))
    full = build(inst, 13, Options(prune_reach=False, prune_cells=False)).size()
    pruned = build(inst, 13, Options()).size()
    assert pruned["variables"] < full["variables"] and pruned["clauses"] < full["clauses"]
    a = solve(inst, "sat", prune=False, minimize_travel=False)
    b = solve(inst, "sat", minimize_travel=False)
    assert a.metrics.makespan == b.metrics.makespan == 13


def test_the_model_is_the_sum_of_its_families():
    from bille.encodings.model import Options, build

    inst = load_instance(bundled_path("bridge-3"))
    end = inst.start_state  # a window back to where it started
    for model in (build(inst, 9, Options(), min_done=8), build(inst, 6, Options(connectivity="lazy"), end=end)):
        size = model.size()
        for key, total in size.items():  # besides the constant true: one variable, one clause
            assert sum(part[key] for part in model.families.values()) == total - (key in ("variables", "clauses"))
    assert "makespan (done)" in build(inst, 9, Options(), min_done=8).families
    assert list(model.families) == ["tiles, loads and poses", "actions", "window ends", "picks, places and loads",
                                    "collisions"]


# ---- random tiny instances: bounds and the exact solver against breadth-first search ----------

from hypothesis import HealthCheck, assume, given, settings, strategies as st  # noqa: E402

from test_properties import build as random_instance, scenes  # noqa: E402


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(scene=scenes(), length=st.integers(1, 6), goals=st.lists(st.booleans(), min_size=3, max_size=3))
def test_bounds_and_cpsat_agree_with_breadth_first_search_on_random_instances(scene, length, goals):
    inst, *_ = random_instance(scene, length, goals)
    assume(inst.num_robots <= 2)
    reference = solve(inst, "bfs", max_states=20_000)
    assume(reference.status == "optimal")
    optimum = reference.metrics.makespan
    assert lower_bound(inst).lower <= optimum
    result = solve(inst, "cpsat", time_limit=60, minimize_travel=False)
    assert result.status == "optimal" and validate(inst, result.schedule).valid
    assert result.metrics.makespan == optimum


def test_the_dimacs_dump_is_compact_and_names_variables_first(tmp_path):
    from pysat.formula import CNF
    from pysat.solvers import Solver

    from bille.encodings.model import Options, build

    inst = load_instance(bundled_path("corridor-2"))
    model = build(inst, 13, Options())
    path = tmp_path / "corridor-2.cnf"
    model.dump(path)
    lines = path.read_text().splitlines()
    header = next(k for k, line in enumerate(lines) if line.startswith("p cnf"))
    assert all(line.startswith("c ") for line in lines[:header]) and header >= model.num_vars
    assert not any(line.startswith("c ") for line in lines[header + 1:])
    assert path.stat().st_size < 20_000_000
    cnf = CNF(from_file=str(path))
    with Solver(name="cadical195", bootstrap_with=cnf.clauses) as solver:
        assert solver.solve()  # corridor-2's optimum is 13: satisfiable at 13
    smaller = tmp_path / "corridor-2-12.cnf"
    build(inst, 12, Options()).dump(smaller)
    with Solver(name="cadical195", bootstrap_with=CNF(from_file=str(smaller)).clauses) as solver:
        assert not solver.solve()  # and not at 12 (eager connectivity: no cut is missing)


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_an_incumbent_above_the_horizon_cap_is_still_returned(method, optimum, monkeypatch):
    from bille.solvers.bounds import scaffold, static as bounds

    # without the scaffold scenarios, whose bound is the optimum, 9
    monkeypatch.setattr(bounds, "scaffold_search", lambda *a, **k: scaffold.Scenarios([]))
    inst = TINY["s5-move-tile"]()  # optimum 9, static bound 7 without the scaffold scenarios
    best = solve(inst, "bfs", time_limit=300)
    opt = optimum("s5-move-tile")
    assert lower_bound(inst).lower <= opt - 1
    ids = bind(inst, best.schedule)
    wait = [list(ms.names).index("wait") for ms in inst.movesets]
    import numpy as np

    padded = Schedule.from_ids(inst, np.concatenate([np.array([wait] * 3).T, ids], axis=1))  # 3 steps late
    result = solve(inst, method, incumbent=padded, max_makespan=opt - 1)
    assert result.status == "feasible" and result.lower_bound == opt  # every horizon up to the cap refuted
    assert result.metrics.makespan == opt + 3 and validate(inst, result.schedule).valid


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_the_default_cap_gives_way_to_a_longer_incumbent(method, optimum, monkeypatch):
    # the default cap bounds a search with no schedule to go by; with one, the search goes on up
    # to it (a cap given stays, as the test above shows)
    from bille.solvers.exact import method as exact

    from bille.solvers.bounds import scaffold, static as bounds

    # without the scaffold scenarios, whose bound is the optimum, 9
    monkeypatch.setattr(bounds, "scaffold_search", lambda *a, **k: scaffold.Scenarios([]))
    inst = TINY["s5-move-tile"]()  # optimum 9, static bound 7 without the scaffold scenarios
    lower = lower_bound(inst).lower
    monkeypatch.setattr(exact, "default_cap", lambda bound: bound)  # as if the optimum lay beyond it
    result = solve(inst, method, time_limit=120)
    assert result.stats["incumbent"]["makespan"] > lower  # the heuristics' schedule, above that cap
    assert result.status == "optimal" and result.metrics.makespan == result.lower_bound == optimum("s5-move-tile")
    assert validate(inst, result.schedule).valid


@pytest.mark.parametrize("solver", ["glucose42", "minisat22", "cadical195"])
def test_a_sat_solve_past_its_deadline_answers_unknown_without_solving(solver):
    from bille.encodings.backend import open_backend
    from bille.encodings.model import Options, build

    inst = load_instance(bundled_path("corridor-2"))
    with open_backend(solver, build(inst, 13, Options()), inst) as backend:
        assert backend.solve([], Budget(0)).status == "unknown"
        assert backend.stats["conflicts"] == 0
        assert backend.solve([], Budget(600)).status == "sat"  # a timer that never fires
        assert backend.solve([], None).status == "sat"  # and left no interrupt behind


def test_no_solver_thread_under_a_tight_address_space_limit():
    # under an address-space limit with little room, starting a thread can hang in
    # Thread.start: the solve then runs on conflict budgets alone, in this thread, and still
    # ends at its deadline
    import subprocess
    import sys

    code = """
import resource, threading
from bille.encodings.backend import open_backend
from bille.encodings.cnf import THREAD_ROOM
from bille.encodings.model import Options, build
from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.run import Budget
from bille.instances.limits import address_room, mapped
from bille.instances.run import Budget
assert address_room() == float("inf")
inst = load_instance(bundled_path("corridor-2"))
backend = open_backend("glucose42", build(inst, 12, Options()), inst)
started, start = [], threading.Thread.start
threading.Thread.start = lambda self: started.append(self) or start(self)
assert backend.solve([], Budget(60)).status == "unsat"  # corridor-2's optimum is 13
assert started  # with room, the solve runs in a thread of its own
started.clear()
size = mapped() + THREAD_ROOM // 4
resource.setrlimit(resource.RLIMIT_AS, (size, size))
assert 0 < address_room() < THREAD_ROOM
assert backend.solve([], Budget(60)).status == "unsat"
assert not started
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.strip() == "ok", out.stderr


@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_with_no_heuristic_schedule_the_incumbent_comes_from_the_complete_planner(monkeypatch, method):
    from bille.solvers import incumbent
    from test_lacam import TINY_RECONFIGURATION, brute_force

    monkeypatch.setattr(incumbent, "first_schedule", lambda *args, **kw: None)
    inst = next(i for i in TINY_RECONFIGURATION if brute_force(i.name).status == "optimal"
                and brute_force(i.name).metrics.makespan >= 4)
    result = solve(inst, method, time_limit=60)
    assert result.stats["incumbent"]["method"] in ("lacam", "lacam-states"), result.stats
    assert result.stats["incumbent"]["makespan"] >= result.metrics.makespan == brute_force(inst.name).metrics.makespan
    assert result.status == "optimal" and validate(inst, result.schedule).valid


@pytest.mark.slow
@pytest.mark.parametrize("method", ["cpsat", "sat"])
def test_an_instance_the_complete_planner_exhausts_is_infeasible_for_the_exact_solvers(method):
    # no static proof on these, and no schedule up to any horizon cap: the search over whole
    # states runs out of states, as the brute force does
    from test_lacam import TINY_RECONFIGURATION, brute_force

    hard = [i for i in TINY_RECONFIGURATION if not lower_bound(i).impossible
            and brute_force(i.name).status == "infeasible"][:3]
    assert len(hard) == 3
    for inst in hard:
        result = solve(inst, method, time_limit=60)
        assert result.status == "infeasible" and result.schedule is None and result.lower_bound is None
        assert result.stats["reason"] == "the complete planner exhausted the reachable states"


def _stop_after_a_horizon(event):
    if "horizon" in event:  # the first horizon decided (the static bound is told before the search)
        raise KeyboardInterrupt


@pytest.mark.parametrize("method", ["cpsat", "cpsat-lanes", "sat"])
def test_interrupted_keeps_the_incumbent_and_the_bound_proved(method):
    """Ctrl-C, here raised by the progress callback once the first horizon is decided: the
    search ends ``interrupted`` with the heuristics' schedule and the bound that horizon proved."""
    inst = load_instance(bundled_path("corridor-2"))
    threads = {"threads": 2} if method == "cpsat-lanes" else {}
    result = solve(inst, method.split("-")[0], time_limit=120, progress=_stop_after_a_horizon, **threads)
    assert result.status == "interrupted"
    assert validate(inst, result.schedule).valid
    assert result.metrics.makespan == result.stats["incumbent"]["makespan"]
    # the bound is the first horizon not refuted: with two lanes the higher one may be decided
    # first, and the lower one is then stopped undecided
    answers = {h["T"]: h["answer"] for h in result.stats["horizons"]}
    proved = result.stats["horizons"][0]["T"]
    while answers.get(proved) == "unsat":
        proved += 1
    assert result.lower_bound == proved <= result.metrics.makespan
    assert method == "cpsat-lanes" or answers[proved - 1] == "unsat"
