"""The low-level search of :mod:`.lowlevel` for point robots (classic collisions), compiled.

It is :func:`.lowlevel.search` step for step: the same nodes ``(pose, time)`` (one per pose past
the latest time a constraint or another path names), the same order of the open list (least
``f``, then fewest conflicts with the other paths, then latest time, then first pushed), the same
moves in the same order (wait first) and the same test of a node against the best one found at
its place, so it returns the same path (tests/test_cbs_compiled.py compares the two on random
constraint sets). Only the bookkeeping differs: nodes are rows of an array, each with its parent
row, the open list a binary heap of rows, the best row per ``(pose, time)`` an open-addressing
table, the constraints and the conflict-avoidance table sorted arrays of keys
(:func:`flat_table`, :class:`.classic.ClassicAvoid`). Its MDD is in :mod:`.mdd_compiled` (with
:func:`.mdd_compiled.warm_up`), the corridor split's distances in the walk's compiled search
(:meth:`bille.instances.walking.Walk.from_pose_avoiding`); the constraint tree switches to them
once its searches in Python have taken long (:data:`.search.SWITCH`), or from the start where
Numba is loaded already.

The search runs in slices of :data:`SLICE` expansions, so the caller can look at its budget
between two; the arrays live in :class:`Scratch` and grow between two slices when full.
"""
from __future__ import annotations

import numpy as np

from bille.instances.jit import jit

from .constraints import NEVER, Table
from .lowlevel import Agent, Path, Stopped

SLICE = 1 << 14  # expansions between two looks at the budget
FOUND, NONE, PAUSED, GROW = 0, 1, 2, 3
# the columns of a node row, and the counters
POSE, TIME, CONFLICTS, PARENT, ACTION, F = range(6)
N_ROWS, N_HEAP, N_TABLE, EXPANDED, GOAL = range(5)


def flat_table(table: Table, poses: int) -> tuple:
    """``table`` as sorted arrays of keys (cached on it), after the ``stride`` they use (the
    poses, or more if a constraint names a larger cell): banned cells ``t * stride + c``, banned
    moves ``(t * stride + u) * stride + v``, and the ranges' cells with their first times."""
    found = getattr(table, "_flat", None)
    if found is None or found[0] != poses:
        named = [c for cells in table.at.values() for c in cells] + [c for moves in table.edges.values()
                                                                     for m in moves for c in m]
        stride = max([poses, *(c + 1 for c in named)])
        at = sorted(t * stride + c for t, cells in table.at.items() for c in cells)
        edges = sorted((t * stride + u) * stride + v for t, moves in table.edges.items() for u, v in moves)
        cells = sorted(table.ranges)
        found = (poses, stride, np.array(at, np.int64), np.array(edges, np.int64), np.array(cells, np.int64),
                 np.array([table.ranges[c] for c in cells], np.int64))
        table._flat = found
    return found[1:]


@jit
def _has(keys, key):  # pragma: no cover - compiled
    i = np.searchsorted(keys, key)
    return i < keys.shape[0] and keys[i] == key


@jit
def _count(keys, counts, key):  # pragma: no cover - compiled
    i = np.searchsorted(keys, key)
    if i < keys.shape[0] and keys[i] == key:
        return counts[i]
    return 0


@jit
def _before(rows, a, b):  # pragma: no cover - compiled
    """Whether row ``a`` comes out of the open list before row ``b``: (f, conflicts, -time, row)."""
    if rows[a, F] != rows[b, F]:
        return rows[a, F] < rows[b, F]
    if rows[a, CONFLICTS] != rows[b, CONFLICTS]:
        return rows[a, CONFLICTS] < rows[b, CONFLICTS]
    if rows[a, TIME] != rows[b, TIME]:
        return rows[a, TIME] > rows[b, TIME]
    return a < b


@jit
def _push(heap, n, rows, r):  # pragma: no cover - compiled
    i = n
    heap[i] = r
    while i > 0:
        up = (i - 1) // 2
        if not _before(rows, heap[i], heap[up]):
            break
        heap[i], heap[up] = heap[up], heap[i]
        i = up


@jit
def _pop(heap, n, rows):  # pragma: no cover - compiled
    top = heap[0]
    n -= 1
    heap[0] = heap[n]
    i = 0
    while True:
        a = 2 * i + 1
        if a >= n:
            break
        if a + 1 < n and _before(rows, heap[a + 1], heap[a]):
            a += 1
        if not _before(rows, heap[a], heap[i]):
            break
        heap[i], heap[a] = heap[a], heap[i]
        i = a
    return top


@jit
def _slot(table, rows, key, cap1):  # pragma: no cover - compiled
    """The slot of node ``key`` (``pose * cap1 + min(time, cap)``): its row + 1, or 0."""
    mask = table.shape[0] - 1
    s = (key * np.int64(-7046029254386353131)) & mask
    while True:
        e = table[s]
        if e == 0 or rows[e - 1, POSE] * cap1 + min(rows[e - 1, TIME], cap1 - 1) == key:
            return s
        s = (s + 1) & mask


@jit
def rehash(table, rows, cap1, size):  # pragma: no cover - compiled
    out = np.zeros(size, np.int64)
    for e in table:
        if e != 0:
            key = rows[e - 1, POSE] * cap1 + min(rows[e - 1, TIME], cap1 - 1)
            out[_slot(out, rows, key, cap1)] = e
    return out


@jit
def stay_from(p, stride, at, cells):  # pragma: no cover - compiled
    """:meth:`.constraints.Table.stay_from` of a point robot standing on its cell ``p``."""
    if _has(cells, p):
        return NEVER
    last = 0
    for key in at:
        if key % stride == p:
            last = max(last, key // stride)
    return last


@jit
def allowed(p, q, t, stride, at, edges, cells, firsts):  # pragma: no cover - compiled
    """:func:`.lowlevel.allowed` of a point robot."""
    if _has(at, t * stride + q) or _has(edges, (t * stride + p) * stride + q):
        return False
    i = np.searchsorted(cells, q)
    return not (i < cells.shape[0] and cells[i] == q and t >= firsts[i])


@jit
def run(rows, heap, table, counters, succ, wait, dist, home, stride, at, edges, cells, firsts, min_arrival, cap,
        avoid, at_keys, at_counts, at_last, at_size, move_keys, cost_cap, unreachable):  # pragma: no cover
    """One slice of the search (module docstring); ``counters`` keeps where it stands."""
    cap1 = cap + 1
    A = succ.shape[1]
    done = 0
    while counters[N_HEAP] > 0:
        if counters[N_ROWS] + A > rows.shape[0] or 2 * (counters[N_TABLE] + A) > table.shape[0]:
            return GROW
        if done >= SLICE:
            return PAUSED
        r = _pop(heap, counters[N_HEAP], rows)
        counters[N_HEAP] -= 1
        p, t, k = rows[r, POSE], rows[r, TIME], rows[r, CONFLICTS]
        b = table[_slot(table, rows, p * cap1 + min(t, cap), cap1)] - 1
        if rows[b, TIME] < t or (rows[b, TIME] == t and rows[b, CONFLICTS] < k):
            continue
        if rows[r, F] > cost_cap:
            return NONE
        if home[p] and t >= min_arrival and t >= stay_from(p, stride, at, cells):
            counters[GOAL] = r
            return FOUND
        done += 1
        counters[EXPANDED] += 1
        t1 = t + 1
        for j in range(A):
            a = wait if j == 0 else (j - 1 if j - 1 < wait else j)
            q = succ[p, a]
            if q < 0 or dist[q] >= unreachable:
                continue
            if not allowed(p, q, t1, stride, at, edges, cells, firsts):
                continue
            k1 = k
            if avoid:
                if t1 > at_last:
                    k1 += _count(at_keys, at_counts, (at_last + 1) * at_size + q)
                else:
                    k1 += _count(at_keys, at_counts, t1 * at_size + q)
                    if p != q and _has(move_keys, (t1 * at_size + q) * at_size + p):
                        k1 += 1
            s = _slot(table, rows, q * cap1 + min(t1, cap), cap1)
            e = table[s] - 1
            if e >= 0 and (rows[e, TIME] < t1 or (rows[e, TIME] == t1 and rows[e, CONFLICTS] <= k1)):
                continue
            n = counters[N_ROWS]
            rows[n, POSE], rows[n, TIME], rows[n, CONFLICTS], rows[n, PARENT], rows[n, ACTION] = q, t1, k1, r, a
            rows[n, F] = max(t1 + dist[q], min_arrival)
            counters[N_ROWS] = n + 1
            if e < 0:
                counters[N_TABLE] += 1
            table[s] = n + 1
            _push(heap, counters[N_HEAP], rows, n)
            counters[N_HEAP] += 1
    return NONE


class Scratch:
    """The arrays of one robot's searches (reused from one search to the next, grown as needed)."""

    def __init__(self) -> None:
        self.rows = np.zeros((1 << 12, 6), np.int64)
        self.heap = np.zeros(1 << 12, np.int64)
        self.table = np.zeros(1 << 13, np.int64)


def search(agent: Agent, arrays: tuple, table: Table, avoid, scratch: Scratch, *, cost_cap: int = NEVER,
           poll=None, stats: dict | None = None) -> Path | None:
    """:func:`.lowlevel.search` of a point robot: ``arrays`` are its walk's ``(succ, wait, dist,
    home)`` (numpy), ``avoid`` a :class:`.classic.ClassicAvoid` or None."""
    from bille.instances.walking import UNREACHABLE

    succ, wait, dist, home = arrays
    start = agent.start
    if dist[start] >= UNREACHABLE:
        return None
    stride, at, edges, cells, firsts = flat_table(table, len(dist))
    cap = max(table.last, 0 if avoid is None else avoid.last) + 1
    if avoid is None:
        at_keys = at_counts = move_keys = np.zeros(0, np.int64)
        at_last, at_size = 0, 1
    else:
        at_keys, at_counts, move_keys, at_last, at_size = avoid.keys, avoid.counts, avoid.move_keys, avoid.last, avoid.size
    rows, heap = scratch.rows, scratch.heap
    rows[0] = (start, 0, 0, -1, -1, max(int(dist[start]), table.min_arrival))
    heap[0] = 0
    scratch.table[:] = 0
    scratch.table[_slot(scratch.table, rows, start * (cap + 1), cap + 1)] = 1
    counters = np.array([1, 1, 1, 0, -1], np.int64)
    while True:
        got = run(scratch.rows, scratch.heap, scratch.table, counters, succ, wait, dist, home, stride, at, edges, cells,
                  firsts, table.min_arrival, cap, avoid is not None, at_keys, at_counts, at_last, at_size, move_keys,
                  cost_cap, UNREACHABLE)
        if got == GROW:
            if counters[N_ROWS] + succ.shape[1] > scratch.rows.shape[0]:
                scratch.rows = np.concatenate([scratch.rows, np.zeros_like(scratch.rows)])
                scratch.heap = np.concatenate([scratch.heap, np.zeros_like(scratch.heap)])
            else:
                scratch.table = rehash(scratch.table, scratch.rows, cap + 1, 2 * scratch.table.shape[0])
        elif got == PAUSED:
            if poll is not None and poll():
                raise Stopped
        else:
            break
    if stats is not None:
        stats["low_expanded"] = stats.get("low_expanded", 0) + int(counters[EXPANDED])
    return _unwind(agent, scratch.rows, int(counters[GOAL])) if got == FOUND else None


def _unwind(agent: Agent, rows: np.ndarray, r: int) -> Path:
    poses, actions, cells = [], [], []
    while r >= 0:
        p, a, r = int(rows[r, POSE]), int(rows[r, ACTION]), int(rows[r, PARENT])
        poses.append(p)
        actions.append(a)
    poses.reverse()
    actions.reverse()
    for p, a in zip(poses, actions[1:]):
        cells.append(next(c for b, _, c in agent.moves(p) if b == a))
    return Path(tuple(poses), (-1, *actions[1:]), (frozenset(), *cells), len(poses) - 1)

