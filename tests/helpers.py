"""Small builders for hand-drawn test instances, and what a schedule does with its tiles."""
from __future__ import annotations

import json

from bille.instances import instance_from_text
from bille.instances.moveset import Kind
from bille.instances.rules import State, run
from bille.instances.schedule import bind
from bille.solvers import schedule_from_text


def make(grid: str, robots: list[dict], *, goal: str | None = None, moveset: str = "S7",
         robot_goals=None, name: str = "test", collisions: str | None = None):
    """An instance from a drawn grid (leading/trailing blank lines and indentation removed)."""
    lines = [f"name: {name}", f"moveset: {moveset}", "grid: |"] + ["  " + r for r in _rows(grid)]
    if collisions is not None:
        lines.append(f"collisions: {collisions}")
    if goal is not None:
        lines += ["goal: |"] + ["  " + r for r in _rows(goal)]
    lines.append("robots: " + json.dumps(robots))
    if robot_goals is not None:
        lines.append("robot_goals: " + json.dumps(robot_goals))
    return instance_from_text("\n".join(lines) + "\n", name)


def sched(*rows: str):
    """A schedule from one whitespace-separated action string per robot."""
    return schedule_from_text("robots:\n" + "".join(f"  - [{', '.join(r.split())}]\n" for r in rows))


def _rows(text: str) -> list[str]:
    return [r.strip() for r in text.strip().splitlines()]


def manipulations(inst, schedule) -> list[tuple[int, int, str, int]]:
    """(step, robot, "pick" | "place", target cell) of every manipulation, in order."""
    ids = bind(inst, schedule)
    state, out = inst.start_state, []
    for t, nxt in enumerate(run(inst.world, state, ids)):
        assert isinstance(nxt, State)
        for i, g in enumerate(inst.world.graphs):
            kind = g.kind[ids[i, t]]
            if kind in (Kind.PICK, Kind.PLACE):
                out.append((t, i, "pick" if kind == Kind.PICK else "place", int(g.target[state.poses[i], ids[i, t]])))
        state = nxt
    return out


def split_with_and_without(inst, kind: str, max_nodes: int):
    """Where cbs makes a ``kind`` split (``rectangle``, ``corridor``) on ``inst``: its result,
    checked optimal and valid, and the result with that reasoning switched off; else None."""
    from bille.solvers import solve, validate

    result = solve(inst, "cbs", time_limit=None, max_nodes=max_nodes)
    if not result.stats.get("split", {}).get(kind):
        return None
    assert result.status == "optimal" and validate(inst, result.schedule).valid
    return result, solve(inst, "cbs", time_limit=None, max_nodes=max_nodes, **{kind: False})


def diagonal_moveset(folder) -> str:
    """A point moveset file in ``folder`` (returned as a path) that also steps north-east: beside
    the shipped ``point``, robots of two movesets."""
    from pathlib import Path

    shipped = Path(__file__).parent.parent / "instances" / "movesets" / "point.yaml"
    path = Path(folder) / "diagonal.yaml"
    path.write_text(shipped.read_text().replace("name: point", "name: diagonal").replace(
        "  west:        {at: [-1, 0]}\n", "  west:        {at: [-1, 0]}\n  north-east:  {at: [1, -1]}\n"))
    return str(path)
