"""Corridor reasoning for point robots (classic collisions).

Two robots that meet head-on in a corridor are split by plain CBS once per cell and time at
which they could meet there: exponentially many nodes before one of them waits outside. The
*corridor* split (Li, Harabor, Stuckey, Koenig, AIJ 2021) decides in one branch per robot which
one goes through first. This module finds it and proves it complete; :mod:`.search` decides when
it is used.

Set-up. The robots' moves can be undone (a move from ``u`` to ``v`` has one from ``v`` to ``u``;
:mod:`.method` switches the split off otherwise), so a cell's neighbours are the cells it can move
to and come from alike. A *corridor* ``C = v_1 .. v_k`` is a maximal chain of cells with exactly
two neighbours each in both robots' walking graphs, ``v_i`` next to ``v_(i+1)``; ``a`` is
``v_1``'s other neighbour, ``b`` ``v_k``'s, ``a != b``, neither in ``C``. So ``C`` is entered and
left only through ``a`` and ``b``. Neither robot starts in ``C``. Robot 1 is the one whose current
path goes on to ``b``, robot 2 to ``a``. With ``d_r(x)`` robot ``r``'s walking distance from its
start to ``x`` and ``d'_r(x)`` the same avoiding ``C``:

- branch 1: robot 1 is not at ``b`` at any time ``0 .. T1``, ``T1 = min(d'_1(b) - 1, d_2(a) + k + 1)``;
- branch 2: robot 2 is not at ``a`` at any time ``0 .. T2``, ``T2 = min(d'_2(a) - 1, d_1(b) + k + 1)``.

Complete. Let ``p1``, ``p2`` break both: ``p1`` is first at ``b`` at ``t1 <= T1`` and ``p2`` first at
``a`` at ``t2 <= T2``. (i) ``p1`` came to ``b`` through ``C``: otherwise each of its visits to ``C``
before ``t1`` enters from ``a`` and returns to ``a`` (``b`` is not visited before ``t1``, ``p1`` does
not start in ``C``); waiting at ``a`` instead makes a walk of ``t1`` steps that avoids ``C``, so
``t1 >= d'_1(b) > T1``. Hence ``p1`` is at ``a`` at some ``s1 < t1``, inside ``C`` from ``s1 + 1`` to
``t1 - 1``, and ``t1 - s1 >= k + 1``. Likewise ``p2`` is at ``b`` at ``s2``, in ``C``, at ``a`` at ``t2``.
(ii) Number the line ``a = 0, v_1 = 1, .., v_k = k, b = k + 1``; each step changes a position on
it by at most one. If ``[s1, t1]`` and ``[s2, t2]`` overlap, on their overlap ``pos1 - pos2`` is at
most 0 at its start (robot 1 at ``a``, or robot 2 at ``b``) and at least 0 at its end (robot 1 at
``b``, or robot 2 at ``a``), 0 only on a shared cell; so the two share a cell at one time, or
exchange two cells in one step: a conflict. Without one, ``t1 < s2`` or ``t2 < s1``. (iii) If
``t1 < s2``: ``t2 >= s2 + k + 1 >= t1 + k + 2 >= d_1(b) + k + 2 > T2``, against ``t2 <= T2``; the
other case is the same with the robots exchanged. So every conflict-free pair keeps a branch.

The split is used only when the current paths break both branches (so both children exclude
them), from a vertex conflict on a cell of ``C`` or a swap with an end in ``C``.
"""
from __future__ import annotations

from collections import deque

from bille.instances.walking import UNREACHABLE

from .constraints import NEVER, VERTEX
from .lowlevel import MDD, Agent, Path, meets_all

CORRIDOR = 5  # a conflict kind, after the rectangle's


class Corridors:
    """The corridors of the robots' walking graphs and the distances the split needs (cached)."""

    def __init__(self, agents: list[Agent], caches: tuple | None = None) -> None:
        self.agents = agents
        # keyed by walking graph (chains, neighbours) and by robot (distances: from its start), so
        # the searches over pairs of robots share them with the search over all (``caches``)
        self.caches = caches or ({}, {}, {})
        self._chains, self._dist, self._neighbours = self.caches

    def _walk_of(self, k: int):
        """The walking graph of robot ``k``: the :class:`~bille.instances.walking.Walk` whose
        ``moves`` it reads (robots of one moveset share one), or those moves."""
        moves = self.agents[k].moves
        return getattr(moves, "__self__", moves)

    def _graph(self, k: int) -> int:
        """The walking graph of robot ``k``, as a key."""
        return id(self._walk_of(k))

    def neighbours(self, k: int, p: int) -> list[int]:
        """The cells robot ``k`` can move to from ``p`` (each once: two actions may go alike);
        cached per walking graph, which robots of one moveset share."""
        key = (self._graph(k), p)
        found = self._neighbours.get(key)
        if found is None:
            moves = self.agents[k].moves(p)
            found = self._neighbours[key] = list(dict.fromkeys(q for _, q, _ in moves if q != p))
        return found

    def chain(self, k: int, v: int) -> tuple[frozenset, int, int, int] | None:
        """``(C, a, b, k)`` for the corridor through cell ``v`` of robot ``k``'s graph, or None."""
        key = (self._graph(k), v)
        if key not in self._chains:
            self._chains[key] = self._walk(k, v)
        return self._chains[key]

    def _walk(self, k: int, v: int):
        if len(self.neighbours(k, v)) != 2:
            return None
        cells, ends = {v}, []
        for nxt in self.neighbours(k, v):
            prev, cur = v, nxt
            while len(self.neighbours(k, cur)) == 2 and cur not in cells:
                cells.add(cur)
                prev, cur = cur, next(q for q in self.neighbours(k, cur) if q != prev)
            ends.append(cur)
        a, b = ends
        if a == b or a in cells or b in cells:
            return None  # a loop: no corridor
        return frozenset(cells), a, b, len(cells)

    def distance(self, k: int, target: int, avoid: frozenset = frozenset()) -> int:
        """Robot ``k``'s walking distance from its start to ``target`` avoiding ``avoid``: a
        breadth-first search from the start kept per ``(k, avoid)`` and taken only as far as the
        targets asked for so far need (so a near target costs a few cells, not the map); with the
        compiled low level, the whole map's at once (tens of microseconds)."""
        agent = self.agents[k]
        key = (agent.index, avoid)
        search = self._dist.get(key)
        if search is None:
            if len(self._dist) > 4096:
                self._dist.clear()
            start = agent.start
            if agent.arrays is not None:
                search = self._dist[key] = self._walk_of(k).from_pose_avoiding(start, avoid)
            else:
                search = self._dist[key] = ({start: 0}, deque([start]))
        if not isinstance(search, tuple):
            found = int(search[target])
            return NEVER if found >= UNREACHABLE else found
        seen, queue = search
        while target not in seen and queue:
            p = queue.popleft()
            for q in self.neighbours(k, p):
                if q not in seen and q not in avoid:
                    seen[q] = seen[p] + 1
                    queue.append(q)
        return seen.get(target, NEVER)

    def split(self, conflict, paths: list[Path], mdds: tuple[MDD | None, MDD | None]):
        """The corridor split of a vertex or swap ``conflict`` as ``((CORRIDOR, i, j, t, (B1,
        B2)), score)`` (``score``: how many branches every least-cost path breaks, 0-2), or None."""
        _, i, j, t, where = conflict
        for v in (where if isinstance(where, tuple) else (where,)):
            found = self.chain(i, v)
            if found is not None:
                break
        else:
            return None
        if found != self.chain(j, v):
            return None
        cells, a, b, k = found
        si, sj = self.agents[i].start, self.agents[j].start
        if si in cells or sj in cells:
            return None
        for ei, ej in ((b, a), (a, b)):  # robot i leaves by ei, robot j by ej
            ti = min(self.distance(i, ei, cells) - 1, self.distance(j, ej) + k + 1)
            tj = min(self.distance(j, ej, cells) - 1, self.distance(i, ei) + k + 1)
            if _visits(paths[i], ei, ti) and _visits(paths[j], ej, tj):  # so d_j(ej), d_i(ei) are finite
                bi = tuple((VERTEX, ei, time) for time in range(ti + 1))
                bj = tuple((VERTEX, ej, time) for time in range(tj + 1))
                score = meets_all(mdds[0], bi) + meets_all(mdds[1], bj)
                return (CORRIDOR, i, j, t, (bi, bj)), score
        return None


def _visits(path: Path, cell: int, until: int) -> bool:
    """Whether ``path`` is on ``cell`` at some time ``0 .. until``."""
    poses = path.poses
    return any(poses[time] == cell for time in range(min(until, len(poses) - 1) + 1))
