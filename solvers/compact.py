"""Compaction: every robot's actions as early as the rules allow, in their order.

A schedule from a search over joint states (LaCAM* over whole states, say) is full of waits: a
robot waits at one step and moves at the next, although moving first would have changed
nothing for the others. Compaction moves such an action one step earlier, into its own wait,
whenever the two joint actions so changed are both valid and lead to the same state as before
(so everything after them is unchanged and stays valid); it repeats this, action by action, from
the first step to the last, until no action moves. The makespan never grows, and it shrinks
when the last actions move up. The compacted schedule is still checked by the validator
wherever it is used.
"""
from __future__ import annotations


import numpy as np

from bille.instances import Instance
from bille.instances.metrics import makespan
from bille.instances.run import Budget
from bille.instances.rules import State, Violation, apply, run


def compact(instance: Instance, ids: np.ndarray, budget: Budget | None = None) -> np.ndarray:
    """``ids`` (a valid schedule's action ids, ``int[m, T]``) with each action moved as early as
    it can go (module docstring), trimmed of trailing waits; within ``budget`` (None, or a budget
    without a time limit: until no action moves)."""
    world = instance.world
    ids = np.array(ids, dtype=np.int64, copy=True)
    wait = [g.wait for g in world.graphs]
    states: list[State] = [instance.start_state, *run(world, instance.start_state, ids)]
    if any(isinstance(s, Violation) for s in states):
        raise ValueError("compact: the schedule is not valid")
    moved = True
    while moved and (budget is None or not budget.expired()):
        moved = False
        for t in range(1, ids.shape[1]):
            for i in range(ids.shape[0]):
                u = t  # robot i's action at t goes back through the waits before it, one by one
                while u > 0 and ids[i, u] != wait[i] and ids[i, u - 1] == wait[i]:
                    if not _earlier(world, states, ids, i, u, wait[i]):
                        break
                    u -= 1
                    moved = True
    return ids[:, :makespan(instance, ids)]


def _earlier(world, states, ids, i, u, wait) -> bool:
    """Move robot ``i``'s action at step ``u`` into its wait at ``u - 1`` if both changed joint
    actions are valid and reach the same state as before; True if it moved."""
    before, after = ids[:, u - 1].copy(), ids[:, u].copy()
    before[i], after[i] = ids[i, u], wait
    middle = apply(world, states[u - 1], before)
    if isinstance(middle, Violation):
        return False
    last = apply(world, middle, after)
    if isinstance(last, Violation) or last != states[u + 1]:
        return False
    ids[:, u - 1], ids[:, u] = before, after
    states[u] = middle
    return True
