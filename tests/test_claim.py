"""A result's claim: what it proves, rendered one way for each output."""
from __future__ import annotations

import numpy as np
import pytest

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.claim import EVERY, Claim, base_status, shown_status, status_key
from bille.instances.result import Result
from bille.solvers import solve, validate

WALKING_SOC = Claim("sum-of-costs", then="makespan", walking_only=True)
KEEP = Claim(among="the schedules that keep the structure", spelled="cells=keep", bounds="keep-structure", lower=57)


@pytest.mark.parametrize("claim, key, shown", [
    (EVERY, "optimal", "optimal"),
    (WALKING_SOC, "optimal-sum-of-costs-walking-only", "optimal (sum of costs over walking-only schedules)"),
    (Claim(walking_only=True), "optimal-walking-only", "optimal (makespan over walking-only schedules)"),
    (Claim("sum-of-costs"), "optimal-sum-of-costs", "optimal (sum of costs)"),
    (KEEP, "optimal-in-class", "optimal (makespan among the schedules that keep the structure)"),
])
def test_one_rendering_per_output(claim, key, shown):
    assert status_key("optimal", claim) == key and base_status(key) == "optimal"
    assert shown_status("optimal", claim) == shown
    assert status_key("feasible", claim) == shown_status("feasible", claim) == "feasible"
    assert Claim.from_json(claim.to_json()) == claim
    assert claim.unconditional == (key == "optimal")


def test_the_text_names_the_tie_break_and_the_class():
    assert WALKING_SOC.text() == "sum of costs, then makespan, walking only (no pick or place)"
    assert KEEP.text() == "makespan among the schedules that keep the structure (cells=keep)"
    assert Result("bfs", "optimal", claim=KEEP).to_json()["claim"]["lower"] == 57
    with pytest.raises(ValueError, match="unknown objective"):
        Claim("flowtime")


def test_restricted_optima_are_never_bare_optimal():
    """Each method's optimum carries its claim; only the makespan over every schedule is bare."""
    inst = load_instance(bundled_path("point-4"))
    seen = {}
    for method, options in (("bfs", {}), ("mstar", {}), ("astar", {}), ("bfs", {"cells": "keep"})):
        result = solve(inst, method, time_limit=30, **options)
        assert result.status == "optimal" and validate(inst, result.schedule).valid
        seen[method + str(options)] = (status_key(result.status, result.claim), result.metrics.makespan)
    assert seen["bfs{}"] == ("optimal", 10)  # the brute force's optimum over every schedule
    assert seen["mstar{}"][0] == seen["astar{}"][0] == "optimal-sum-of-costs-walking-only"
    assert seen["mstar{}"][1] > 10
    assert seen["bfs{'cells': 'keep'}"][0] == "optimal-in-class"


def test_a_failure_says_its_kind_for_code_and_its_text_for_people():
    from helpers import make

    from bille.instances.failure import Failure
    from bille.instances.run import Budget

    with pytest.raises(ValueError, match="unknown failure kind"):
        Failure("oops", "text")
    inst = make("TTTTTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[7, 0]])
    capped = solve(inst, "bfs", engine="compiled", max_steps=3)
    assert capped.status == "unsolved" and capped.failure == Failure("cap", "step bound")
    assert capped.to_json()["failure"] == {"kind": "cap", "text": "step bound"}
    late = solve(load_instance(bundled_path("lt-1")), "bfs", budget=Budget(0.0))
    assert late.status == "timeout" and late.failure.kind == "time-limit"
    keep = solve(inst, "bfs", engine="compiled", cells="keep", max_steps=3)
    assert keep.failure.kind == "cap" and keep.claim.lower == 4


def test_the_counts_tools_read_are_typed():
    import re
    from pathlib import Path

    from bille.instances.counters import KEYS, Counters
    from bille.instances.result import Result

    with pytest.raises(TypeError, match="nodes"):
        Result("x", "feasible", stats={"nodes": "3"}).counters
    with pytest.raises(TypeError, match="steps"):
        Counters.of({"steps": True})
    counted = Counters.of({"states": np.int64(7), "first_s": np.float64(0.25)})  # NumPy's numbers are numbers
    assert counted.states == 7 and type(counted.states) is int and counted.first_s == 0.25
    counts = solve("compare-4", "lacam").counters  # LaCAM* counts its nodes
    assert isinstance(counts.nodes, int) and counts.nodes > 0 and counts.relays is None
    loop = solve("lt-4", "temporal-astar", load_transfer=True).counters
    assert loop.steps > 0 and loop.jobs > 0 and loop.plan_ms_max >= loop.plan_ms_mean >= 0
    # the tools read them through Counters, never by their keys
    read = re.compile(r"stats(\.get\(|\[)\s*[\"'](" + "|".join(KEYS) + r")[\"']")
    tools = Path(__file__).parent.parent / "tools"
    offenders = [f"{p.name}:{n}" for p in tools.rglob("*.py") for n, line in enumerate(p.read_text().splitlines(), 1)
                 if read.search(line)]
    assert not offenders, offenders
