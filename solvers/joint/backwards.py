"""The breadth-first search backwards over an abstraction's table, compiled
(:mod:`.abstraction`: the abstract world, why its distances bound the steps left, and the
table's index): the abstract goals at distance 0, then layer by layer every state one joint
step before a state of the layer, each step checked by the abstract rules (the robots' steps
read backwards from the pose tables, their collision sets, the groups' counts before the step)."""
from __future__ import annotations

import numpy as np

from bille.instances.jit import jit

from . import kernel
from .compiled import UNREACHED, robot_index, sort_groups
from .marks import fits_bits


@jit
def goals(dist, m, V, gid, glob, front, goal_cell, cgoal, NC, order, blocks, binom, sym_start,
           sym_idx):  # pragma: no cover - compiled
    """Every abstract goal at distance 0: no load, each robot with a goal cell on it."""
    total = np.int64(1)
    for i in range(m):
        total *= V[i] // 2
    lv = np.zeros(m, np.int64)
    for code in range(total):
        r = code
        ok = True
        for i in range(m - 1, -1, -1):
            half = V[i] // 2
            lp = r % half
            r //= half
            if goal_cell[i] >= 0 and front[gid[i], glob[gid[i], lp]] != goal_cell[i]:
                ok = False
                break
            lv[i] = 2 * lp
        if ok:
            sort_groups(lv, sym_start, sym_idx)
            dist[robot_index(lv, order, blocks, binom) * NC + cgoal] = 0


@jit
def layer(dist, level, frontier, lo, hi, out, nout, m, gid, local, rstart, rp, ra, kind, target, carry_ok, masks,
           W, group, size, mult, k, sym_start, sym_idx, order, blocks, binom):  # pragma: no cover - compiled
    """The states one step before those of ``frontier[lo:hi]`` (at ``level``) that have no distance
    yet get ``level + 1`` and are listed in ``out`` from ``nout`` on. Stops before a state whose
    steps backwards might not fit in ``out``; returns where it stopped and the new ``nout``."""
    NC = np.int64(1)
    for j in range(k):
        NC *= size[j] + 1
    A = kind.shape[1]
    cv = np.zeros((m, A), np.int64)  # each robot's steps backwards: its value before,
    cp = np.zeros((m, A), np.int64)  # pose before, action,
    ca = np.zeros((m, A), np.int64)
    cc = np.zeros((m, A), np.int64)  # load before,
    cg = np.zeros((m, A), np.int64)  # group picked (+) or placed on (-): 1 + group, signed
    nc = np.zeros(m, np.int64)
    vals = np.zeros(m, np.int64)
    before_vals = np.zeros(m, np.int64)
    choice = np.zeros(m, np.int64)
    usedw = np.zeros((m + 1, max(W, 1)), np.int64)
    counts = np.zeros(max(k, 1), np.int64)
    delta_pick = np.zeros(max(k, 1), np.int64)
    delta_place = np.zeros(max(k, 1), np.int64)
    for e in range(lo, hi):
        idx = frontier[e]
        cidx = idx % NC
        r = idx // NC
        for b in range(blocks.shape[0] - 1, -1, -1):  # each block's rank read back (robot_index)
            start, nb, bsize = blocks[b, 0], blocks[b, 1], blocks[b, 2]
            rank = r % bsize
            r //= bsize
            w = binom.shape[0] - 1
            for j in range(nb - 1, -1, -1):
                while binom[w, j + 1] > rank:
                    w -= 1
                rank -= binom[w, j + 1]
                vals[order[start + j]] = w - j
                w -= 1
        for j in range(k):
            counts[j] = (cidx // mult[j]) % (size[j] + 1)
        dead = False
        for i in range(m):
            g = gid[i]
            q = vals[i] >> 1
            c1 = vals[i] & 1
            n = 0
            for e in range(rstart[g, q], rstart[g, q + 1]):
                p = rp[e]
                a = ra[e]
                kk = kind[g, a]
                t = target[g, p, a]
                if kk == kernel.PICK:
                    if c1 != 1 or t < 0 or group[t] < 0:
                        continue
                    c0 = 0
                    sg = 1 + group[t]
                elif kk == kernel.PLACE:
                    if c1 != 0 or t < 0 or group[t] < 0 or not carry_ok[g, p, a]:
                        continue
                    c0 = 1
                    sg = -(1 + group[t])
                else:
                    if c1 == 1 and not carry_ok[g, p, a]:
                        continue
                    c0 = c1
                    sg = 0
                cv[i, n] = 2 * local[g, p] + c0
                cp[i, n] = p
                ca[i, n] = a
                cc[i, n] = c0
                cg[i, n] = sg
                n += 1
            nc[i] = n
            if n == 0:
                dead = True
        if dead:
            continue
        most = np.int64(1)
        for i in range(m):
            most *= nc[i]
        if nout + most > out.shape[0]:
            return e, nout
        lev = 0
        choice[0] = -1
        while lev >= 0:
            choice[lev] += 1
            ok = False
            while choice[lev] < nc[lev]:
                n = choice[lev]
                g = gid[lev]
                if fits_bits(usedw, lev, masks[g, cp[lev, n], ca[lev, n], cc[lev, n]]):
                    ok = True
                    break
                choice[lev] += 1
            if not ok:
                lev -= 1
                continue
            if lev < m - 1:
                lev += 1
                choice[lev] = -1
                continue
            # a joint step backwards: the counts before it
            for j in range(k):
                delta_pick[j] = 0
                delta_place[j] = 0
            for i in range(m):
                s = cg[i, choice[i]]
                if s > 0:
                    delta_pick[s - 1] += 1
                elif s < 0:
                    delta_place[-s - 1] += 1
            before = np.int64(0)
            fine = True
            for j in range(k):
                b = counts[j] + delta_pick[j] - delta_place[j]
                if b < 0 or b > size[j] or delta_pick[j] > b or delta_place[j] > size[j] - b:
                    fine = False
                    break
                before += b * mult[j]
            if not fine:
                continue
            for i in range(m):
                before_vals[i] = cv[i, choice[i]]
            sort_groups(before_vals, sym_start, sym_idx)  # interchangeable robots sorted (module docstring)
            prev = robot_index(before_vals, order, blocks, binom) * NC + before
            if dist[prev] == UNREACHED:
                dist[prev] = level + 1
                out[nout] = prev
                nout += 1
    return hi, nout
