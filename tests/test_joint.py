"""The compiled joint search against the Python rules and the Python search.

Its successors must be exactly those of :func:`bille.instances.rules.apply` (every joint action,
the state it leads to) on random reachable states; its optima exactly the Python search's, within
the class ``all``; a class optimum at least the unconditional one and reached by a schedule of
the class; the bound below an incumbent never above the optimum; every schedule valid.
"""
from __future__ import annotations

import functools
from itertools import product
from random import Random

import pytest

from bille.instances import OptionError
from bille.instances.rules import State, apply
from bille.instances.run import Budget, Events, Run
from bille.instances.successors import candidate_actions, disjoint_products
from bille.solvers import solve, validate
from bille.solvers.bfs import Options, plan
from bille.solvers.bounds.classes import classes_of
from bille.solvers.joint.cells import cells_of
from bille.solvers.joint.store import successors
from bille.solvers.joint.tables import compile_tables
from helpers import make
from tinyworlds import tiny_instances

REFERENCE_STATES = 5_000  # the Python search gives up beyond this; such instances are not compared


def python_successors(inst, state) -> dict:
    """Joint action -> new state, by the Python rules."""
    options = [candidate_actions(inst, state, i) for i in range(inst.num_robots)]
    joints = product(*options) if inst.world.classic else disjoint_products(inst, state, options)
    out = {}
    for joint in joints:
        new = apply(inst.world, state, joint)
        if isinstance(new, State):
            out[tuple(int(a) for a in joint)] = new
    return out


CLASSIC = [
    make("TTTT\nTTTT\nTTT.", [{"at": [0, 0]}, {"at": [1, 0]}, {"at": [2, 1]}], moveset="point", collisions="classic",
         goal="TTTT\nTTTT\nTT.T", robot_goals=[[3, 0], None, [0, 2]]),
    make("TTT.\nTT..\nTTT.", [{"at": [0, 0], "carrying": True}, {"at": [1, 1]}], moveset="point",
         collisions="classic", goal="TTT.\nTTT.\nTTT."),
]


@pytest.mark.parametrize("inst", tiny_instances(40) + CLASSIC, ids=lambda i: i.name)
def test_compiled_successors_are_the_rules_successors(inst):
    rnd = Random(inst.name)
    t = compile_tables(inst, cells_of(inst, "all"))
    n = inst.width * inst.height
    state = inst.start_state
    for _ in range(12):  # a random walk through reachable states
        expected = python_successors(inst, state)
        actions, rows = successors(t, n, t.pack(state, canonical=False))
        got = {tuple(int(a) for a in acts): tuple(int(w) for w in row) for acts, row in zip(actions, rows)}
        assert set(got) == set(expected), inst.name
        for joint, new in expected.items():
            assert got[joint] == tuple(int(w) for w in t.pack(new, canonical=False)), (inst.name, joint)
        if not expected:
            break
        state = expected[rnd.choice(sorted(expected))]


@functools.cache
def reference(inst):
    return solve(inst, "bfs", time_limit=None, engine="python", max_states=REFERENCE_STATES)


def bfs(inst, **options):
    """The compiled search through solve(): its schedule validated, its metrics measured."""
    return solve(inst, "bfs", time_limit=None, engine="compiled", **options)


def compare_with_reference(instances, direction: str = "forward") -> int:
    decided = 0
    for inst in instances:
        ref, got = reference(inst), bfs(inst, direction=direction)
        if ref.status == "optimal":
            decided += 1
            assert got.status == "optimal", inst.name
            assert got.metrics.makespan == ref.metrics.makespan == got.lower_bound, inst.name
            assert validate(inst, got.schedule).valid
        elif ref.status == "infeasible":
            decided += 1
            assert got.status == "infeasible", inst.name
        if got.status == "optimal":  # also where the reference gave up: above what it proved
            assert got.metrics.makespan >= (ref.lower_bound or 0), inst.name
    return decided


@pytest.mark.parametrize("direction", ["forward", "both"])
def test_optima_equal_the_python_search(direction):
    assert compare_with_reference(tiny_instances(40), direction) >= 30


@pytest.mark.slow
@pytest.mark.parametrize("direction", ["forward", "both"])
def test_optima_equal_the_python_search_on_many(direction):
    assert compare_with_reference(tiny_instances(240, first_seed=1000), direction) >= 150


def test_both_ends_agree_on_classes_and_classic_instances():
    for inst in tiny_instances(30, first_seed=500) + CLASSIC:
        for cells in ("keep", "no-scaffold", "all"):
            one, two = bfs(inst, cells=cells), bfs(inst, cells=cells, direction="both")
            assert one.status == two.status, (inst.name, cells)
            if one.status == "optimal":
                assert one.metrics.makespan == two.metrics.makespan, (inst.name, cells)
                assert validate(inst, two.schedule).valid


def test_both_ends_stop_with_the_bound_of_the_layers_done():
    inst = make("TTTTTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[7, 0]])
    got = bfs(inst, direction="both", max_steps=3)
    assert got.status == "unsolved" and got.lower_bound == 4 and got.failure.text == "step bound"
    got = bfs(inst, direction="both")
    assert got.status == "optimal" and got.metrics.makespan == 7


def check_classes(instances) -> int:
    """Each class's optimum: at least the unconditional one, reached by a schedule of the class,
    nested (keep >= no-scaffold >= all), never given as the instance's lower bound."""
    checked = 0
    for inst in instances:
        whole = bfs(inst)
        if whole.status != "optimal":
            continue
        last = whole.metrics.makespan
        for kind, key in (("no-scaffold", "no-scaffold"), ("keep", "keep-structure")):
            got = bfs(inst, cells=kind)
            assert got.lower_bound is None and got.stats["class"]["cells"] == kind
            if got.status == "optimal":
                assert validate(inst, got.schedule).valid
                assert key in classes_of(inst, got.schedule), (inst.name, kind)
                assert got.metrics.makespan >= last, (inst.name, kind)
                assert not got.claim.unconditional and got.claim.lower == got.metrics.makespan
                last = got.metrics.makespan
                checked += 1
            else:
                assert got.status == "unsolved" and "exists" in got.failure.text, inst.name
                last = float("inf")
    return checked


def test_class_optima_are_nested_and_their_schedules_in_class():
    assert check_classes(tiny_instances(30)) >= 20


@pytest.mark.slow
def test_class_optima_against_the_exact_model():
    """The keep class's optimum equals the CP-SAT model's under keep_structure, which searches
    the same set of schedules by a different method."""
    compared = 0
    for inst in tiny_instances(60, first_seed=300):
        got = bfs(inst, cells="keep")
        exact = solve(inst, "cpsat", keep_structure=True, time_limit=20)
        if exact.status == "optimal" and got.status == "optimal":
            assert exact.metrics.makespan == got.metrics.makespan, inst.name
            compared += 1
        elif got.status == "unsolved" and exact.status == "optimal":
            pytest.fail(f"{inst.name}: the model finds a schedule that keeps the structure, the search none")
    assert compared >= 25


def test_below_an_incumbent_the_optimum_is_found_or_the_incumbent_proved():
    checked = pruned = 0
    for inst in tiny_instances(40):
        whole = bfs(inst)
        keep = bfs(inst, cells="keep")
        if whole.status != "optimal" or keep.status != "optimal":
            continue
        got = bfs(inst, incumbent=keep.schedule)
        assert got.status == "optimal" and got.metrics.makespan == whole.metrics.makespan, inst.name
        assert got.lower_bound == whole.metrics.makespan and validate(inst, got.schedule).valid
        pruned += got.stats["pruned"]
        proved = bfs(inst, incumbent=whole.schedule)  # nothing shorter: the incumbent proved
        assert proved.status == "optimal" and proved.metrics.makespan == whole.metrics.makespan
        kept = bfs(inst, cells="keep", incumbent=keep.schedule)  # the tile bound on a class's own cells
        assert kept.status == "optimal" and kept.metrics.makespan == keep.metrics.makespan
        checked += 1
    assert checked >= 15 and pruned > 0


def test_stopped_search_keeps_a_proved_bound_of_its_class():
    inst = make("TTTTTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[7, 0]])
    got = bfs(inst, max_steps=3)
    assert got.status == "unsolved" and got.lower_bound == 4 and got.failure.text == "step bound"
    got = bfs(inst, max_steps=3, cells="keep")
    assert got.lower_bound is None and got.stats["class"]["lower_bound"] == 4
    assert "among the schedules that keep the structure" in got.stats["stopped"]
    capped = bfs(inst, max_states=3)
    assert capped.status == "unsolved" and capped.failure.text.startswith("state cap")
    assert capped.lower_bound == capped.stats["depth"] + 1


@pytest.mark.parametrize("direction", ["forward", "both"])
def test_cancel_keeps_the_bound(direction):
    inst = make("\n".join(["T" * 6] * 4), [{"at": [0, 0]}, {"at": [5, 3]}, {"at": [0, 3]}], moveset="point",
                robot_goals=[[5, 3], [0, 0], [5, 0]])
    budget = Budget()
    looks = iter(range(10**9))

    def progress(info):
        if next(looks) == 2:
            budget.cancel()
    got = plan(inst, Options(direction=direction, engine="compiled"), run=Run(budget, Events(on_progress=progress)))
    assert got.status == "interrupted" and got.failure.text == "interrupted"
    assert got.lower_bound == got.stats["depth"] + 1 <= bfs(inst).metrics.makespan


def test_interchangeable_robots_give_a_valid_schedule():
    # three robots without goal cells on one moveset: stored in sorted order, replayed as themselves
    inst = make("TTTT\nTTT.", [{"at": [0, 0]}, {"at": [3, 0]}, {"at": [1, 1], "carrying": True}], moveset="point",
                goal="TTTT\nTTTT")
    ref, got = reference(inst), bfs(inst)
    assert ref.status == got.status
    if got.status == "optimal":
        assert got.metrics.makespan == ref.metrics.makespan and validate(inst, got.schedule).valid


def test_bad_cells_are_named():
    inst = make("TT\n..", [{"at": [0, 0]}], moveset="point")
    with pytest.raises(OptionError, match=r"\(5, 0\) is outside the 2x2 grid"):
        bfs(inst, add_cells=[[5, 0]])
    with pytest.raises(OptionError, match="list of \\[x, y\\] pairs"):
        Options.parse({"add_cells": [1, 2]})
    with pytest.raises(OptionError, match="engine python"):
        Options(engine="python", cells="keep")


def test_many_robots_without_goals_and_a_small_state_cap_stop_cleanly():
    # the goal states' count overflowed a float (160 robots), and more goal states than the state
    # cap did not fit the stores: both went forward only, or stopped at the cap
    robots = [{"at": [x, y]} for y in range(0, 20) for x in range(0, 20, 2)][:160]
    inst = make("\n".join(["T" * 19 + "."] + ["T" * 20] * 19), robots, moveset="point",
                goal="\n".join(["T" * 20] * 19 + ["." + "T" * 19]))
    got = plan(inst, Options(engine="compiled", max_states=50), run=Run(Budget(5)))
    assert got.status == "unsolved" and got.failure.text.startswith("state cap")


def test_a_moveset_whose_pick_carries_cells_goes_forward_only(tmp_path):
    # steps backwards would count a pick's carried cells with the load after it: not reversible
    from pathlib import Path

    from bille.solvers.joint.tables import reversible
    shipped = (Path(__file__).parent.parent / "instances" / "movesets" / "point.yaml").read_text()
    odd = tmp_path / "odd.yaml"
    odd.write_text(shipped.replace("name: point", "name: odd").replace(
        "pick-north:  {at: [0, 0], pick: [0, -1]}", "pick-north:  {at: [0, 0], pick: [0, -1], carried: [[1, 0]]}"))
    inst = make("TTT.\nTTT.", [{"at": [0, 1]}], moveset=str(odd), goal="TTTT\nTT..")
    assert not reversible(compile_tables(inst, cells_of(inst, "all")))
    ref, got = reference(inst), bfs(inst, direction="both")
    assert ref.status == got.status and (got.metrics is None or got.metrics.makespan == ref.metrics.makespan)


def test_deepening_finds_the_optimum_of_each_class():
    """Searched below a rising bound from nothing proved, each class's optimum is the plain
    search's (module solvers.joint.search, "Deepening"): every bound it proves on the way is at
    most that optimum, and a class without schedules is exhausted."""
    from bille.solvers.joint.search import deepen

    checked = 0
    for inst in tiny_instances(40):
        for kind in ("all", "keep"):
            plain = bfs(inst, cells=kind)
            cells = cells_of(inst, kind)
            bounds = []
            events = Events(on_progress=lambda p: bounds.append(p["lower"]) if "deepening" in p else None)
            got = deepen(inst, cells, Budget(), proved=0, max_states=1_000_000, events=events,
                         tables=compile_tables(inst, cells, distances=True))
            if plain.status == "optimal":
                assert got.stop == "goal" and got.proved == plain.metrics.makespan, (inst.name, kind)
                assert all(b <= plain.metrics.makespan for b in bounds)
                ids = got.ids
                assert ids.shape[1] == plain.metrics.makespan
                checked += 1
            elif plain.status in ("infeasible", "unsolved"):
                assert got.stop == "exhausted", (inst.name, kind)
    assert checked >= 30


def test_a_search_that_does_not_decide_in_its_share_deepens(monkeypatch):
    """Asked to deepen, without the abstraction (which deepens from its own bound), the plain
    search gets a share of the time limit (none here: it stops at once), then the search
    deepens: the same optimum, a valid schedule."""
    from bille.solvers import bfs as bfs_module

    monkeypatch.setattr(bfs_module, "PLAIN_SHARE", 0.0)
    monkeypatch.setattr(bfs_module, "PLAIN_MIN", 0.0)
    deepened = 0
    for inst in tiny_instances(12):
        plain = bfs(inst, cells="keep")
        if plain.status != "optimal" or plain.metrics.makespan < 2:
            continue
        events = []
        got = plan(inst, Options(engine="compiled", cells="keep", deepen=True, abstraction=False),
                   run=Run(Budget(60.0), Events(on_progress=events.append)))
        report = validate(inst, got.schedule)
        assert got.status == "optimal" and report.valid, inst.name
        assert report.metrics.makespan == plain.metrics.makespan == got.claim.lower, inst.name
        deepened += any("deepening" in e for e in events)
    assert deepened >= 1
