"""The two collision rules as conflicts between two paths, the branches that resolve them, and
how hard each conflict is (cardinal, semi-cardinal, non-cardinal).

A conflict is a tuple ``(kind, i, j, t, where)``:

==========  ================================================================================
``CELLS``   Bill-E: robots ``i`` and ``j`` both have cell ``where`` in their collision sets of
            step ``t``. Branches: ``i`` keeps ``where`` out of step ``t``; or ``j`` does. Every
            schedule without this conflict keeps one of the two (rule 3: the sets are disjoint).
``VERTEX``  classic: both stand on cell ``where`` at time ``t``. Branches as for CELLS.
``EDGE``    classic: ``i`` moves ``where = (u, v)``, ``j`` moves ``(v, u)`` in step ``t``.
            Branches: ``i`` does not move ``u -> v`` in step ``t``; or ``j`` not ``v -> u``.
``TARGET``  ``i`` has arrived for good at its goal cell ``where`` by time ``t`` (its cost
            ``l_i <= t``) and ``j`` uses that cell in step ``t`` (classic: stands on it at time
            ``t``). Branches (target reasoning, Li et al. 2021): ``l_i > t`` (``AFTER``); or ``j``
            never uses the cell from step ``t`` on (``RANGE``). Complete: if ``l_i <= t``, robot
            ``i``'s front foot is on the cell at every time from ``t`` on, so it is in ``i``'s
            collision set of every step from ``t`` on (classic: ``i`` stands on it), and ``j``'s
            may not hold it.
==========  ================================================================================

Both branches of each kind exclude the conflict of the current paths, so the search progresses.
"""
from __future__ import annotations

from .constraints import AFTER, CELL, EDGE, RANGE, VERTEX
from .corridor import CORRIDOR
from .lowlevel import MDD, Agent, Path
from .rectangle import RECTANGLE

CELLS, VERTEXC, EDGEC, TARGET = range(4)
KIND_NAMES = ("cells", "vertex", "edge", "target", "rectangle", "corridor")


def first_conflict(agents: list[Agent], i: int, pi: Path, j: int, pj: Path, classic: bool):
    """The earliest conflict between robot ``i`` on ``pi`` and robot ``j`` on ``pj``, or None."""
    last = max(pi.cost, pj.cost)
    if classic:
        return _classic(agents, i, pi, j, pj, last)
    ai, aj = agents[i], agents[j]
    stand_i = stand_j = None
    for t in range(1, last + 1):
        if t <= pi.cost:
            ci = pi.cells[t]
        else:
            ci = stand_i = stand_i or ai.stand(pi.poses[-1])
        if t <= pj.cost:
            cj = pj.cells[t]
        else:
            cj = stand_j = stand_j or aj.stand(pj.poses[-1])
        if ci.isdisjoint(cj):
            continue
        common = ci & cj
        if ai.goal >= 0 and pi.cost <= t and ai.goal in common:
            return (TARGET, i, j, t, ai.goal)
        if aj.goal >= 0 and pj.cost <= t and aj.goal in common:
            return (TARGET, j, i, t, aj.goal)
        return (CELLS, i, j, t, min(common))
    return None


def _classic(agents: list[Agent], i: int, pi: Path, j: int, pj: Path, last: int):
    P, Q = pi.poses, pj.poses
    ni, nj = len(P) - 1, len(Q) - 1
    for t in range(1, last + 1):
        u, v = P[min(t, ni)], Q[min(t, nj)]
        if u == v:
            if agents[i].goal == u and ni <= t:
                return (TARGET, i, j, t, u)
            if agents[j].goal == v and nj <= t:
                return (TARGET, j, i, t, v)
            return (VERTEXC, i, j, t, u)
        pu, pv = P[min(t - 1, ni)], Q[min(t - 1, nj)]
        if pu == v and pv == u and u != pu:
            return (EDGEC, i, j, t, (pu, u))
    return None


def branches(conflict) -> tuple[tuple[int, tuple], tuple[int, tuple]]:
    """The two children of a conflict: ``(robot, constraints)`` each (module docstring; those
    of a rectangle, :mod:`.rectangle`, or a corridor, :mod:`.corridor`, carry their own)."""
    kind, i, j, t, where = conflict
    if kind == CELLS:
        return (i, ((CELL, where, t),)), (j, ((CELL, where, t),))
    if kind == VERTEXC:
        return (i, ((VERTEX, where, t),)), (j, ((VERTEX, where, t),))
    if kind == EDGEC:
        u, v = where
        return (i, ((EDGE, u, v, t),)), (j, ((EDGE, v, u, t),))
    if kind == RECTANGLE or kind == CORRIDOR:
        return (i, where[0]), (j, where[1])
    return (i, ((AFTER, t),)), (j, ((RANGE, where, t),))


def forced(agent: Agent, m: MDD | None, conflict, side: int, classic: bool) -> bool:
    """Whether every path of least cost of the robot on ``side`` (0: ``i``, 1: ``j``) has the
    conflict, so that its branch raises that robot's cost (``m``: its MDD, None if unknown)."""
    kind, i, j, t, where = conflict
    if kind == TARGET and side == 0:
        return True  # l_i <= t now; the branch asks l_i > t
    if m is None:
        return False
    c = m.cost
    if classic:
        if kind == EDGEC:
            u, v = where if side == 0 else where[::-1]
            return t <= c and m.levels[t - 1] == {u} and m.levels[t] == {v}
        return m.levels[min(t, c)] == {where}  # (never empty: a path of cost c exists)
    if t <= c:
        return bool(m.steps[t]) and all(where in cells for _, _, cells in m.steps[t])
    return bool(m.levels[c]) and all(where in agent.stand(p) for p in m.levels[c])
