"""The classic PIBT generator (:class:`.pibt.Classic`) compiled with Numba: the same algorithm,
the same order of its random draws and so the same configurations, several times faster on
hundreds of robots. tests/test_lacam.py runs both on the same constraints and compares.

It serves where every robot walks alike (one walk, so one table of moves) and Numba is loaded
already (the SUO step loads it on large problems, :mod:`.scatter`); elsewhere the Python
generator runs. A pose's moves are numbered as :meth:`bille.instances.walking.Walk.moves` lists
them (the wait first), so forced moves ``(robot, k)`` mean the same in both. The Python
generator draws one random float per move of each robot it decides; here the same floats come
from the same Mersenne Twister run in the compiled code on a copy of the search's
``random.Random`` state (CPython's algorithm: its 624 words, their regeneration, its tempering
and its 53-bit floats), and the search's state is then set to the copy's.
"""
from __future__ import annotations

import numpy as np

from bille.instances.jit import jit

from .pibt import Classic, Poses


class CompiledClassic(Classic):
    """:class:`.pibt.Classic` with :meth:`generate` compiled (module docstring)."""

    def __init__(self, problem, rng) -> None:
        super().__init__(problem, rng)
        walk = problem.walks[0]
        order = np.array([walk.wait] + [a for a in range(walk.succ.shape[1]) if a != walk.wait], dtype=np.int64)
        succ = walk.succ[:, order].astype(np.int64)
        first = np.argsort(succ < 0, axis=1, kind="stable")  # the valid moves first, in their order
        self.move_q = np.take_along_axis(succ, first, axis=1)
        self.move_a = order[first]
        self.move_n = (succ >= 0).sum(axis=1).astype(np.int64)
        width = max((len(row) for row in self.nbrs), default=0)
        self.nbr = np.full((len(self.nbrs), max(width, 1)), -1, dtype=np.int64)
        for v, row in enumerate(self.nbrs):
            self.nbr[v, :len(row)] = row
        self.nbr_n = np.array([len(row) for row in self.nbrs], dtype=np.int64)
        self.dist = problem.dist_table
        self.home = problem.home_table
        self._prefer_of = None
        self.prefer_at = np.full((0, 0), -1, dtype=np.int64)
        P = succ.shape[0]
        self.here = np.full(P, -1, dtype=np.int64)
        self.next_at = np.full(P, -1, dtype=np.int64)

    def _prefer_arrays(self) -> np.ndarray:
        """The SUO paths' next cells as an array ``[robot, pose]`` (-1: none), made once."""
        if self.prefer is not self._prefer_of:
            self._prefer_of = self.prefer
            out = np.full((len(self.problem.walks), self.here.shape[0]), -1, dtype=np.int64) if self.prefer \
                else np.full((0, 0), -1, dtype=np.int64)
            for i, row in enumerate(self.prefer or ()):
                for v, q in row.items():
                    out[i, v] = q
            self.prefer_at = out
        return self.prefer_at

    def compatible(self, config: Poses, forced: tuple, i: int) -> list[int]:
        """:meth:`.pibt.Classic.compatible` on the move table: robot ``i``'s moves that the
        ``forced`` moves leave possible (no vertex or swap conflict with them)."""
        v = config[i]
        ends = {int(self.move_q[config[j], k]) for j, k in forced}
        out = []
        for k in range(int(self.move_n[v])):
            q = int(self.move_q[v, k])
            if q in ends or any(config[j] == q and j != i and self.move_q[config[j], kk] == v for j, kk in forced):
                continue
            out.append(k)
        return out

    def generate(self, config: Poses, order: list[int], forced: tuple,
                 pinned: dict[int, frozenset]) -> tuple[tuple[int, ...], Poses] | None:
        m = len(config)
        at = np.array(config, dtype=np.int64)
        state = self.rng.getstate()  # the search's Mersenne Twister: drawn from in place, then set back
        mt = np.array(state[1][:624], dtype=np.int64)
        mti = np.array([state[1][624]], dtype=np.int64)  # its index: the next word to use
        forced_i = np.array([i for i, _ in forced], dtype=np.int64)
        forced_k = np.array([k for _, k in forced], dtype=np.int64)
        choice = np.full(m, -1, dtype=np.int64)
        ok = _generate(at, np.array(order, dtype=np.int64), forced_i, forced_k, self.move_q, self.move_n,
                       self.dist, self.home, self.nbr, self.nbr_n, self._prefer_arrays(), mt, mti,
                       self.here, self.next_at, choice)
        self.rng.setstate((state[0], tuple(mt.tolist()) + (int(mti[0]),), state[2]))
        if not ok:
            return None
        return tuple(self.move_a[at, choice].tolist()), tuple(self.move_q[at, choice].tolist())


@jit
def _generate(config, order, forced_i, forced_k, move_q, move_n, dist, home, nbr, nbr_n, prefer, mt, mti,
              here, next_at, choice):  # pragma: no cover - compiled
    """:meth:`.pibt.Classic.generate` on arrays; ``here`` and ``next_at`` come in as -1 and are
    left so. ``choice`` gets each robot's move number; False if the constraint cannot be met."""
    m = config.shape[0]
    frames = np.empty((m, 7), dtype=np.int64)  # the pushes under way, at most one frame a robot
    ranks = np.empty((m, move_q.shape[1]), dtype=np.int64)
    for i in range(m):
        here[config[i]] = i
    ok = True
    for f in range(forced_i.shape[0]):
        i, k = forced_i[f], forced_k[f]
        q = move_q[config[i], k]
        if next_at[q] >= 0 or _swaps(i, q, config, here, choice, move_q):
            ok = False
            break
        choice[i] = k
        next_at[q] = i
    if ok:
        for n in range(order.shape[0]):
            i = order[n]
            if choice[i] < 0:
                _decide(i, config, move_q, move_n, dist, home, nbr, nbr_n, prefer, mt, mti, here, next_at, choice,
                        frames, ranks)
    for i in range(m):  # every cell next_at was given is a move's cell of some robot: all back to -1
        for k in range(move_n[config[i]]):
            next_at[move_q[config[i], k]] = -1
    if ok:  # two robots on one cell, or two swapping (the forced moves may leave either)
        for i in range(m):
            q = move_q[config[i], choice[i]]
            if next_at[q] >= 0:
                ok = False
            next_at[q] = i
            j = here[q]
            if j >= 0 and j != i and move_q[config[j], choice[j]] == config[i]:
                ok = False
        for i in range(m):
            next_at[move_q[config[i], choice[i]]] = -1
    for i in range(m):
        here[config[i]] = -1
    return ok


@jit
def _swaps(i, q, config, here, choice, move_q):  # pragma: no cover - compiled
    j = here[q]
    if j < 0 or j == i or choice[j] < 0:
        return False
    return move_q[config[j], choice[j]] == config[i]


@jit
def _decide(root, config, move_q, move_n, dist, home, nbr, nbr_n, prefer, mt, mti, here, next_at, choice,
            frames, ranks):  # pragma: no cover - compiled
    """:meth:`.pibt.Classic._decide` for robot ``root``, its recursion on an explicit stack
    (Numba's machine code for a recursive function cannot be cached): a frame is ``frames[f] =
    (robot, pusher, moves, rank under way, puller, cell claimed, robot pushed)`` and ``ranks[f]``
    its moves in the order tried."""
    depth = 1
    _enter(0, root, -1, config, move_q, move_n, dist, home, nbr, nbr_n, prefer, mt, mti, here, choice, frames,
           ranks)
    result, back = False, False
    while depth > 0:
        f = depth - 1
        i, pusher, n, puller = frames[f, 0], frames[f, 1], frames[f, 2], frames[f, 4]
        v = config[i]
        if back:  # the robot pushed has been decided: ``result``
            back = False
            if result:
                if frames[f, 3] == 0 and puller >= 0:
                    _pull(puller, i, config, move_q, move_n, here, next_at, choice)
                depth -= 1
                back = True
                continue
            next_at[frames[f, 5]] = frames[f, 6]  # it stays where i wanted to go
            choice[i] = -1
            frames[f, 3] += 1
        descended, done = False, False
        while frames[f, 3] < n:
            rank = frames[f, 3]
            k = ranks[f, rank]
            q = move_q[v, k]
            if next_at[q] >= 0 or (pusher >= 0 and q == config[pusher]) or _swaps(i, q, config, here, choice, move_q):
                frames[f, 3] += 1
                continue
            j = here[q]
            choice[i] = k
            next_at[q] = i
            if j >= 0 and j != i and choice[j] < 0:
                frames[f, 5], frames[f, 6] = q, j
                _enter(depth, j, i, config, move_q, move_n, dist, home, nbr, nbr_n, prefer, mt, mti, here, choice,
                       frames, ranks)
                depth += 1
                descended = True
                break
            if rank == 0 and puller >= 0:
                _pull(puller, i, config, move_q, move_n, here, next_at, choice)
            done = True
            break
        if descended:
            continue
        if done:
            result = True
        else:  # nowhere to go: it stays (a forced move into its cell fails in the caller)
            choice[i] = 0
            if next_at[v] < 0:
                next_at[v] = i
            result = False
        depth -= 1
        back = True
    return result


@jit
def _word(mt, mti):  # pragma: no cover - compiled
    """The next 32-bit output of the Mersenne Twister whose 624 words are ``mt`` and whose index
    is ``mti[0]`` (CPython's ``genrand_uint32``: the words regenerated when all are used)."""
    if mti[0] >= 624:
        for k in range(624):
            y = (mt[k] & 0x80000000) | (mt[(k + 1) % 624] & 0x7FFFFFFF)
            mt[k] = mt[(k + 397) % 624] ^ (y >> 1) ^ (0x9908B0DF if y & 1 else 0)
        mti[0] = 0
    y = mt[mti[0]]
    mti[0] += 1
    y ^= y >> 11
    y ^= (y << 7) & 0x9D2C5680
    y ^= (y << 15) & 0xEFC60000
    return y ^ (y >> 18)


@jit
def _random(mt, mti):  # pragma: no cover - compiled
    """Python's ``random()`` from that state: 53 bits from two outputs (``genrand_res53``)."""
    a = _word(mt, mti) >> 5
    b = _word(mt, mti) >> 6
    return (a * 67108864.0 + b) * (1.0 / 9007199254740992.0)


@jit
def _enter(f, i, pusher, config, move_q, move_n, dist, home, nbr, nbr_n, prefer, mt, mti, here, choice, frames,
           ranks):  # pragma: no cover - compiled
    """Frame ``f`` for robot ``i`` pushed by ``pusher`` (-1: none): its moves ranked as
    :meth:`.pibt.Classic._decide` ranks them (one random draw per move), and its swap partner."""
    v = config[i]
    n = move_n[v]
    keys = np.empty(n, dtype=np.float64)
    want = prefer[i, v] if prefer.shape[0] > 0 else -1
    for k in range(n):
        q = move_q[v, k]
        if q == want:
            base = -1.0
        else:
            busy = 2 if (here[q] >= 0 and here[q] != i) else 0
            base = float(4 * dist[i, q] + busy)
        keys[k] = base + _random(mt, mti)
        ranks[f, k] = k
    for a in range(1, n):  # insertion sort by (key, k), as Python's sort of the pairs
        key, kk = keys[a], ranks[f, a]
        b = a - 1
        while b >= 0 and (keys[b] > key or (keys[b] == key and ranks[f, b] > kk)):
            keys[b + 1], ranks[f, b + 1] = keys[b], ranks[f, b]
            b -= 1
        keys[b + 1], ranks[f, b + 1] = key, kk
    puller = _swap_partner(i, move_q[v, ranks[f, 0]], config, dist, home, nbr, nbr_n, here, choice)
    if puller >= 0:  # make way first: the partner follows into i's cell
        for a in range(n // 2):
            ranks[f, a], ranks[f, n - 1 - a] = ranks[f, n - 1 - a], ranks[f, a]
    frames[f, 0], frames[f, 1], frames[f, 2], frames[f, 3], frames[f, 4] = i, pusher, n, 0, puller


@jit
def _pull(j, i, config, move_q, move_n, here, next_at, choice):  # pragma: no cover - compiled
    v = config[i]
    if choice[j] >= 0 or next_at[v] >= 0 or move_q[v, choice[i]] == config[j]:
        return
    u = config[j]
    for k in range(move_n[u]):
        if move_q[u, k] == v:
            choice[j] = k
            next_at[v] = j
            return


@jit
def _swap_partner(i, best, config, dist, home, nbr, nbr_n, here, choice):  # pragma: no cover - compiled
    v = config[i]
    j = here[best]
    if j >= 0 and j != i and choice[j] < 0 and _must_pass(i, j, v, best, dist, home, nbr, nbr_n, here) \
            and _can_pass(best, v, home, nbr, nbr_n, here):
        return j
    if best != v:
        for x in range(nbr_n[v]):
            u = nbr[v, x]
            k = here[u]
            if k >= 0 and u != best and dist[k, best] < dist[k, v] \
                    and _must_pass(k, i, v, best, dist, home, nbr, nbr_n, here) \
                    and _can_pass(best, v, home, nbr, nbr_n, here):
                return k
    return -1


@jit
def _through(at, came, home, nbr, nbr_n, here):  # pragma: no cover - compiled
    n, way = 0, -1
    for x in range(nbr_n[at]):
        u = nbr[at, x]
        if u == came:
            continue
        if nbr_n[u] == 1:
            k = here[u]
            if k >= 0 and home[k, u]:
                continue
        n += 1
        way = u
    return n, way


@jit
def _must_pass(pusher, puller, v_pusher, v_puller, dist, home, nbr, nbr_n, here):  # pragma: no cover - compiled
    a, b = v_pusher, v_puller
    while dist[pusher, b] < dist[pusher, a]:
        n, way = _through(b, a, home, nbr, nbr_n, here)
        if n >= 2:
            return False
        if n == 0:
            break
        a, b = b, way
    return dist[puller, a] < dist[puller, b] and (dist[pusher, a] == 0 or dist[pusher, b] < dist[pusher, a])


@jit
def _can_pass(v_pusher, v_puller, home, nbr, nbr_n, here):  # pragma: no cover - compiled
    a, b, origin = v_pusher, v_puller, v_pusher
    while b != origin:
        n, way = _through(b, a, home, nbr, nbr_n, here)
        if n >= 2:
            return True
        if n == 0:
            return False
        a, b = b, way
    return False
