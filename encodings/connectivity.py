"""Connectivity of the tiles (docs/rules.md, rule 5) in the time-expanded model: the eager encoding
(layered reachability from the first tile) and the lazy one (cuts added when a solution breaks it).
"""
from __future__ import annotations

import numpy as np

from bille.instances import Instance
from bille.instances.grid import HEADING_VECTORS, components, is_connected


def eager_connectivity(builder) -> None:
    """Layered reachability from the first tile (in cell order) at every inner time point, added
    to the model of the ``builder`` (:class:`.model._Builder`): ``root``, ``none_before``
    and ``reach`` variables, unary distance labels of at most ``|goal tiles| - 1`` layers. Sound
    and complete: tiles on the grid plus tiles carried number ``|goal tiles|`` at every time, so
    a connected set has at most that many tiles, and each of them is within ``|goal tiles| - 1``
    neighbour steps of the root; a disconnected set has a tile no layer reaches."""
    m, W = builder.m, builder.world.width
    cells = builder.cells
    layers = max(1, min(len(cells), int(builder.inst.goal_tiles.sum())) - 1)
    nbrs = {c: [c + dy * W + dx for dx, dy in HEADING_VECTORS
                if 0 <= c % W + dx < W and 0 <= c // W + dy < builder.world.height and builder.cand[c + dy * W + dx]]
            for c in cells}
    for t in range(1, builder.T):
        builder.tick()
        lits = [builder.tile(t, c) for c in cells]
        if all(abs(l) == m.true for l in lits):  # the tiles are known at t: check them here
            mask = np.zeros(builder.world.width * builder.world.height, dtype=bool)
            mask[[c for c, l in zip(cells, lits) if l == m.true]] = True
            if not is_connected(mask, builder.world.width, builder.world.height):
                m.clauses.append([-m.true])
            continue
        none_before = m.true  # no tile in the cells before this one
        reach_prev = {}
        for c in cells:
            tile = builder.tile(t, c)
            root = m.var(("root", t, c))
            m.clauses += [[-root, tile], [-root, none_before], [-tile, -none_before, root]]
            nb = m.var(("none_before", t, c))
            m.clauses += [[-nb, none_before], [-nb, -tile], [-none_before, tile, nb]]
            none_before = nb
            reach_prev[c] = root
        for k in range(1, layers + 1):
            reach = {}
            for c in cells:
                r = m.var(("reach", t, c, k))
                m.clauses.append([-r, reach_prev[c]] + [reach_prev[n] for n in nbrs[c]])
                m.clauses.append([-r, builder.tile(t, c)])
                reach[c] = r
            reach_prev = reach
        for c in cells:
            m.clauses.append([-builder.tile(t, c), reach_prev[c]])


def connectivity_cuts(model, instance: Instance, masks: list[np.ndarray]) -> list[list[int]]:
    """Clauses excluding the disconnected tile sets of a solution, at every inner time point.

    For a component ``S`` of a disconnected step and a tile ``c'`` of another component: not
    (all of ``S`` tiles, none of ``S``'s neighbour cells a tile, and ``c'`` a tile). True of every
    connected tile set (if all of ``S`` are tiles and none of its neighbours, ``S`` is a whole
    component, and a tile outside it makes a second one), false of this one: a cut never removes
    a valid schedule.
    """
    W, H = instance.width, instance.height
    cuts, seen = [], set()
    for comps in _split(masks, W, H):
        count = len(comps)
        for k, S in enumerate(comps):
            other = comps[(k + 1) % count][0]
            border, in_s = set(), set(S)  # the neighbours of a component are empty cells
            for c in S:
                for dx, dy in HEADING_VECTORS:
                    x, y = c % W + dx, c // W + dy
                    if 0 <= x < W and 0 <= y < H and y * W + x not in in_s:
                        border.add(y * W + x)
            key = (tuple(S), tuple(sorted(border)), other)
            if key in seen:
                continue
            seen.add(key)
            for t in range(1, model.T):
                lits = [-model.tile[(t, c)] for c in S if (t, c) in model.tile]
                lits += [model.tile[(t, c)] for c in border if (t, c) in model.tile]
                if (t, other) in model.tile:
                    lits.append(-model.tile[(t, other)])
                cuts.append(lits)
    return cuts


def separator_cuts(model, instance: Instance, masks: list[np.ndarray], candidates: np.ndarray) -> list[list[int]]:
    """Minimal vertex-separator cuts excluding the disconnected tile sets of a solution.

    For two components ``A`` and ``B`` of a disconnected step, with cells ``a`` in ``A`` and ``b``
    in ``B``: let ``N(A)`` be the candidate cells next to ``A`` (all empty in this solution),
    ``Z`` the candidate cells reachable from ``b`` without entering ``A`` or ``N(A)``, and ``N``
    the cells of ``N(A)`` next to ``Z`` (a minimal separator of ``a`` and ``b``). Cut: not ``a``,
    or not ``b``, or some cell of ``N`` holds a tile.

    Why it holds for every connected tile set: if ``a`` and ``b`` both hold tiles and the set is
    connected, a path of tiles joins them through candidate cells (only candidate cells ever hold
    tiles). Follow it backwards from ``b``: it starts in ``Z`` (``b`` is in ``Z``) and ends at
    ``a``, outside ``Z``, so it leaves ``Z`` at some cell; a cell next to ``Z`` that is not in
    ``Z`` is, by the definition of ``Z``, in ``N(A)``, hence in ``N``; so some cell of ``N`` holds
    a tile. It excludes the solution: there ``a`` and ``b`` hold tiles and ``N`` (next to ``A``,
    not in ``A``) is empty. Separators are short (one to a few cells on thin structures), so the
    clauses propagate well; they are added at every inner time point (the argument holds at each).
    """
    W, H = instance.width, instance.height
    cuts, seen = [], set()

    def nbrs(c):
        x, y = c % W, c // W
        for dx, dy in HEADING_VECTORS:
            if 0 <= x + dx < W and 0 <= y + dy < H and candidates[c + dy * W + dx]:
                yield c + dy * W + dx

    for comps in _split(masks, W, H):
        for k, A in enumerate(comps):
            for B in (comps[:k] + comps[k + 1:])[:2]:
                a, b = A[0], B[0]
                in_a = set(A)
                around = {n for c in A for n in nbrs(c) if n not in in_a}
                zone, stack = {b}, [b]
                while stack:
                    c = stack.pop()
                    for n in nbrs(c):
                        if n not in zone and n not in around and n not in in_a:
                            zone.add(n)
                            stack.append(n)
                sep = sorted(n for n in around if any(z in zone for z in nbrs(n)))
                key = (a, b, tuple(sep))
                if key in seen:
                    continue
                seen.add(key)
                for t in range(1, model.T):
                    lits = [model.tile[(t, c)] for c in sep if (t, c) in model.tile]
                    for c in (a, b):
                        if (t, c) in model.tile:
                            lits.append(-model.tile[(t, c)])
                    cuts.append(lits)
    return cuts


def _split(masks: list[np.ndarray], W: int, H: int):
    """The cells of each component, for every mask of more than one component."""
    for mask in masks:
        labels, count = components(mask, W, H)
        if count > 1:
            yield [np.flatnonzero(labels == k + 1).tolist() for k in range(count)]
