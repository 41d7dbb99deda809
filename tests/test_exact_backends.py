"""The back-end interface (bille.encodings.backend): CP-SAT and the python-sat solvers answer the
same model alike, under assumptions, with an objective, and with connectivity left to cuts."""
import pytest

from bille.encodings.backend import Objective, open_backend
from bille.encodings.model import Options, build
from bille.encodings.solution import decode, tiles_at
from bille.instances.grid import is_connected
from bille.instances.schedule import Schedule
from bille.solvers import solve, validate
from helpers import make
from tinyworlds import tiny_instance

SOLVERS = ["cpsat", "glucose42", "minisat22", "cadical195"]
# a tile to move round a corner: 9 steps, none fewer (brute force)
MOVE = dict(grid=".....\nTTTT.\nTTTT.\n.....", robots=[{"front": [1, 2], "back": [0, 2]}],
            goal=".....\n.TTTT\nTTTT.\n.....", moveset="S5")


@pytest.fixture(scope="module")
def move():
    inst = make(MOVE["grid"], MOVE["robots"], goal=MOVE["goal"], moveset=MOVE["moveset"])
    assert solve(inst, "bfs").metrics.makespan == 9
    return inst


def _schedule(inst, model, outcome, steps):
    return Schedule.from_ids(inst, decode(model, inst, outcome.value)[:, :steps])


@pytest.mark.parametrize("solver", SOLVERS)
def test_every_back_end_decides_the_horizons_around_the_optimum(move, solver):
    for T, answer in ((8, "unsat"), (9, "sat")):
        model = build(move, T, Options())
        with open_backend(solver, model, move) as backend:
            outcome = backend.solve()
        assert outcome.status == answer
        if answer == "sat":
            assert validate(move, _schedule(move, model, outcome, T)).valid


@pytest.mark.parametrize("solver", SOLVERS)
def test_assumptions_hold_for_one_call(move, solver):
    model = build(move, 11, Options(), min_done=8)
    with open_backend(solver, model, move) as backend:
        assert backend.solve([model.done[8]]).status == "unsat"
        outcome = backend.solve([model.done[9]])
        assert outcome.status == "sat" and validate(move, _schedule(move, model, outcome, 9)).valid
        assert backend.solve().status == "sat"  # neither assumption is left behind


@pytest.mark.parametrize("solver", SOLVERS)
def test_a_chain_objective_finds_the_shortest_schedule(move, solver):
    """``done[1..L]`` maximized with ``done[L]`` required: the shortest schedule, proved."""
    L = 12
    model = build(move, L, Options(), min_done=1)
    done = [model.done[k] for k in range(1, L + 1)]
    with open_backend(solver, model, move) as backend:
        outcome = backend.solve(objective=Objective(done, maximize=True, chain=True, at_most=L - 1))
    assert outcome.status == "sat"
    k = next(k for k in range(1, L + 1) if outcome.value(model.done[k]))
    assert k == 9 and validate(move, _schedule(move, model, outcome, k)).valid


@pytest.mark.parametrize("solver", SOLVERS)
def test_the_fewest_motions_agree_across_back_ends_and_a_bound_below_them_is_refuted(move, solver):
    model = build(move, 9, Options())
    with open_backend(solver, model, move) as backend:
        first = backend.solve()
        best = backend.solve(objective=Objective(model.motion), hint=first.values)
        assert best.status == "sat"
        fewest = Objective(model.motion).cost(best.value)
        assert fewest <= Objective(model.motion).cost(first.value)
        assert validate(move, _schedule(move, model, best, 9)).metrics.tiles_traveled == fewest
        below = backend.solve(objective=Objective(model.motion, at_most=fewest - 1))
        assert below.status == "unsat" and below.values is None
    if solver == "cpsat":
        return
    with open_backend("cpsat", model, move) as reference:
        assert Objective(model.motion).cost(reference.solve(objective=Objective(model.motion)).value) == fewest


@pytest.mark.parametrize("connectivity", ["lazy", "cuts"])
@pytest.mark.parametrize("solver", SOLVERS)
def test_a_solution_that_breaks_the_structure_is_cut_off_before_it_is_returned(solver, connectivity):
    # a random 4x2 instance, optimum 4 (brute force): at horizon 3 only schedules that break the
    # structure remain, so the back end must cut every one of them off and refute the horizon
    inst = tiny_instance(647, max_robots=2)
    assert solve(inst, "bfs").metrics.makespan == 4
    for T, answer in ((3, "unsat"), (4, "sat")):
        model = build(inst, T, Options(connectivity=connectivity))
        with open_backend(solver, model, inst, connectivity=connectivity) as backend:
            outcome = backend.solve()
        assert outcome.status == answer
        if answer == "unsat":
            assert outcome.cuts > 0
        else:
            masks = tiles_at(model, inst, outcome.value)
            assert all(is_connected(mask, inst.width, inst.height) for mask in masks)
            assert validate(inst, _schedule(inst, model, outcome, T)).valid


def test_an_unknown_solver_is_refused(move):
    with pytest.raises(ValueError, match="unknown solver"):
        open_backend("gurobi", build(move, 9, Options()), move)
