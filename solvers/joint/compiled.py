"""Small compiled parts of the joint search: the hash table of stored states (open addressing
over row numbers + 1), bit counts and the connectivity flood fill (rule 5)."""
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


@jit
def lookup(states, table, row):  # pragma: no cover - compiled
    """The slot of ``row`` in ``table``: its entry if stored, else the empty slot where it goes."""
    mask = table.shape[0] - 1
    slot = hash_row(row) & mask
    while True:
        e = table[slot]
        if e == 0 or _same(states, e - 1, row):
            return slot
        slot = (slot + 1) & mask


@jit
def rehash(states, n, size):  # pragma: no cover - compiled
    """A table of ``size`` slots (a power of two) holding rows ``0..n-1``."""
    table = np.zeros(size, dtype=np.int64)
    mask = size - 1
    for r in range(n):
        slot = hash_row(states[r]) & mask
        while table[slot] != 0:
            slot = (slot + 1) & mask
        table[slot] = r + 1
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
