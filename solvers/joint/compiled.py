"""Small compiled parts of the joint search: the hash table of stored states (open addressing
over row numbers + 1, each entry tagged with its state's hash) and the storing of a batch of
successors, bit counts and the connectivity flood fill (rule 5)."""
from __future__ import annotations

import numpy as np

from bille.instances.jit import jit


@jit
def hash_row(row):  # pragma: no cover - compiled
    h = np.int64(-7046029254386353131)
    for w in row:
        h ^= w
        h *= np.int64(-7046029254386353131)
        h ^= (h >> np.int64(31)) & np.int64(0x1FFFFFFFF)
    return h


@jit
def _same(states, r, row):  # pragma: no cover - compiled
    for k in range(row.shape[0]):
        if states[r, k] != row[k]:
            return False
    return True


# an entry: the row number + 1 in its low bits, above them the high bits of the row's hash (a tag:
# most slots of other rows are passed over without reading their states)
ROW_BITS = 40
ROWS = (np.int64(1) << np.int64(ROW_BITS)) - 1


@jit
def lookup(states, table, row):  # pragma: no cover - compiled
    """The slot of ``row`` in ``table``: its entry if stored, else the empty slot where it goes
    (an entry: the tag of its hash and the row number + 1; :func:`row_of` reads the number back)."""
    return _find(states, table, row, hash_row(row))


@jit
def _find(states, table, row, h):  # pragma: no cover - compiled
    mask = table.shape[0] - 1
    slot = h & mask
    high = (h >> np.int64(ROW_BITS)) << np.int64(ROW_BITS)
    while True:
        e = table[slot]
        if e == 0 or ((e & ~ROWS) == high and _same(states, (e & ROWS) - 1, row)):
            return slot
        slot = (slot + 1) & mask


@jit
def row_of(entry):  # pragma: no cover - compiled
    """The row number of a table entry (-1 for an empty slot)."""
    return (entry & ROWS) - 1


@jit
def rehash(states, n, size):  # pragma: no cover - compiled
    """A table of ``size`` slots (a power of two) holding rows ``0..n-1``."""
    table = np.zeros(size, dtype=np.int64)
    mask = size - 1
    for r in range(n):
        h = hash_row(states[r])
        slot = h & mask
        while table[slot] != 0:
            slot = (slot + 1) & mask
        table[slot] = ((h >> np.int64(ROW_BITS)) << np.int64(ROW_BITS)) | (r + 1)
    return table


@jit
def popcount(w):  # pragma: no cover - compiled
    c = 0
    while w != 0:
        w &= w - 1
        c += 1
    return c


@jit
def connected(tiles, width, height, total, anchor, stack, seen, stamp):  # pragma: no cover - compiled
    """Whether the ``total`` tiles of ``tiles`` form one 4-connected piece (flood from ``anchor``)."""
    if total == 0:
        return False
    if tiles[anchor] == 0:
        anchor = -1
        for c in range(tiles.shape[0]):
            if tiles[c] != 0:
                anchor = c
                break
    top = 0
    stack[0] = anchor
    seen[anchor] = stamp
    count = 1
    while top >= 0:
        c = stack[top]
        top -= 1
        x = c % width
        y = c // width
        for d in range(4):
            nx, ny = x, y
            if d == 0:
                ny = y - 1
            elif d == 1:
                nx = x + 1
            elif d == 2:
                ny = y + 1
            else:
                nx = x - 1
            if nx < 0 or ny < 0 or nx >= width or ny >= height:
                continue
            nc = ny * width + nx
            if tiles[nc] != 0 and seen[nc] != stamp:
                seen[nc] = stamp
                count += 1
                top += 1
                stack[top] = nc
    return count == total


@jit
def store(pend, n, links, hs, states, parent, table, counters, touch):  # pragma: no cover - compiled
    """Store the new rows among ``pend[:n]`` in order, as the search stores each one it meets
    (``links[i]``: twice the row of the state it succeeds, plus 1 for a goal state): their counts
    in ``counters`` (states, table entries). Returns the row of the first goal state stored, the
    rows after it left unstored, or -1.

    The rows are looked up after two passes that only read: their slots, then the first state
    each slot names. The reads of one pass do not wait for each other, so the memory is fetched
    for all the rows at once instead of one miss after another; the lookups then find it cached."""
    mask = table.shape[0] - 1
    acc = np.int64(0)
    for i in range(n):
        h = hash_row(pend[i])
        hs[i] = h
        acc += table[h & mask]
    for i in range(n):
        e = table[hs[i] & mask]
        if e != 0:
            acc += states[(e & ROWS) - 1, 0]
    touch[0] = acc  # kept, so that the reads are not optimised away
    for i in range(n):
        slot = _find(states, table, pend[i], hs[i])
        if table[slot] != 0:
            continue
        r = counters[0]
        states[r, :] = pend[i]
        parent[r] = links[i] >> 1
        table[slot] = ((hs[i] >> np.int64(ROW_BITS)) << np.int64(ROW_BITS)) | (r + 1)
        counters[0] = r + 1
        counters[1] += 1
        if links[i] & 1:
            return r
    return -1


@jit
def sort_groups(vals, sym_start, sym_idx):  # pragma: no cover - compiled
    """The values of each group of interchangeable robots put in sorted order, in place."""
    for s in range(sym_start.shape[0] - 1):
        for x in range(sym_start[s] + 1, sym_start[s + 1]):
            for y in range(x, sym_start[s], -1):
                ia = sym_idx[y - 1]
                ib = sym_idx[y]
                if vals[ia] > vals[ib]:
                    tmp = vals[ia]
                    vals[ia] = vals[ib]
                    vals[ib] = tmp
                else:
                    break


UNREACHED = 255  # the abstraction's distance where no abstract goal is reached


@jit
def robot_index(lv, order, blocks, binom):  # pragma: no cover - compiled
    """The index of the robots' local values ``lv`` (each group of interchangeable robots sorted)
    among the abstraction's robot parts (:class:`.abstraction.Abstraction`): block by block, a
    group's sorted values ranked as a multiset (the combinatorial number system over ``v_j + j``)."""
    idx = np.int64(0)
    for b in range(blocks.shape[0]):
        start, r, size = blocks[b, 0], blocks[b, 1], blocks[b, 2]
        rank = np.int64(0)
        for j in range(r):
            rank += binom[lv[order[start + j]] + j, j + 1]
        idx = idx * size + rank
    return idx


@jit
def abstract_distance(vals, row, nR, gid, local, order, blocks, binom, gmask, size, dist):  # pragma: no cover
    """The abstract distance of the state with robot values ``vals`` (``pose * 2 + carrying``,
    each group of interchangeable robots sorted) and the tiles of the packed ``row``
    (:class:`.abstraction.Abstraction`)."""
    for i in range(vals.shape[0]):
        if local[gid[i], vals[i] >> 1] < 0:
            return UNREACHED
    idx = np.int64(0)
    for b in range(blocks.shape[0]):  # robot_index of the local values, read in place
        start, r, bsize = blocks[b, 0], blocks[b, 1], blocks[b, 2]
        rank = np.int64(0)
        for j in range(r):
            i = order[start + j]
            rank += binom[2 * local[gid[i], vals[i] >> 1] + (vals[i] & 1) + j, j + 1]
        idx = idx * bsize + rank
    for j in range(size.shape[0]):
        c = 0
        for w in range(gmask.shape[1]):
            c += popcount(row[nR + w] & gmask[j, w])
        idx = idx * (size[j] + 1) + c
    return dist[idx]
