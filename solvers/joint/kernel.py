"""The compiled successor function and layered breadth-first search over packed joint states.

A joint state is a row of ``L`` machine words (int64): first the robots, each ``pose * 2 +
carrying`` in ``rbits`` bits, ``rpw`` to a word; then the tiles on the cells allowed to change,
one bit each, 63 to a word (the other cells keep their start's tiles, :mod:`.tables`). The
successors of a state are its joint actions under docs/rules.md, "One time step", built by
backtracking over the robots from the compiled pose tables (:mod:`bille.instances.posegraph`),
the same tables :func:`bille.instances.rules.apply` reads:

1. precondition, 2. workspace and 4. support per robot (the candidates; a robot's new feet
   cannot be picked from under it nor placed on by another in the same step without a collision,
   so the tiles before the step decide rule 4, as in :func:`bille.instances.successors.candidate_actions`);
3. collision while choosing each robot's action (:func:`.marks.fits`): disjoint collision sets, or the
   classic convention (vertex, swap, exclusive pick/place targets);
5. connectivity of the new tiles at the leaf (:func:`connected`).

The search keeps every state found in ``states`` (a layer is a range of rows), a parent index per
state, and an open-addressing hash table of row numbers + 1 (:mod:`.compiled`). Successors are
stored 128 at a time, in the order met (:func:`.compiled.store`: their memory fetched at once),
and all of them before the kernel returns. :func:`expand` works through a range
of rows and stops after ``work`` steps of the backtracking, keeping its place in ``cursor`` so
the caller can look at its budget between calls and go on; it also stops when the table is half
full (the caller doubles it, :func:`rehash`) or the rows run out.

The same function, with ``mode`` :data:`FIND` or :data:`COLLECT`, matches a given successor (to
rebuild a schedule) or lists every successor (the parity test against the Python rules).

Robots listed in one symmetry group (same moveset, no goal cell) are interchangeable: a joint
state is stored with their values sorted (:mod:`.search` proves this keeps the search exact).

``dist[i, pose]`` is a lower bound on the steps robot ``i`` needs from ``pose`` to its goal
cell, and ``U`` an upper bound to search below: a state at depth ``g`` with ``g + h >= U`` is
not stored (:mod:`.search` proves ``h`` admissible); ``counters[LEAST_CUT]`` keeps the least
``g + h`` (or, for a robot's move cut on its own, ``g + dist + load``) of what was cut.
"""
from __future__ import annotations

import numpy as np

from .compiled import abstract_distance, jit, connected, popcount, sort_groups, store
from .marks import fits, fits_bits, release, unmark

WAIT, MOTION, PICK, PLACE = 0, 1, 2, 3  # bille.instances.moveset.Kind
SEARCH, FIND, COLLECT = 0, 1, 2  # modes of expand
DONE, GOAL, PAUSED, FULL, GROW = 0, 1, 2, 3, 4  # what expand returns
# counters[]: states stored, entries in the hash table, goal row, leaves (joint actions valid),
# states cut below U, the least bound among what was cut
N_STATES, N_TABLE, GOAL_ROW, LEAVES, PRUNED, LEAST_CUT = 0, 1, 2, 3, 4, 5
TILE_BITS = 63


@jit
def _goal(r, counters, cursor, parent):  # pragma: no cover - compiled
    """Whether a goal state was stored (at row ``r``, -1 if none): noted, and the search's place
    set after the state it succeeds."""
    if r < 0:
        return False
    counters[GOAL_ROW] = r
    cursor[0] = parent[r] + 1
    cursor[2] = 0
    return True


@jit
def expand(mode, states, parent, table, counters, cursor, hi, work, max_rows, depth, U,
           # the instance's tables (.tables.Tables)
           m, rbits, rpw, nR, nT, width, height, classic, gid, succ, coll, carry, carry_ok, need, target, kind,
           bit_of, cell_of, fixed, fixed_count, anchor, goal_words, dist, sym_start, sym_idx, masks, W, reach, fetch,
           pdb_local, pdb_order, pdb_blocks, pdb_binom, pdb_gmask, pdb_size, pdb_dist,
           # scratch, allocated once by the caller
           tiles, occ, endocc, startocc, tgt, cand, ncand, choice, pose, carrying, after, vals, row, seen, stack,
           stamp, usedw, pend, pgoal, hs, touch,
           # FIND: the successor to match (its canonical row) and where its joint action goes;
           # COLLECT: rows and joint actions of every successor (raw, not canonical)
           match, out_actions, out_rows):  # pragma: no cover - compiled
    L = nR + nT
    bits = W > 0 and not classic  # rule 3 by the collision sets' bit masks (.tables)
    rmask = (np.int64(1) << np.int64(rbits)) - 1
    big = U < (1 << 40)
    pos = cursor[0]
    steps = 0
    npend = 0  # successors met but not yet stored (.compiled.store), at most PENDING; none between calls
    while pos < hi:
        if cursor[2] == 0 and steps >= work:  # between two states: nothing marked, nothing to undo
            got = _goal(store(pend, npend, pgoal, hs, states, parent, table, counters, touch), counters, cursor, parent)
            cursor[0] = cursor[0] if got else pos
            return GOAL if got else PAUSED
        # ---- the state at row pos: robots, tiles, each robot's candidate actions ----------------
        steps += 1  # a state without successors costs its decoding too
        src = states[pos]
        for i in range(m):
            v = (src[i // rpw] >> np.int64((i % rpw) * rbits)) & rmask
            pose[i] = v >> 1
            carrying[i] = v & 1
        for b in range(cell_of.shape[0]):
            tiles[cell_of[b]] = (src[nR + b // TILE_BITS] >> np.int64(b % TILE_BITS)) & 1
        dead = False
        for i in range(m):
            g = gid[i]
            p = pose[i]
            c = carrying[i]
            n = 0
            for a in range(kind.shape[1]):
                s = succ[g, p, a]
                if s < 0 or (c == 1 and not carry_ok[g, p, a]):
                    continue
                k = kind[g, a]
                t = target[g, p, a]
                if k == PICK:
                    if c == 1 or t < 0 or tiles[t] == 0 or bit_of[t] < 0:
                        continue
                    load = 1
                elif k == PLACE:
                    if c == 0 or t < 0 or tiles[t] == 1 or bit_of[t] < 0:
                        continue
                    load = 0
                else:
                    if tiles[need[g, p, a, 0]] == 0 or tiles[need[g, p, a, 1]] == 0:
                        continue
                    load = c
                if big and depth + 1 + dist[i, s] + load >= U:
                    counters[LEAST_CUT] = min(counters[LEAST_CUT], depth + 1 + dist[i, s] + load)
                    continue
                cand[i, n] = a
                n += 1
            ncand[i] = n
            if n == 0:
                dead = True
        if dead:  # a robot with nothing to do: no successor
            cursor[2] = 0
            pos += 1
            continue
        if classic:
            for i in range(m):
                startocc[pose[i]] = i + 1
        if cursor[2] == 1:  # resuming inside this state: mark the robots chosen so far again
            level = cursor[1]
            for i in range(level + 1):
                if bits:
                    if choice[i] >= 0:
                        fits_bits(usedw, i, masks[gid[i], pose[i], cand[i, choice[i]], carrying[i]])
                elif choice[i] >= 0:
                    fits(i, cand[i, choice[i]], gid[i], pose[i], carrying[i], classic, coll, carry, succ, target,
                          occ, endocc, startocc, tgt, after)
        else:
            level = 0
            choice[0] = -1
        for w in range(W):
            usedw[0, w] = 0
        # ---- backtracking over the robots' candidates (rule 3 as they are chosen) ---------------
        while level >= 0:
            if steps >= work or counters[N_STATES] + npend >= max_rows or \
                    2 * (counters[N_TABLE] + npend) >= table.shape[0]:  # the caller may grow the table, then resume
                release(level, m, bits, classic, cand, choice, gid, pose, carrying, coll, carry, succ, target, occ,
                         endocc, tgt, startocc)
                got = _goal(store(pend, npend, pgoal, hs, states, parent, table, counters, touch), counters, cursor,
                            parent)
                npend = 0
                if got:
                    return GOAL
                cursor[0] = pos
                cursor[1] = level
                cursor[2] = 1
                if counters[N_STATES] >= max_rows:
                    return FULL
                if 2 * counters[N_TABLE] >= table.shape[0]:
                    return GROW
                return PAUSED
            steps += 1
            g = gid[level]
            p = pose[level]
            c = carrying[level]
            if choice[level] >= 0 and not bits:
                unmark(level, cand[level, choice[level]], g, p, c, classic, coll, carry, succ, target, occ, endocc,
                        tgt)
            choice[level] += 1
            ok = False
            while choice[level] < ncand[level]:
                a = cand[level, choice[level]]
                if bits:
                    if fits_bits(usedw, level, masks[g, p, a, c]):
                        ok = True
                        break
                elif fits(level, a, g, p, c, classic, coll, carry, succ, target, occ, endocc, startocc, tgt,
                           after):
                    ok = True
                    break
                choice[level] += 1
            if not ok:
                choice[level] = -1
                level -= 1
                continue
            if level < m - 1:
                level += 1
                choice[level] = -1
                continue
            # ---- a leaf: one joint action, rules 1-4 hold; the new tiles, rule 5 ---------------
            for k in range(L):
                row[k] = 0
            for k in range(nT):
                row[nR + k] = src[nR + k]
            changed = False
            for i in range(m):
                gi = gid[i]
                a = cand[i, choice[i]]
                k = kind[gi, a]
                load = carrying[i]
                if k == PICK or k == PLACE:
                    b = bit_of[target[gi, pose[i], a]]
                    bit = np.int64(1) << np.int64(b % TILE_BITS)
                    if k == PICK:
                        row[nR + b // TILE_BITS] &= ~bit
                        load = 1
                    else:
                        row[nR + b // TILE_BITS] |= bit
                        load = 0
                    changed = True
                vals[i] = 2 * np.int64(succ[gi, pose[i], a]) + load
            if changed:
                total = fixed_count
                for k in range(nT):
                    total += popcount(row[nR + k])
                for b in range(cell_of.shape[0]):
                    tiles[cell_of[b]] = (row[nR + b // TILE_BITS] >> np.int64(b % TILE_BITS)) & 1
                stamp[0] += 1
                joined = connected(tiles, width, height, total, anchor, stack, seen, stamp[0])
                for b in range(cell_of.shape[0]):
                    tiles[cell_of[b]] = (src[nR + b // TILE_BITS] >> np.int64(b % TILE_BITS)) & 1
                if not joined:
                    continue
            counters[LEAVES] += 1
            if mode == COLLECT:
                r = counters[N_STATES]
                if r < out_rows.shape[0]:
                    for i in range(m):
                        out_actions[r, i] = cand[i, choice[i]]
                    for i in range(m):
                        w = i // rpw
                        out_rows[r, w] |= vals[i] << np.int64((i % rpw) * rbits)
                    for k in range(nT):
                        out_rows[r, nR + k] = row[nR + k]
                counters[N_STATES] = r + 1
                continue
            # the admissible bound of the new state (.search): each robot's walk and load, the tiles
            h = 0
            if big:
                for i in range(m):
                    e = dist[i, vals[i] >> 1] + (vals[i] & 1)
                    if e > h:
                        h = e
                mis = 0
                for k in range(nT):
                    mis += popcount(row[nR + k] ^ goal_words[k])
                e = (mis + m - 1) // m if m > 0 else 0
                if e > h:
                    h = e
                if reach.shape[0] > 0 and mis > 0:  # each cell off the goal: its pick or place (.tables)
                    for b in range(cell_of.shape[0]):
                        has = (row[nR + b // TILE_BITS] >> np.int64(b % TILE_BITS)) & 1
                        want = (goal_words[b // TILE_BITS] >> np.int64(b % TILE_BITS)) & 1
                        if has == want:
                            continue
                        best = 1 << 30
                        for i in range(m):
                            gi = gid[i]
                            q = vals[i] >> 1
                            if has == 1:  # a tile to take away: reach, a place first if loaded, pick, a place after
                                e = reach[b, gi, q] + (vals[i] & 1) + 2
                            elif (vals[i] & 1) == 1:  # a tile to bring, and this robot holds one: reach, place
                                e = reach[b, gi, q] + 1
                            else:  # fetch one first: reach a pick, pick, carry it there, place
                                e = fetch[b, gi, q]
                            if e < best:
                                best = e
                        if best > h:
                            h = best
                if depth + 1 + h >= U:
                    counters[PRUNED] += 1
                    counters[LEAST_CUT] = min(counters[LEAST_CUT], depth + 1 + h)
                    continue
            sort_groups(vals, sym_start, sym_idx)  # the robots of a symmetry group in sorted order
            if big and pdb_dist.shape[0] > 0:  # the abstraction's distance, of the sorted values (.abstraction)
                e = abstract_distance(vals, row, nR, gid, pdb_local, pdb_order, pdb_blocks, pdb_binom, pdb_gmask, pdb_size,
                                      pdb_dist)
                if depth + 1 + e >= U:
                    counters[PRUNED] += 1
                    counters[LEAST_CUT] = min(counters[LEAST_CUT], depth + 1 + e)
                    continue
            for i in range(m):
                row[i // rpw] |= vals[i] << np.int64((i % rpw) * rbits)
            if mode == FIND:
                same = True
                for k in range(L):
                    if row[k] != match[k]:
                        same = False
                        break
                if same:
                    for i in range(m):
                        out_actions[0, i] = cand[i, choice[i]]
                    release(level, m, bits, classic, cand, choice, gid, pose, carrying, coll, carry, succ, target,
                             occ, endocc, tgt, startocc)
                    return GOAL
                continue
            goal = True
            for k in range(nT):
                if row[nR + k] != goal_words[k]:
                    goal = False
            if goal:
                for i in range(m):
                    if (vals[i] & 1) != 0 or dist[i, vals[i] >> 1] != 0:
                        goal = False
                        break
            for k in range(L):  # stored when pend is full, in the order met
                pend[npend, k] = row[k]
            pgoal[npend] = 2 * pos + goal
            npend += 1
            if npend == pend.shape[0]:
                npend = 0
                if _goal(store(pend, pend.shape[0], pgoal, hs, states, parent, table, counters, touch), counters,
                         cursor, parent):
                    release(level, m, bits, classic, cand, choice, gid, pose, carrying, coll, carry, succ, target,
                             occ, endocc, tgt, startocc)
                    return GOAL
        if classic:
            for i in range(m):
                startocc[pose[i]] = 0
        cursor[2] = 0
        pos += 1
    if _goal(store(pend, npend, pgoal, hs, states, parent, table, counters, touch), counters, cursor, parent):
        return GOAL
    cursor[0] = pos
    return DONE
