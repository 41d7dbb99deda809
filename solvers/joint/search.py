"""Layered breadth-first search over the joint states of one class of schedules, compiled.

:func:`search` stores every joint state reached (robots' poses and loads, the tiles on the cells
the class allows to change; :mod:`.kernel`) once, layer by layer, and stops at the first goal
state: its depth is the class's optimum, and the parent links give a schedule of that makespan.

**Why it is exact.** Layer ``d`` holds every state reachable in ``d`` steps by a schedule of the
class and in no fewer (each state is stored at its first, least depth; a state met again is
dropped, since what can follow it does not depend on how it was reached). Every state is tested
for the goal when it is stored, so when layer ``d + 1`` is being built, no schedule of the class
has a makespan of ``d`` or less: a search stopped there (time, Ctrl-C, the state cap) has proved
the class's optimum is at least ``d + 1``; an exhausted search proves the class has no schedule.

**Pruning below an upper bound** ``U`` (a schedule known, of makespan ``U``). A state at depth
``g`` is dropped when ``g + h >= U``, with

    ``h = max( max_i ( dist_i(pose_i) + carrying_i ),  ceil(mismatch / m),  max_c tile_c )``

``dist_i`` (:func:`.tables._distances`) counts the motions robot ``i`` needs to reach a pose with
its front foot on its goal cell, over the moves whose new feet are on cells that may hold a tile
in the class (rule 4 puts every foot on a tile, and no other cell ever holds one); a robot that
carries must besides place its tile, a step without motion; ``mismatch`` counts the cells
allowed to change whose tile differs from the goal's, and each needs a pick or a place, at most
one per robot and step. ``tile_c``, for each cell ``c`` off the goal (where the class allows at
most 64 cells to change), is the least over the robots of the steps before that cell is set
right by that robot: ``reach_c`` (:func:`.tables._transport`: the motions to a pose whose pick
or place targets ``c``; the pick or place comes from such a pose) and then, for a tile to take
away, a place first if the robot is loaded (a pick needs empty hands), the pick, and a place
after it (no robot ends loaded); for a tile to bring, the place, after the fewest steps to get
a tile if the robot holds none: a pick on some cell allowed to change, reached and done, the
motions from there to a pose targeting ``c``. Some robot sets ``c`` right, so ``tile_c`` is at
most the steps left. Each term is at most the steps left in any schedule from the state, so
a dropped state starts no schedule shorter than ``U``. The first occurrence of a state has the
least ``g``, so dropping it loses no shorter occurrence. An exhausted search then proves that
no schedule of the class is shorter than ``U``; stopped early, that none is shorter than
``min(d + 1, U)``.

**Deepening** (:func:`deepen`, asked for where no schedule is known, after the plain search's
share of the time). The search runs again and again below a bound ``U`` that rises. A
run below ``U`` that is exhausted has cut some states (or some robot's moves, on that robot's
term alone); let ``C >= U`` be the least bound among what it cut (``g + h``, or ``g + 1 + dist
+ load`` for a move). A schedule of makespan ``T`` passes only through states with ``g + h <=
T`` and moves with ``g + 1 + dist + load <= T`` (the bounds are admissible), so one with ``T <
C`` had nothing cut and would have been found: none has a makespan below ``C``. The next run
searches below ``C + 1``. A run that reaches a goal has stored every state of every schedule
shorter than its ``U``, each at its least depth, so the first goal it meets is an optimum; a
run that is exhausted with nothing cut proves that the class has no schedule.

**Interchangeable robots.** Robots with one moveset and no goal cell are stored in sorted order
of their values (pose and load). Swapping two such robots maps the schedules from a state onto
the schedules from the swapped state, action for action, with the same makespan (the rules and
the goal treat them alike), so one representative of each set of states decides them all. The
schedule is rebuilt by replaying the path forward from the start with the robots' own
identities (:func:`_unwind`), each step checked by :func:`bille.instances.rules.apply`.

Checked against the Python reference search (:mod:`bille.solvers.bfs`, ``engine=python``) and
the CP-SAT model on tiny instances, and the successors against the Python rules on random
states (tests/test_joint.py).
"""
from __future__ import annotations

import math
import numpy as np

from bille.instances import Instance
from bille.instances.run import Budget, Events

from . import kernel
from .store import NO_BOUND, Outcome, Store, replay, working_arrays
from .cells import Cells
from .tables import Tables, compile_tables



def bytes_per_state(tables: Tables) -> int:
    """Memory one stored state takes at most: its words, its parent, and its share of the hash
    table (at most a quarter full after doubling, 8 bytes a slot)."""
    return 8 * tables.L + 8 + 32


def search(instance: Instance, cells: Cells, budget: Budget, *, U: int | None = None, max_states: int,
           max_steps: int | None = None, events: Events | None = None, tables: Tables | None = None,
           direction: str = "forward") -> Outcome:
    """Breadth-first search within ``cells`` below ``U`` (module docstring); ``budget`` polled
    within layers, ``max_states`` stored states at most, ``max_steps`` layers at most.
    ``direction``: ``forward``, or ``both`` for the search from both ends
    (:mod:`.bidirectional`) where the goal states can be listed."""
    t = tables or compile_tables(instance, cells)
    bound = NO_BOUND if U is None else int(U)
    root = instance.start_state
    row = t.pack(root)
    if t.is_goal(row):
        return Outcome("goal", 0, ids=np.zeros((instance.num_robots, 0), dtype=np.int64), states=1)
    if bound <= 0:
        return Outcome("exhausted", bound, states=1)
    if direction == "both":
        from .bidirectional import MAX_GOALS, goal_rows, search_both
        from .tables import reversible

        goals = goal_rows(instance, t, budget, min(MAX_GOALS, int(max_states) // 4)) \
            if reversible(t) else None
        if goals is not None:
            return search_both(instance, cells, t, goals, budget, U=U, max_states=max_states, max_steps=max_steps,
                               events=events)
    n = instance.width * instance.height
    rows = max(2, int(max_states))
    scratch = working_arrays(t, n, t.kind.shape[1], t.m, t.L)
    store = Store(t, rows, row[None, :], scratch)
    out = Outcome("time", 1)
    while True:
        depth = store.depth
        proved = min(depth + 1, bound)
        if max_steps is not None and depth >= max_steps:
            return _ended(out, "steps", proved, depth, store.counters)
        if budget.expired():  # between layers too: a small layer may end before the kernel looks
            return _ended(out, "cancelled" if budget.cancelled else "time", proved, depth, store.counters)
        got = store.layer(budget, rows, bound)
        if got == "goal":
            out = _ended(out, "goal", depth + 1, depth + 1, store.counters)
            out.ids = _unwind(instance, t, store.states, store.parent, store.goal_row, scratch)
            return out
        if got != "done":
            return _ended(out, got, proved, depth, store.counters)
        lo, hi = store.lo, store.hi
        out.layers.append(hi - lo)
        if events is not None:
            events.progress({"class": cells.key, "depth": depth + 1, "states": hi, "layer": hi - lo,
                             "lower": min(depth + 2, bound), "best": U, "elapsed": budget.elapsed()})
        if lo == hi:
            return _ended(out, "exhausted", bound if U is not None else math.inf, depth + 1, store.counters)


def deepen(instance: Instance, cells: Cells, budget: Budget, *, proved: int, max_states: int,
           events: Events | None = None, tables: Tables, upper: int | None = None) -> Outcome:
    """The search below a rising bound (module docstring, "Deepening"), from ``proved`` (no
    schedule of the class is shorter: the plain search's proof, or the abstraction's bound at the
    start). ``tables`` with the distances. ``upper``: a schedule of that makespan is known, so the
    bound rises to it at most, and a run below it exhausted proves nothing in the class shorter
    (the outcome of :func:`search` below ``upper``). The outcome as :func:`search`'s; a stopped
    run proves at least ``proved``."""
    def below(proved: int) -> int:
        return proved + 1 if upper is None else min(proved + 1, int(upper))

    U = below(proved)
    states = 0
    while True:
        out = search(instance, cells, budget, U=U, max_states=max_states, events=events, tables=tables)
        states += out.states
        if out.stop != "exhausted" or (upper is not None and U >= upper):
            out.proved = max(out.proved, proved)
            out.states = states
            return out
        if out.least_cut >= NO_BOUND:  # nothing cut: every state of the class was searched
            out.proved, out.states = (math.inf if upper is None else int(upper)), states
            return out
        proved = int(out.least_cut)
        if events is not None:
            events.progress({"class": cells.key, "lower": proved, "best": upper, "deepening": U,
                             "elapsed": budget.elapsed()})
        U = below(proved)


def _ended(out: Outcome, stop: str, proved, depth: int, counters: np.ndarray) -> Outcome:
    out.stop, out.proved, out.depth = stop, proved, depth
    out.least_cut = int(counters[kernel.LEAST_CUT])
    out.states = int(counters[kernel.N_STATES])
    out.leaves = int(counters[kernel.LEAVES])
    out.pruned = int(counters[kernel.PRUNED])
    return out


def _unwind(instance: Instance, t: Tables, states, parent, goal_row: int, scratch) -> np.ndarray:
    """The schedule to the state at ``goal_row`` (module docstring)."""
    path = [goal_row]
    while path[-1] != 0:
        path.append(int(parent[path[-1]]))
    return replay(instance, t, [states[r] for r in path[-2::-1]], scratch)



