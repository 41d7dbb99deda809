"""The joint actions of a state: each robot's own candidate actions and their combinations whose
collision sets are disjoint (docs/rules.md, "One time step").

Shared by the searches over whole states (tiles, poses, loads): the brute-force reference
search and LaCAM* over whole states. Both filters only save work: every joint action they yield
is still judged by :func:`~bille.instances.rules.apply`.
"""
from __future__ import annotations

import numpy as np

from .instance import Instance
from .moveset import Kind
from .rules import State

WAIT, MOTION, PICK, PLACE = (int(k) for k in (Kind.WAIT, Kind.MOTION, Kind.PICK, Kind.PLACE))


def candidate_actions(instance: Instance, state: State, i: int) -> list[int]:
    """Robot ``i``'s actions that pass its own rules 1, 2 and 4 on the current tiles.

    Rules between robots are left to :func:`~bille.instances.rules.apply`; a robot's new foot
    cannot become a tile by another robot's action in the same step without a collision, so this
    filter loses no valid joint action.
    """
    g = instance.world.graphs[i]
    p, carrying, tiles = state.poses[i], bool(state.carrying[i]), state.tiles
    kind, target = g.kind, g.target[p]
    ok = g.succ[p] >= 0
    if carrying:
        ok &= g.carry_ok[p]
    has = tiles[target]  # (a target of -1, on no pick or place, reads a cell that is not used)
    ok &= (kind != PICK) | (not carrying and has)
    ok &= (kind != PLACE) | (carrying and ~has)
    walks = (kind == WAIT) | (kind == MOTION)
    ok &= ~walks | tiles[g.need[p]].all(axis=1)
    return np.flatnonzero(ok).tolist()


def collision_cells(instance: Instance, state: State, i: int, a: int) -> frozenset[int]:
    """Robot ``i``'s collision set of action ``a`` from ``state`` (carried-tile cells included
    when it carries)."""
    g, p = instance.world.graphs[i], state.poses[i]
    cells = set(g.coll[p, a].tolist())
    if state.carrying[i]:
        cells |= set(g.carry[p, a].tolist())
    cells.discard(-1)
    return frozenset(cells)


def disjoint_products(instance: Instance, state: State, options: list[list[int]]):
    """Joint actions from per-robot ``options`` whose collision sets are pairwise disjoint
    (rule 3), by backtracking."""
    sets = [[(a, collision_cells(instance, state, i, a)) for a in opts] for i, opts in enumerate(options)]

    def admit(i, item, used, chosen):
        return used | item[1] if used.isdisjoint(item[1]) else None

    for chosen in backtrack(sets, admit, frozenset()):
        yield tuple(a for a, _ in chosen)


def backtrack(options: list[list], admit, start):
    """Every tuple of one item of each ``options[i]`` in turn that ``admit`` lets through:
    ``admit(i, item, context, chosen)`` gives the context for the next robot, or None to refuse
    ``item`` after ``chosen[:i]``. Without recursion, so a thousand robots need no deeper stack.

    >>> list(backtrack([[1, 2], [1, 2]], lambda i, x, used, chosen: None if x in used else used | {x}, frozenset()))
    [(1, 2), (2, 1)]
    """
    m = len(options)
    if m == 0:
        yield ()
        return
    context = [start] + [None] * m
    at, chosen, i = [0] * m, [None] * m, 0
    while i >= 0:
        if at[i] == len(options[i]):
            at[i] = 0
            i -= 1
            if i >= 0:
                at[i] += 1
            continue
        item = options[i][at[i]]
        after = admit(i, item, context[i], chosen)
        if after is None:
            at[i] += 1
            continue
        chosen[i] = item
        if i == m - 1:
            yield tuple(chosen)
            at[i] += 1
        else:
            context[i + 1] = after
            i += 1
