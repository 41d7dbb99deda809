"""The MDD of :func:`.lowlevel.mdd` for point robots, compiled (the moves of every least-cost
path, found layer by layer forwards and kept backwards from the goal poses);
tests/test_cbs_compiled.py compares it with the Python one."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from bille.instances.jit import jit

from .constraints import Table
from .lowlevel import MDD, Agent
from .lowlevel_compiled import Scratch, allowed, flat_table, search, stay_from


@jit
def mdd_run(start, succ, dist, home, cost, stride, at, edges, cells, firsts, min_arrival, out):  # pragma: no cover
    """The moves of :func:`.lowlevel.mdd` as rows ``(time, p, q, action)`` of ``out``, layer by
    layer: their number, or -1 if ``out`` is too small."""
    P, A = succ.shape
    mark = np.full(P, -1, np.int64)
    level = np.zeros(P, np.int64)
    nxt = np.zeros(P, np.int64)
    level[0] = start
    size, n = 1, 0
    first = np.zeros(cost + 2, np.int64)  # the rows of step t: first[t] .. first[t + 1] - 1
    for t in range(1, cost + 1):
        first[t] = n
        m = 0
        for i in range(size):
            p = level[i]
            for a in range(A):
                q = succ[p, a]
                if q < 0 or t + dist[q] > cost or not allowed(p, q, t, stride, at, edges, cells, firsts):
                    continue
                if n >= out.shape[0]:
                    return -1
                out[n, 0], out[n, 1], out[n, 2], out[n, 3] = t, p, q, a
                n += 1
                if mark[q] != t:
                    mark[q] = t
                    nxt[m] = q
                    m += 1
        level, nxt = nxt, level
        size = m
    first[cost + 1] = n
    # back from the goal poses of the last layer: a move is kept when it leads to a kept pose
    keep = np.full((2, P), -1, np.int64)
    for i in range(size if cost > 0 else 0):
        q = level[i]
        if home[q] and cost >= min_arrival and cost >= stay_from(q, stride, at, cells):
            keep[cost % 2, q] = cost
    for t in range(cost, 0, -1):
        for r in range(first[t], first[t + 1]):
            if keep[t % 2, out[r, 2]] == t:
                keep[(t - 1) % 2, out[r, 1]] = t - 1
                out[r, 0] = -out[r, 0]  # kept: marked, read back below
    w = 0
    for r in range(n):
        if out[r, 0] < 0:
            out[w, 0], out[w, 1], out[w, 2], out[w, 3] = -out[r, 0], out[r, 1], out[r, 2], out[r, 3]
            w += 1
    return w


def mdd(agent: Agent, arrays: tuple, table: Table, cost: int) -> MDD:
    """:func:`.lowlevel.mdd` of a point robot (``arrays`` as :func:`search`'s)."""
    succ, _, dist, home = arrays
    stride, at, edges, cells, firsts = flat_table(table, len(dist))
    out = np.zeros((4096, 4), np.int64)
    while True:
        n = mdd_run(agent.start, succ, dist, home, cost, stride, at, edges, cells, firsts, table.min_arrival, out)
        if n >= 0:
            break
        out = np.zeros((2 * out.shape[0], 4), np.int64)
    if cost == 0:
        start = agent.start
        stay = home[start] and table.min_arrival <= 0 and table.stay_from(start, agent.stand(start)) <= 0
        return MDD(0, (frozenset((start,) if stay else ()),), ((),))
    rows = out[:n]
    first = np.searchsorted(rows[:, 0], np.arange(cost + 2))  # step t's rows: first[t] .. first[t + 1] - 1
    return MDD(cost, _Levels(rows, first), _Steps(agent, rows, first))


class _Lazy(Sequence):
    """An MDD's levels or steps, one per time, each read from the rows (and kept) when asked for:
    a large MDD is asked for a few of them only."""

    def __init__(self, rows: np.ndarray, first: np.ndarray) -> None:
        self.rows, self.first, self._got = rows, first, {}

    def __len__(self) -> int:
        return len(self.first) - 1

    def __getitem__(self, t):
        if not isinstance(t, int):
            return [self[i] for i in range(len(self))[t]]
        t = range(len(self))[t]
        found = self._got.get(t)
        if found is None:
            found = self._got[t] = self._read(t)
        return found

    def _read(self, t: int):
        raise NotImplementedError


class _Levels(_Lazy):
    """The poses at each time: the ends of the step's moves (time 0: the starts of step 1's)."""

    def _read(self, t: int) -> frozenset:
        if t == 0:
            return frozenset(self.rows[self.first[1]:self.first[2], 1].tolist())
        return frozenset(self.rows[self.first[t]:self.first[t + 1], 2].tolist())


class _Steps(_Lazy):
    """The moves ``(p, q, cells)`` of each step."""

    def __init__(self, agent: Agent, rows: np.ndarray, first: np.ndarray) -> None:
        super().__init__(rows, first)
        self.agent = agent

    def _read(self, t: int) -> tuple:
        moves = self.agent.moves
        return tuple((p, q, next(c for b, _, c in moves(p) if b == a))
                     for _, p, q, a in self.rows[self.first[t]:self.first[t + 1]].tolist())


def warm_up() -> None:
    """Load (or compile) the compiled low level now (:mod:`.lowlevel_compiled` and this module):
    a search and an MDD on two cells."""
    succ = np.array([[0, 1], [1, 0]], np.int32)  # wait, and a step to the other cell

    def moves(p: int) -> list:
        return [(0, p, frozenset((p,))), (1, 1 - p, frozenset((1 - p,)))]

    arrays = (succ, 0, np.array([1, 0], np.int64), np.array([False, True]))
    agent = Agent(0, 0, moves, [1, 0], [False, True], 1, arrays)
    path = search(agent, arrays, Table(()), None, Scratch())
    mdd(agent, arrays, Table(()), path.cost)
