"""What the searches from one end and from both ends share: how a search ended (:class:`Outcome`),
the kernel's working arrays, the replay of a path of stored states into a schedule, and the
successors of one state (the parity test's view of the kernel)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bille.instances import Instance
from bille.instances.rules import State, apply
from bille.instances.run import Budget

from . import kernel
from .compiled import rehash
from .tables import Tables

NO_BOUND = 1 << 62
PENDING = 128  # successors the kernel stores together (.compiled.store)
WORK = 1 << 16  # backtracking steps between two looks at the budget, over the robots (a few ms)


def new_counters() -> np.ndarray:
    """The counters :func:`.kernel.expand` keeps (their indices in :mod:`.kernel`)."""
    counters = np.zeros(kernel.LEAST_CUT + 1, dtype=np.int64)
    counters[kernel.LEAST_CUT] = NO_BOUND
    return counters


def work(t: Tables) -> int:
    """Backtracking steps between two looks at the budget: a step costs about as much as the
    robots are many (the new state is built at each leaf) and, with a pick or place, as the
    grid is large (the connectivity flood fill)."""
    return max(64, (1024 + WORK // max(1, t.m)) // max(1, t.width * t.height // 512))


@dataclass
class Outcome:
    """How a search ended. ``stop``: ``goal`` (``ids``: a schedule of the class's optimum,
    ``[m, T]`` action ids), ``exhausted`` (no schedule of the class below ``U``, or none at all
    without ``U``), ``time``, ``cancelled``, ``states`` (the state cap), ``steps`` (the depth
    cap). ``proved``: no schedule of the class has a makespan below it (module docstring)."""

    stop: str
    proved: int
    ids: np.ndarray | None = None
    least_cut: int = NO_BOUND  # the least bound of a state cut below U (module .search, deepening)
    depth: int = 0
    states: int = 0
    leaves: int = 0
    pruned: int = 0
    layers: list = field(default_factory=list)

    def stats(self) -> dict:
        return {"states": self.states, "depth": self.depth, "joint_actions": self.leaves, "pruned": self.pruned}


def working_arrays(t: Tables, n: int, A: int, m: int, L: int) -> tuple:
    """The kernel's working arrays (in its order), allocated once per search."""
    mm = max(m, 1)
    tiles = np.zeros(n, np.uint8)
    tiles[:] = t.fixed
    return (tiles, np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, np.int64),
            np.zeros((mm, A), np.int64), np.zeros(mm, np.int64), np.full(mm, -1, np.int64), np.zeros(mm, np.int64),
            np.zeros(mm, np.int64), np.zeros(mm, np.int64), np.zeros(mm, np.int64), np.zeros(L, np.int64),
            np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(1, np.int64), np.zeros((mm + 1, max(t.W, 1)), np.int64),
            np.zeros((PENDING, L), np.int64), np.zeros(PENDING, np.int64), np.zeros(PENDING, np.int64),
            np.zeros(1, np.int64))


def successors(t: Tables, n: int, row: np.ndarray, cap: int = 1 << 16) -> tuple[np.ndarray, np.ndarray]:
    """Every valid joint action of the state ``row`` and the raw (unsorted) state it leads to,
    as ``(actions[k, m], rows[k, L])`` (the parity test's view of the kernel)."""
    m, L, A = t.m, t.L, t.kind.shape[1]
    scratch = working_arrays(t, n, A, m, L)
    actions = np.zeros((cap, max(m, 1)), np.int64)
    rows = np.zeros((cap, L), np.int64)
    counters = new_counters()
    kernel.expand(kernel.COLLECT, row[None, :].copy(), np.zeros(1, np.int64), np.zeros(2, np.int64), counters,
                  np.zeros(3, np.int64), 1, NO_BOUND, NO_BOUND, 0, NO_BOUND, *t.args(), *scratch, row.copy(),
                  actions, rows)
    k = int(counters[kernel.N_STATES])
    if k > cap:
        raise ValueError(f"more than {cap} successors")
    return actions[:k, :m], rows[:k]


def replay(instance: Instance, t: Tables, rows: list, scratch) -> np.ndarray:
    """Action ids ``[m, len(rows)]`` of the steps from the start through the (sorted) states
    ``rows`` in turn, with each robot's own identity: each step is one of the successors of the
    actual state whose sorted form is the next row, checked by the Python rules."""
    state = instance.start_state
    m, L = t.m, t.L
    steps = []
    for target in rows:
        raw = t.pack(state, canonical=False)[None, :]
        actions = np.zeros((1, max(m, 1)), np.int64)
        got = kernel.expand(kernel.FIND, raw, np.zeros(1, np.int64), np.zeros(2, np.int64), new_counters(),
                            np.zeros(3, np.int64), 1, NO_BOUND, NO_BOUND, 0, NO_BOUND, *t.args(), *scratch,
                            np.asarray(target).copy(), actions, np.zeros((1, L), np.int64))
        if got != kernel.GOAL:
            raise RuntimeError("joint search: a stored state is no successor of the one before it")
        joint = actions[0, :m].copy()
        nxt = apply(instance.world, state, joint)
        if not isinstance(nxt, State):
            raise RuntimeError(f"joint search: the rebuilt step breaks a rule: {nxt}")
        steps.append(joint)
        state = nxt
    return np.array(steps, dtype=np.int64).T.reshape(m, len(steps))


class Store:
    """The states one search has stored: rows, parents, hash table, counters, and the layer under
    way (a range of rows; the first layer is the seeds, whose paths start there)."""

    def __init__(self, t: Tables, rows: int, seeds: np.ndarray, scratch) -> None:
        self.t, self.scratch, self.rows = t, scratch, rows
        self.states = np.zeros((rows, t.L), dtype=np.int64)  # pages are touched only as states are stored
        self.parent = np.zeros(rows, dtype=np.int64)
        k = self.seeds = len(seeds)
        self.states[:k] = seeds
        self.table = rehash(self.states, k, 1 << max(12, (2 * k).bit_length() + 1))
        self.counters = new_counters()
        self.counters[kernel.N_STATES] = self.counters[kernel.N_TABLE] = k
        self.lo, self.hi, self.depth = 0, k, 0
        self.cursor: np.ndarray | None = None  # where the layer under way stands, between calls

    @property
    def stored(self) -> int:
        return int(self.counters[kernel.N_STATES])

    @property
    def goal_row(self) -> int:
        return int(self.counters[kernel.GOAL_ROW])

    def layer(self, budget: Budget, cap: int, U: int = NO_BOUND) -> str:
        """Build the next layer below ``U``, or go on with the one under way, with at most ``cap``
        states stored: ``done`` (the layer is complete), ``goal`` (a goal state was stored, at
        :attr:`goal_row`; the layer is not complete, and a call goes on with it), ``time``,
        ``cancelled`` or ``states``."""
        if self.cursor is None:
            self.cursor = np.zeros(3, dtype=np.int64)
            self.cursor[0] = self.lo
        m, L = self.t.m, self.t.L
        while True:
            got = kernel.expand(kernel.SEARCH, self.states, self.parent, self.table, self.counters, self.cursor,
                                self.hi, work(self.t), cap, self.depth, U, *self.t.args(), *self.scratch,
                                self.states[0].copy(), np.zeros((1, max(m, 1)), np.int64), np.zeros((1, L), np.int64))
            if got == kernel.GROW:
                self.table = rehash(self.states, self.stored, 2 * self.table.shape[0])
            elif got == kernel.FULL:
                return "states"
            elif got == kernel.PAUSED:
                if budget.expired():
                    return "cancelled" if budget.cancelled else "time"
            elif got == kernel.GOAL:
                return "goal"
            else:
                self.lo, self.hi, self.cursor = self.hi, self.stored, None
                self.depth += 1
                return "done"

    def path(self, row: int) -> list[int]:
        """Rows from this store's seed to ``row``."""
        out = [row]
        while out[-1] >= self.seeds:
            out.append(int(self.parent[out[-1]]))
        return out[::-1]
