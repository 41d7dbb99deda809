"""The abstraction's distances (bille.solvers.joint.abstraction): a bound that never exceeds the
steps left, checked step by step on reachable states and against the optima of the search
without it, and the search it guides gives the same optima."""
from __future__ import annotations

from random import Random

import numpy as np
import pytest

from bille.instances.run import Budget
from bille.solvers import solve, validate
from bille.solvers.bounds.classes import classes_of
from bille.solvers.joint import abstraction
from bille.solvers.joint.cells import cells_of
from bille.solvers.joint.compiled import UNREACHED
from bille.solvers.joint.store import successors
from bille.solvers.joint.tables import compile_tables
from tinyworlds import bridge_instance, tiny_instances

KEYS = {"keep": "keep-structure", "no-scaffold": "no-scaffold"}


def bridges(count: int) -> list:
    out, seed = [], 0
    while len(out) < count:
        inst = bridge_instance(seed)
        seed += 1
        if inst is not None:
            out.append(inst)
    return out


def bfs(inst, **options):
    return solve(inst, "bfs", time_limit=None, engine="compiled", **options)


def guided_tables(inst, kind):
    cells = cells_of(inst, kind)
    t = compile_tables(inst, cells)
    return abstraction.attach(inst, cells, t, Budget(), 1 << 34)


def check_steps(inst, kind, rnd, walks=6, length=10) -> int:
    """Along random walks through the class's states: the bound falls by at most one a step
    (every successor's bound is at least the state's less one), and is 0 at a goal state."""
    t, built = guided_tables(inst, kind)
    if built is None:
        return 0
    n = inst.width * inst.height
    a = abstraction.Abstraction(t.pdb_local, t.pdb_order, t.pdb_blocks, t.pdb_binom, t.pdb_gmask, t.pdb_size,
                                t.pdb_dist)
    checked = 0
    for _ in range(walks):
        row = t.pack(inst.start_state, canonical=False)
        for _ in range(length):
            h = a.at(t, row)
            if t.is_goal(row):
                assert h == 0, inst.name
            _, rows = successors(t, n, row)
            if len(rows) == 0:
                break
            for new in rows:
                assert a.at(t, new) >= h - 1, (inst.name, kind)
                checked += 1
            row = rows[rnd.randrange(len(rows))]
    return checked


@pytest.mark.parametrize("kind", ["keep", "no-scaffold"])
def test_the_bound_falls_at_most_one_a_step(kind):
    rnd = Random(kind)
    checked = sum(check_steps(inst, kind, rnd) for inst in tiny_instances(16) + bridges(10))
    assert checked >= 2000


def compare(instances, kinds=("keep", "no-scaffold")) -> tuple[int, int]:
    """The guided search's optimum is the plain search's, its schedule valid and in the class,
    and the abstraction's bound at the start at most that optimum; returns the classes decided
    and those where the abstraction was built."""
    decided = built = 0
    for inst in instances:
        for kind in kinds:
            plain = bfs(inst, cells=kind, abstraction=False, direction="forward")
            got = bfs(inst, cells=kind)
            assert got.status == plain.status, (inst.name, kind)
            made = got.stats.get("abstraction")
            built += made is not None
            if plain.status != "optimal":
                continue
            decided += 1
            report = validate(inst, got.schedule)
            assert report.valid and KEYS[kind] in classes_of(inst, got.schedule), (inst.name, kind)
            assert report.metrics.makespan == plain.metrics.makespan == got.claim.lower, (inst.name, kind)
            assert got.lower_bound is None and not got.claim.unconditional
            if made is not None:
                assert made["start"] <= plain.metrics.makespan, (inst.name, kind)
            incumbent = bfs(inst, cells=kind, incumbent=plain.schedule)  # below it: nothing
            assert incumbent.status == "optimal" and incumbent.metrics.makespan == plain.metrics.makespan
    return decided, built


def test_guided_optima_equal_the_plain_search():
    decided, built = compare(tiny_instances(30) + bridges(20))
    assert decided >= 60 and built >= 60


@pytest.mark.slow
def test_guided_optima_equal_the_plain_search_on_many():
    decided, built = compare(tiny_instances(120, first_seed=500) + bridges(60)[20:])
    assert decided >= 200 and built >= 200


def test_a_class_without_schedules_is_one_still():
    """Where the class has no schedule, neither search finds one (the abstraction may see it
    at once: no abstract goal reached)."""
    seen = 0
    for inst in tiny_instances(60):
        plain = bfs(inst, cells="keep", abstraction=False, direction="forward")
        if plain.status == "unsolved":
            got = bfs(inst, cells="keep")
            assert got.status == "unsolved" and "exists" in got.failure.text, inst.name
            seen += 1
    assert seen >= 1


def test_every_cell_gets_no_abstraction():
    inst = tiny_instances(1)[0]
    t, built = guided_tables(inst, "all")
    assert built is None and t.pdb_dist.shape[0] == 0
    assert "abstraction" not in bfs(inst, cells="all").stats


def test_an_unreachable_index_is_the_largest_bound():
    inst = bridges(1)[0]
    t, built = guided_tables(inst, "keep")
    assert built is not None and t.pdb_dist.dtype == np.uint8
    assert (t.pdb_dist <= UNREACHED).all() and int(t.pdb_dist.min()) == 0


def brute_force_agrees(instances, states: int) -> int:
    """The guided search's class optima against the brute force over the tiles' configurations
    (tests/refsearch.py: the classes defined again, independently)."""
    from refsearch import class_optimum

    agreed = 0
    for inst in instances:
        for kind in ("keep", "no-scaffold"):
            try:
                best, _ = class_optimum(inst, KEYS[kind], max_states=states)
            except RuntimeError:  # too many states for the brute force
                continue
            got = bfs(inst, cells=kind)
            if best is None:
                assert got.status == "unsolved", (inst.name, kind)
            else:
                assert got.status == "optimal" and got.metrics.makespan == best, (inst.name, kind)
                assert validate(inst, got.schedule).valid
            agreed += 1
    return agreed


def test_guided_optima_equal_the_brute_force():
    assert brute_force_agrees(tiny_instances(16, first_seed=10_000, max_robots=2) + bridges(6), 5_000) >= 30


@pytest.mark.slow
def test_guided_optima_equal_the_brute_force_on_many():
    assert brute_force_agrees(tiny_instances(50, first_seed=20_000) + bridges(25), 6_000) >= 100


def test_the_build_stops_at_its_budget_and_the_search_goes_on_unguided(monkeypatch):
    """The build polls its budget between parts of a layer: a budget spent after a few looks
    stops it (no table), and bfs then searches the class without it, to the same optimum."""
    from itertools import count

    from bille.solvers.bfs import Options, plan

    inst = bridges(1)[0]
    cells = cells_of(inst, "keep")
    t = compile_tables(inst, cells)
    ticks = count()
    assert abstraction.build(inst, cells, t, Budget(2.5, clock=lambda: float(next(ticks)))) is None
    assert abstraction.build(inst, cells, t, Budget()) is not None
    plain = bfs(inst, cells="keep", abstraction=False)
    monkeypatch.setattr(abstraction, "build", lambda *args, **kw: None)  # as if its share ran out
    got = plan(inst, Options(engine="compiled", cells="keep"))
    assert "abstraction" not in got.stats
    assert got.status == plain.status == "optimal"
    assert validate(inst, got.schedule).metrics.makespan == plain.metrics.makespan
