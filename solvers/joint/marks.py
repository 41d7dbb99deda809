"""Rule 3 while the kernel's backtracking chooses the robots' actions one by one (:mod:`.kernel`):
the cells each chosen action marks, tested and undone as the choice moves on."""
from __future__ import annotations

from .compiled import jit


@jit
def fits_bits(usedw, level, mask):  # pragma: no cover - compiled
    """Rule 3 by bit masks: whether an action's collision set ``mask`` (its words) shares no cell
    with the sets chosen below ``level`` (``usedw[level]``); if so, ``usedw[level + 1]`` gets
    their union."""
    for w in range(mask.shape[0]):
        if usedw[level, w] & mask[w] != 0:
            return False
    for w in range(mask.shape[0]):
        usedw[level + 1, w] = usedw[level, w] | mask[w]
    return True


@jit
def fits(i, a, g, p, c, classic, coll, carry, succ, target, occ, endocc, startocc, tgt, after):  # pragma: no cover
    """Whether robot ``i``'s action ``a`` is free of collisions with the robots chosen before it
    (rule 3, or the classic convention); marks its cells if so."""
    if classic:
        v = succ[g, p, a]
        t = target[g, p, a]
        if endocc[v] != 0:
            return False
        j = startocc[v] - 1
        if j >= 0 and j < i and after[j] == p:
            return False
        if tgt[p] != 0 or tgt[v] != 0:
            return False
        if t >= 0 and (startocc[t] != 0 or endocc[t] != 0 or tgt[t] != 0):
            return False
        endocc[v] = i + 1
        if t >= 0:
            tgt[t] = i + 1
        after[i] = v
        return True
    for k in range(coll.shape[3]):
        cell = coll[g, p, a, k]
        if cell >= 0 and occ[cell] != 0 and occ[cell] != i + 1:
            return False
    if c:
        for k in range(carry.shape[3]):
            cell = carry[g, p, a, k]
            if cell >= 0 and occ[cell] != 0 and occ[cell] != i + 1:
                return False
    for k in range(coll.shape[3]):
        cell = coll[g, p, a, k]
        if cell >= 0:
            occ[cell] = i + 1
    if c:
        for k in range(carry.shape[3]):
            cell = carry[g, p, a, k]
            if cell >= 0:
                occ[cell] = i + 1
    after[i] = succ[g, p, a]
    return True


@jit
def unmark(i, a, g, p, c, classic, coll, carry, succ, target, occ, endocc, tgt):  # pragma: no cover
    if classic:
        endocc[succ[g, p, a]] = 0
        t = target[g, p, a]
        if t >= 0:
            tgt[t] = 0
        return
    for k in range(coll.shape[3]):
        cell = coll[g, p, a, k]
        if cell >= 0 and occ[cell] == i + 1:
            occ[cell] = 0
    if c:
        for k in range(carry.shape[3]):
            cell = carry[g, p, a, k]
            if cell >= 0 and occ[cell] == i + 1:
                occ[cell] = 0


@jit
def release(level, m, bits, classic, cand, choice, gid, pose, carrying, coll, carry, succ, target, occ, endocc, tgt,
             startocc):  # pragma: no cover - compiled
    """Leave a state in the middle of its backtracking: every mark of the robots chosen so far
    undone (cell marks; the bit masks need none), so the scratch is clean for the next state."""
    for i in range(level + 1):
        if choice[i] >= 0 and not bits:
            unmark(i, cand[i, choice[i]], gid[i], pose[i], carrying[i], classic, coll, carry, succ, target, occ,
                    endocc, tgt)
    if classic:
        for i in range(m):
            startocc[pose[i]] = 0
