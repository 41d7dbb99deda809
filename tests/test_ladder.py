"""The widening ladder of anytime solving (solvers/anytime/ladder.py): every rung's claim checked
against the same class searched without an incumbent (no pruning), on tiny instances."""
import pytest

from bille.instances.bundled import bundled_path
from bille.instances.grid import articulation_points
from bille.instances.instance import load_instance
from bille.instances.run import Budget
from bille.solvers import solve
from bille.solvers.anytime.ladder import RUNG, candidates, climb
from bille.solvers.incumbent import from_schedule

from tinyworlds import bridge_instance, tiny_instances

TINY = [inst for inst in map(bridge_instance, range(30)) if inst is not None][:8] + tiny_instances(6)


@pytest.mark.parametrize("inst", TINY, ids=lambda inst: inst.name)
def test_the_candidates_can_be_lifted_and_set_back(inst):
    start, goal = inst.start.tiles, inst.goal_tiles
    cut = articulation_points(start, inst.width, inst.height)
    cells = candidates(inst)
    assert len(set(cells)) == len(cells)
    for x, y in cells:
        c = y * inst.width + x
        assert start[c] and goal[c] and not cut[c]


def _in_line(inst, cut, x, y):
    """Whether (x, y) goes on straight from a run of two cut cells, over tiles."""
    tiles = inst.start.tiles | inst.goal_tiles
    w = inst.width
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        cx, cy = x - dx, y - dy
        while 0 <= cx < w and 0 <= cy < inst.height and tiles[cy * w + cx]:
            bx, by = cx - dx, cy - dy
            if cut[cy * w + cx] and 0 <= bx < w and 0 <= by < inst.height and cut[by * w + bx]:
                return True
            cx, cy = bx, by
    return False


@pytest.mark.parametrize("inst", TINY + [load_instance(bundled_path("lt-1"))], ids=lambda inst: inst.name)
def test_the_cells_in_line_with_a_passage_come_first(inst):
    cut = articulation_points(inst.start.tiles, inst.width, inst.height)
    flags = [_in_line(inst, cut, x, y) for x, y in candidates(inst)]
    assert flags == sorted(flags, reverse=True)  # every cell in line before every other


def test_lt1_rungs_go_along_the_bridge_row():
    assert candidates(load_instance(bundled_path("lt-1")))[:2 * RUNG] == [(3, 3), (12, 3), (2, 3), (13, 3)]


@pytest.mark.slow
@pytest.mark.parametrize("inst", TINY, ids=lambda inst: inst.name)
def test_every_rung_claims_its_class_optimum(inst):
    keep = solve(inst, "bfs", cells="keep", time_limit=60)
    if keep.status != "optimal":
        pytest.skip("no schedule keeps the structure")
    best = [from_schedule(inst, keep.schedule, "keep")]
    offered = []

    def offer(schedule):
        offered.append(schedule)
        best.append(from_schedule(inst, schedule, "ladder"))

    rows = climb(inst, lambda: best[-1], Budget(60), offer, 2_000_000, top=False)
    assert len(rows) == -(-len(candidates(inst)) // RUNG)  # every rung decided on these
    for row in rows:
        plain = solve(inst, "bfs", cells="keep", add_cells=row["add_cells"], time_limit=60)
        assert plain.status == "optimal"
        claimed = row.get("optimum", row.get("lower_bound"))
        assert claimed == plain.metrics.makespan, row  # the class's optimum, found below the incumbent
    for schedule in offered:  # a shorter schedule offered is valid, and shorter than keep's optimum
        checked = solve(inst, "bfs", cells="keep", time_limit=60)
        assert from_schedule(inst, schedule, "x").makespan < checked.metrics.makespan


@pytest.mark.parametrize("inst", TINY, ids=lambda inst: inst.name)
def test_the_top_claims_the_optimum_without_scaffold(inst):
    """The top of the ladder, searched first: the class without scaffold, its optimum the plain
    search's (no abstraction, no incumbent); decided, it ends the ladder."""
    keep = solve(inst, "bfs", cells="keep", time_limit=60)
    if keep.status != "optimal":
        pytest.skip("no schedule keeps the structure")
    best = [from_schedule(inst, keep.schedule, "keep")]
    rows = climb(inst, lambda: best[-1], Budget(60), lambda s: best.append(from_schedule(inst, s, "top")), 2_000_000)
    assert rows and rows[0]["cells"] == "no-scaffold" and rows[0]["decided"] and len(rows) == 1
    plain = solve(inst, "bfs", cells="no-scaffold", abstraction=False, direction="forward", time_limit=60)
    assert plain.status == "optimal"
    assert rows[0].get("optimum", rows[0].get("lower_bound")) == plain.metrics.makespan == best[-1].makespan


@pytest.mark.slow
def test_anytime_climbs_the_ladder_and_keeps_what_it_finds():
    inst = bridge_instance(0)  # keep-structure optimum 8, the widened classes 7 then 6
    result = solve(inst, "anytime", time_limit=30, parallel=False)
    rows = result.stats["ladder"]
    assert rows and all("optimum" in r or "lower_bound" in r for r in rows)
    assert all(r["decided"] == (r["status"] in ("optimal", "feasible")) for r in rows[:-1])  # climbed past
    best = min(r.get("optimum", 1 << 30) for r in rows)
    assert result.metrics.makespan <= best <= 6
    off = solve(inst, "anytime", time_limit=30, parallel=False, ladder=False)
    assert "ladder" not in off.stats


def test_bille_solve_prints_each_rung():
    from bille.tools.solve_commands import _ladder_lines

    rows = [{"add_cells": [[3, 3], [12, 3]], "status": "optimal", "decided": True, "optimum": 56, "s": 12.3},
            {"add_cells": [[3, 3], [12, 3], [2, 3], [13, 3]], "status": "feasible", "decided": True,
             "lower_bound": 56, "s": 40.0},
            {"add_cells": [[3, 3], [12, 3], [2, 3], [13, 3], [14, 3], [2, 1]], "status": "timeout", "decided": False,
             "lower_bound": 48, "s": 93.2}]
    lines = _ladder_lines(rows)
    assert lines[1] == "  +(3,3)(12,3): optimal 56, 12.3 s"
    assert lines[2].endswith(">= 56 (nothing shorter than the best schedule then), 40.0 s")
    assert lines[3] == "  +(3,3)(12,3)(2,3)(13,3)(14,3)(2,1): >= 48 (stopped), 93.2 s"


def test_the_ladder_stops_once_the_best_schedule_is_proved_optimal():
    inst = TINY[0]
    keep = solve(inst, "bfs", cells="keep", time_limit=60)
    assert keep.status == "optimal"
    best = from_schedule(inst, keep.schedule, "keep")
    asked = []

    def closed():
        asked.append(1)
        return len(asked) > 1  # closed after the first rung

    rows = climb(inst, lambda: best, Budget(60), lambda schedule: None, 2_000_000, closed, top=False)
    assert len(rows) == 1 and len(asked) == 2
    assert climb(inst, lambda: best, Budget(60), lambda schedule: None, 2_000_000, lambda: True) == []


def test_bille_solve_prints_the_top():
    from bille.tools.solve_commands import _ladder_lines

    lines = _ladder_lines([{"cells": "no-scaffold", "status": "optimal", "decided": True, "optimum": 54, "s": 19.9}])
    assert lines[1].startswith("  no-scaffold") and lines[1].endswith(": optimal 54, 19.9 s")
