"""Classic collisions at scale: the other robots' paths as numpy tables.

Under classic collisions a robot is a point and its pose is its cell, so every path is a row of
cells, one per time; padded with its last cell, the paths of a node are an ``int[m, L]`` matrix.
On it the two things the constraint tree does for every robot it plans again take one numpy
pass instead of a Python loop per robot and step: which other robots its new path meets at all
(:func:`meeting`; the first conflict of each is then found exactly by :mod:`.conflicts`), and
how often each cell is used at each time (:class:`ClassicAvoid`, the conflict-avoidance table).
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from .lowlevel import Path


def matrix(paths: list[Path], length: int) -> np.ndarray:
    """``int[m, length]``: each path's cell at times ``0 .. length - 1`` (its last cell after its end)."""
    return np.array([p.poses + (p.poses[-1],) * (length - len(p.poses)) for p in paths], dtype=np.int64)


def meeting(cells: np.ndarray, k: int) -> list[int]:
    """The robots whose rows of ``cells`` share a cell with row ``k`` at some time after 0, or
    exchange cells with it in one step (the robots it may conflict with)."""
    mine = cells[k]
    same = (cells[:, 1:] == mine[None, 1:]).any(axis=1)
    moved = mine[1:] != mine[:-1]
    swap = ((cells[:, 1:] == mine[None, :-1]) & (cells[:, :-1] == mine[None, 1:]) & moved[None, :]).any(axis=1)
    hit = same | swap
    hit[k] = False
    return np.flatnonzero(hit).tolist()


class ClassicAvoid:
    """The conflict-avoidance table of :class:`~.lowlevel.Avoid` for point robots: robots on a
    cell at a time (counts keyed ``t * size + cell``) and the moves made in each step, as
    the same counts (a tie-breaker only), both sparse."""

    def __init__(self, paths: list[Path | None], skip: int, size: int) -> None:
        others = [p for k, p in enumerate(paths) if k != skip and p is not None]
        self.size = size
        self.last = max((p.cost for p in others), default=0)
        length = self.last + 2
        if not others:
            self.keys = self.counts = self.move_keys = np.zeros(0, np.int64)
            return
        cells = matrix(others, length)
        times = np.arange(length, dtype=np.int64)[None, :]
        # sparse: the robots' cells at each time are few against every cell at every time;
        # sorted, as the compiled search looks them up (.lowlevel_compiled)
        self.keys, self.counts = np.unique((times * size + cells).ravel(), return_counts=True)
        before, after = cells[:, :-1], cells[:, 1:]
        moved = before != after
        self.move_keys = np.unique(((times[:, 1:] * size + before) * size + after)[moved])

    @cached_property
    def at(self) -> dict[int, int]:
        """Robots on a cell at a time, keyed ``t * size + cell``."""
        return dict(zip(self.keys.tolist(), self.counts.tolist()))

    @cached_property
    def moves(self) -> set[int]:
        """The moves of step ``t`` from cell ``u`` to ``v``, keyed ``(t * size + u) * size + v``."""
        return set(self.move_keys.tolist())

    def count(self, p: int, q: int, cells: frozenset, t: int) -> int:
        size = self.size
        if t > self.last:
            return self.at.get((self.last + 1) * size + q, 0)
        n = self.at.get(t * size + q, 0)
        if p != q and ((t * size + q) * size + p) in self.moves:  # someone moves q -> p then
            n += 1
        return n
