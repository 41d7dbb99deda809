"""The joint search from both ends: layers from the start and layers back from the goal states,
until a state is met from both sides.

**Why it is exact.** Let ``a`` layers be complete from the start (every state within ``a`` steps
of it stored) and ``b`` back from the goal states (every state from which a goal state is within
``b`` steps), with no state stored on both sides. Take any schedule of the class, of makespan
``L <= a + b``, and its state after ``k = max(0, L - b)`` steps: ``k <= a`` steps from the start
and ``L - k <= b`` steps from a goal state, so it would be stored on both sides. Hence no schedule
of the class has a makespan of ``a + b`` or less, and a search stopped there has proved ``a + b +
1``. When the next layer (on either side) meets the other side at a state, the path through it
has ``a + b + 1`` steps at most, so exactly that many: it is optimal.

The steps back are the steps forward read backwards (:func:`.tables.reverse_tables`), over the
same class, so the states met backwards are exactly those from which a goal state is reached
forwards. The goal states are listed at the start (:func:`goal_rows`): the goal's tiles, no load,
each robot with a goal cell on a pose with its front foot there, the others on any pose, feet on
tiles and apart. Where there are more than :data:`MAX_GOALS`, the search goes forward only.

The schedule is replayed forward through the met state to the goal state the backward path
ends in (:func:`.store.replay`).
"""
from __future__ import annotations

import itertools
import math

import numpy as np

from bille.instances import Instance
from bille.instances.rules import State
from bille.instances.run import Budget, Events

from . import kernel
from .cells import Cells
from .compiled import jit, lookup, row_of
from .store import Outcome, Store, replay, working_arrays
from .tables import Tables, reverse_tables

MAX_GOALS = 50_000
MAX_GOAL_WORK = 20_000_000  # placements x (cells + robots) packed in Python: about a second


def goal_rows(instance: Instance, t: Tables, budget: Budget, limit: int = MAX_GOALS) -> np.ndarray | None:
    """Every goal state of the class as a (sorted) row, or None where there are more than
    ``limit`` to list, or more than :data:`MAX_GOAL_WORK` robot placements times cells to pack
    (listed in Python), or the budget ends first."""
    world = instance.world
    tiles = instance.goal_tiles
    options = []
    for i, (g, goal) in enumerate(zip(world.graphs, instance.goal_cells)):
        feet = g.feet
        on = g.valid & tiles[np.maximum(feet[:, 0], 0)] & tiles[np.maximum(feet[:, 1], 0)]
        if goal >= 0:
            on &= feet[:, 0] == goal
        options.append(np.flatnonzero(on).tolist())
    placements = sum(math.log(max(1, len(o))) for o in options)  # a product overflows from ~150 robots on
    if limit < 1 or placements > math.log(4 * limit) or math.exp(placements) * (len(t.cell_of) + t.m) > MAX_GOAL_WORK:
        return None
    rows = {}
    for n, poses in enumerate(itertools.product(*options)):
        if n % 1024 == 0 and budget.expired():
            return None
        cells = [c for i, p in enumerate(poses) for c in set(world.graphs[i].feet[p].tolist())]
        if len(cells) != len(set(cells)):
            continue
        state = State(tiles, tuple(int(p) for p in poses), (False,) * len(poses))
        row = t.pack(state)
        rows[row.tobytes()] = row
        if len(rows) > limit:
            return None
    if not rows:
        return np.zeros((0, t.L), np.int64)
    return np.array(list(rows.values()), dtype=np.int64)


@jit
def _meet(states, lo, hi, other, table):  # pragma: no cover - compiled
    """The first row of ``states[lo:hi]`` stored in ``other`` (its row there), or -1, -1."""
    for r in range(lo, hi):
        slot = lookup(other, table, states[r])
        if table[slot] != 0:
            return r, row_of(table[slot])
    return -1, -1


def search_both(instance: Instance, cells: Cells, t: Tables, goals: np.ndarray, budget: Budget, *, U: int | None,
                max_states: int, max_steps: int | None, events: Events | None):
    """The search from both ends (module docstring); an :class:`.search.Outcome`."""
    n = instance.width * instance.height
    back_t = reverse_tables(instance, t)
    rows = max(2, int(max_states) // 2 + len(goals))  # the two stores within the state cap (and its memory)
    fwd = Store(t, rows, t.pack(instance.start_state)[None, :], working_arrays(t, n, t.kind.shape[1], t.m, t.L))
    bwd = Store(back_t, rows, goals, working_arrays(back_t, n, t.kind.shape[1], t.m, t.L))
    out = Outcome("time", 1)

    def ended(stop: str, proved) -> Outcome:
        out.stop, out.proved, out.depth = stop, proved, fwd.depth + bwd.depth
        out.states = fwd.stored + bwd.stored
        out.leaves = int(fwd.counters[kernel.LEAVES] + bwd.counters[kernel.LEAVES])
        out.layers = [fwd.depth, bwd.depth]
        return out

    if len(goals) == 0:
        return ended("exhausted", np.inf if U is None else U)
    a, b = _meet(fwd.states, 0, 1, bwd.states, bwd.table)
    if a >= 0:  # the start is a goal state
        out.ids = np.zeros((instance.num_robots, 0), np.int64)
        return ended("goal", 0)
    while True:
        done = fwd.depth + bwd.depth
        proved = done + 1 if U is None else min(done + 1, U)
        if U is not None and done + 1 >= U:
            return ended("exhausted", U)
        if max_steps is not None and done >= max_steps:
            return ended("steps", proved)
        side, other = (fwd, bwd) if fwd.hi - fwd.lo <= bwd.hi - bwd.lo else (bwd, fwd)
        lo = side.hi
        if budget.expired():  # between layers too, as forward
            got = "cancelled" if budget.cancelled else "time"
        else:
            got = side.layer(budget, min(rows, max_states - other.stored))
        while got == "goal":  # a goal state stored from the start: the sides meet in this layer
            got = side.layer(budget, min(rows, max_states - other.stored))
        if got != "done":
            return ended(got, proved)
        a, b = _meet(side.states, lo, side.hi, other.states, other.table)
        if events is not None:
            events.progress({"class": cells.key, "depth": fwd.depth + bwd.depth, "states": fwd.stored + bwd.stored,
                             "lower": fwd.depth + bwd.depth + 1, "best": U, "elapsed": budget.elapsed()})
        if a >= 0:
            f_row, b_row = (a, b) if side is fwd else (b, a)
            path = [fwd.states[r] for r in fwd.path(f_row)[1:]] + [bwd.states[r] for r in bwd.path(b_row)[::-1][1:]]
            out.ids = replay(instance, t, path, fwd.scratch)
            return ended("goal", done + 1)
        if side.lo == side.hi:  # one side has nothing new: every state it can reach is stored
            return ended("exhausted", np.inf if U is None else U)

