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
    chosen: list[int] = []

    def extend(i: int, used: frozenset):
        if i == len(sets):
            yield tuple(chosen)
            return
        for a, cells in sets[i]:
            if used.isdisjoint(cells):
                chosen.append(a)
                yield from extend(i + 1, used | cells)
                chosen.pop()

    yield from extend(0, frozenset())
