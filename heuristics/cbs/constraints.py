"""What one branch of the constraint tree forbids one robot.

Time: a robot's path is its poses at times ``0 .. T``; *step* ``t`` takes it from time ``t - 1`` to
time ``t``. Under the Bill-E rule two robots conflict at step ``t`` when their collision sets of that
step share a cell (docs/rules.md, rule 3); under classic collisions when they end step ``t`` on the
same cell (vertex) or exchange cells in it (edge). A constraint is a plain tuple:

=======================  ===================================================================
``(CELL, c, t)``         Bill-E: cell ``c`` is not in the robot's collision set of step ``t``
``(VERTEX, v, t)``       classic: the robot is not on cell ``v`` at time ``t``
``(EDGE, u, v, t)``      classic: the robot does not move from ``u`` to ``v`` in step ``t``
``(RANGE, c, t)``        cell ``c`` is not used in any step from ``t`` on (Bill-E: not in the
                         collision set; classic: not stood on at any time from ``t`` on)
``(AFTER, t)``           the robot arrives at its goal for good after time ``t`` (its cost > t)
=======================  ===================================================================

A branch that forbids something of one robot leaves every schedule that does not do it, so the
two children of a conflict together keep every schedule of their parent that has no such
conflict (the branches of :mod:`.conflicts` say why each split is complete).
"""
from __future__ import annotations

CELL, VERTEX, EDGE, RANGE, AFTER = range(5)
NEVER = 1 << 40  # a time no path reaches


class Table:
    """One robot's constraints, indexed for the low-level search.

    ``at[t]``: cells banned at step/time ``t`` (CELL or VERTEX); ``edges[t]``: banned moves
    ``(u, v)``; ``ranges[c]``: the first step from which cell ``c`` is banned; ``min_arrival``:
    the least time at which the robot may arrive for good; ``last``: the latest time any of them
    names (past it, only the ranges remain and they no longer change).
    """

    __slots__ = ("at", "edges", "ranges", "range_cells", "min_arrival", "last", "_stay", "_flat")

    def __init__(self, constraints: tuple) -> None:
        self.at: dict[int, set[int]] = {}
        self.edges: dict[int, set[tuple[int, int]]] = {}
        self.ranges: dict[int, int] = {}
        self.min_arrival = 0
        last = 0
        for con in constraints:
            kind, t = con[0], con[-1]
            if kind == CELL or kind == VERTEX:
                self.at.setdefault(t, set()).add(con[1])
            elif kind == EDGE:
                self.edges.setdefault(t, set()).add((con[1], con[2]))
            elif kind == RANGE:
                c = con[1]
                self.ranges[c] = min(t, self.ranges.get(c, NEVER))
            elif kind == AFTER:
                self.min_arrival = max(self.min_arrival, t + 1)
            last = max(last, t)
        self.range_cells = frozenset(self.ranges)
        self.last = max(last, self.min_arrival)
        self._stay: dict[int, int] = {}
        self._flat = None  # the arrays of the compiled search (.lowlevel_compiled.flat_table)

    def stay_from(self, pose: int, cells: frozenset) -> int:
        """The earliest time from which a robot may stand still at ``pose`` (standing on
        ``cells``) for ever: every later step's ban on those cells is at or before it. NEVER if a
        range bans one of them."""
        found = self._stay.get(pose)
        if found is None:
            if not self.range_cells.isdisjoint(cells):
                found = NEVER
            else:
                found = max((t for t, banned in self.at.items() if not banned.isdisjoint(cells)), default=0)
            self._stay[pose] = found
        return found
