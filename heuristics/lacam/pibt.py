"""LaCAM*'s configuration generators: PIBT (priority inheritance with backtracking, Okumura et
al., AIJ 2022) for robots whose moves occupy collision sets (docs/rules.md, rule 3), and the original
PIBT for classic collisions.

Under rule 3 a robot's collision set contains its cells before the step, so no robot ever enters
a cell another robot stands on *in the same step*: the classic "push the robot ahead and follow
it" is not a move here. Priority inheritance therefore acts one step ahead: a robot whose best
move is blocked by robots still to be decided *pushes* them (they are decided now, each taking
the move that brings it closest to a pose clear of the cells its pusher wants: a biped keeps one
foot down every step, so that can take two steps or more, and it may push others in turn), then
waits and makes its move next step; a push that fails (a robot with no way out) makes it try its
next move. With classic collisions (point robots) a pushed robot must leave the cell its pusher
wants, and a push that fails makes the pusher try its next cell.

A generator completes a *constraint* (some robots' moves fixed) to a next configuration, or says
that it cannot; :mod:`.lacam` searches over configurations with it.
"""
from __future__ import annotations

import random
from dataclasses import dataclass

from bille.instances.lru import LRU

Poses = tuple[int, ...]
ESCAPE_DEPTH = 4  # moves a pushed robot looks ahead to leave the cells its pusher wants


def next_configuration(walks: list, dist_lists: list[list[int]], config: Poses, order: list[int],
                       pinned: dict[int, frozenset], rng: random.Random,
                       wants: dict[int, frozenset] | None = None) -> tuple[tuple[int, ...], Poses]:
    """One free step of the configuration generator (PIBT for collision sets, module docstring):
    robots on ``walks`` at ``config``, each drawn towards lower ``dist_lists[i]``, decided in
    ``order``; ``pinned`` robots wait holding the given cells; ``wants``: robots that wait for
    the given cells, whose occupants are pushed off them first. Returns ``(joint action, next
    poses)``; never fails (waiting is always free) unless the pinned cells overlap."""
    step = _Step(walks, dist_lists)
    got = Bille(step, rng).generate(config, order, (), pinned, wants)
    if got is None:
        raise ValueError("pinned cells overlap another robot")
    return got


def next_priorities(priority: list[float], resting) -> list[float]:
    """LaCAM's priority rule for the next step: a robot away from its goal gains one, a robot
    resting at its goal (``resting[i]``) keeps only the fraction (so no robot is starved)."""
    return [v - int(v) if rest else v + 1 for v, rest in zip(priority, resting)]


@dataclass
class _Step:
    """The part of a :class:`JointProblem` the generator reads, built from ready lists."""

    walks: list
    dist_lists: list

    def moves(self, i: int, pose: int):
        return self.walks[i].moves(pose)


class _Generator:
    def __init__(self, problem, rng: random.Random) -> None:
        self.problem, self.rng = problem, rng  # a JointProblem, or anything with moves, walks, dist_lists


class Bille(_Generator):
    """PIBT for rule 3 (module docstring): the pushed robots move now, the pusher next step."""

    def __init__(self, problem, rng: random.Random) -> None:
        super().__init__(problem, rng)
        self._escapes = LRU(4096)
        self._configs = LRU(64)

    def generate(self, config: Poses, order: list[int], forced: tuple, pinned: dict[int, frozenset],
                 wants: dict[int, frozenset] | None = None) -> tuple[tuple[int, ...], Poses] | None:
        m = len(config)
        self.config = config
        self.moves, self.owner = self._prepare(config)
        self.taken: set[int] = set()
        self.choice: list[int | None] = [None] * m
        for i, cells in pinned.items():
            if not self._free(i, cells):
                return None
            self.choice[i] = 0
            self.taken.update(cells)
        for i, k in forced:
            if i in pinned:
                if k != 0:
                    return None
                continue
            if not self._free(i, self.moves[i][k][2]):
                return None
            self._claim(i, k)
        self.active: set[int] = set()
        for i, cells in (wants or {}).items():  # a robot waiting to manipulate pushes those in the way
            if self.choice[i] is None:
                self._claim(i, 0)
            for j in sorted({self.owner[c] for c in cells if self.owner.get(c, i) != i}):
                if self.choice[j] is None:
                    self._decide(j, frozenset(cells), i)
        for i in order:
            if self.choice[i] is None:
                self._decide(i, None)
        actions = tuple(self.moves[i][k][0] for i, k in enumerate(self.choice))
        return actions, tuple(self.moves[i][k][1] for i, k in enumerate(self.choice))

    def _prepare(self, config: Poses) -> tuple[list, dict[int, int]]:
        """Every robot's moves at ``config`` and the robot standing on each cell (kept for the
        configurations the search comes back to)."""
        def make():
            moves = [self.problem.moves(i, p) for i, p in enumerate(config)]
            owner = {}
            for i, options in enumerate(moves):
                for c in options[0][2]:  # waiting: the cells the robot stands on (and its tile hovers over)
                    owner[c] = i
            return moves, owner

        return self._configs.get(config, make)

    def compatible(self, config: Poses, forced: tuple, i: int) -> list[int]:
        """Robot ``i``'s moves at ``config`` that the ``forced`` moves leave possible."""
        moves, owner = self._prepare(config)
        used = set().union(*(moves[j][k][2] for j, k in forced))
        return [k for k, (_, _, cells) in enumerate(moves[i])
                if used.isdisjoint(cells) and all(owner.get(c, i) == i for c in cells)]

    def _free(self, i: int, cells) -> bool:
        owner = self.owner
        return all(c not in self.taken and owner.get(c, i) == i for c in cells)

    def _claim(self, i: int, k: int) -> None:
        self.choice[i] = k
        self.taken.update(self.moves[i][k][2])

    def _decide(self, i: int, avoid: frozenset | None, pusher: int | None = None) -> bool:
        """Choose robot ``i``'s move; ``avoid``: the cells robot ``pusher`` wants next step.
        True when ``i`` makes progress: pushed, it comes closer to a pose clear of ``avoid``
        (:meth:`_escape`), or pushes the robots in the way of a move that would; unpushed, it
        comes closer to its goal, or pushes for a move that would. False when it cannot."""
        self.active.add(i)
        dist = self.problem.dist_lists[i]
        moves = self.moves[i]
        here = self.config[i]
        if avoid is None:
            rank, now = dist, dist[here]
        else:
            rank = self._escape(i, avoid, self.moves[pusher][0][2])
            now = rank.get(here, ESCAPE_DEPTH + 1)
        ranked = sorted((rank.get(q, ESCAPE_DEPTH + 1) if avoid is not None else dist[q], dist[q], k != 0,
                         self.rng.random(), k) for k, (_, q, _) in enumerate(moves))  # ties: rather wait
        owner, taken, choice, active = self.owner, self.taken, self.choice, self.active
        for score, _, _, _, k in ranked:
            cells = moves[k][2]
            if not taken.isdisjoint(cells):
                continue
            blockers = {owner[c] for c in cells if owner.get(c, i) != i}
            if not blockers:
                self._claim(i, k)
                return score < now
            if score < now and all(choice[j] is None and j not in active for j in blockers):
                # push: the blockers make way now, ``i`` follows next step (rule 3: nobody enters a
                # cell another robot stands on); when one cannot, the next move is tried
                if all([self._decide(j, cells, i) for j in sorted(blockers)]):
                    self._claim(i, 0)
                    return True
        self._claim(i, 0)  # waiting is always free: nobody claims cells another robot stands on
        return False

    def _escape(self, i: int, avoid: frozenset, keep_out: frozenset) -> dict[int, int]:
        """Steps from the poses near robot ``i`` (at most :data:`ESCAPE_DEPTH` moves away) to a
        pose whose cells miss ``avoid``, walking around ``keep_out`` (the pusher's cells) and
        ignoring other robots. A biped keeps one foot down every step, so a robot with both feet
        where its pusher wants to go needs two steps at least, and in a corridor more."""
        walk = self.problem.walks[i]
        start = self.config[i]
        return self._escapes.get((id(walk), start, avoid, keep_out),
                                 lambda: self._escape_steps(walk, start, avoid, keep_out))

    @staticmethod
    def _escape_steps(walk, start: int, avoid: frozenset, keep_out: frozenset) -> dict[int, int]:
        seen, frontier, back = {start}, [start], {}
        for _ in range(ESCAPE_DEPTH):
            ahead = []
            for p in frontier:
                for _, q, cells in walk.moves(p):
                    if q == p or not keep_out.isdisjoint(cells):
                        continue
                    back.setdefault(q, []).append(p)
                    if q not in seen:
                        seen.add(q)
                        ahead.append(q)
            frontier = ahead
        steps = {q: 0 for q in seen if avoid.isdisjoint(walk.moves(q)[0][2])}
        queue = list(steps)
        for q in queue:
            for p in back.get(q, ()):
                if p not in steps:
                    steps[p] = steps[q] + 1
                    queue.append(p)
        return steps


class Classic(_Generator):
    """PIBT with classic collisions (point robots): vertex and swap conflicts only, with
    lacam3's *swap* emulation (Okumura, AAMAS 2024): where two robots must pass each other in a
    corridor, one pulls the other along into a branch instead of both pushing head-on.

    A point robot's pose is its cell, so the poses next to each pose (``nbrs``) are read once
    from the first robot's walk; every robot walks on the same structure."""

    def __init__(self, problem, rng: random.Random) -> None:
        super().__init__(problem, rng)
        self._configs = LRU(64)
        self.prefer: list[dict[int, int]] | None = None  # per robot: its SUO path's next cell (.scatter)
        walk = problem.walks[0] if problem.walks else None  # no robot: nothing to generate
        self.nbrs = [] if walk is None else [
            [q for q in row if q >= 0 and q != v] if standing else []
            for v, (row, standing) in enumerate(zip(walk.succ.tolist(), walk.standing.tolist()))]

    def _prepare(self, config: Poses) -> tuple[list, dict[int, int]]:
        """Every robot's moves at ``config`` and the robot at each cell (kept for the
        configurations the search comes back to)."""
        moves = self.problem.moves
        return self._configs.get(config, lambda: ([moves(i, p) for i, p in enumerate(config)],
                                                  {p: i for i, p in enumerate(config)}))

    def compatible(self, config: Poses, forced: tuple, i: int) -> list[int]:
        """Robot ``i``'s moves at ``config`` that the ``forced`` moves leave possible (no
        vertex or swap conflict with them)."""
        moves, here = self._prepare(config)
        ends = {moves[j][k][1]: j for j, k in forced}
        return [k for k, (_, q, _) in enumerate(moves[i])
                if q not in ends and not any(j == here.get(q, i) != i and moves[j][kk][1] == config[i]
                                             for j, kk in forced)]

    def generate(self, config: Poses, order: list[int], forced: tuple,
                 pinned: dict[int, frozenset]) -> tuple[tuple[int, ...], Poses] | None:
        m = len(config)
        self.config = config
        self.moves, self.here = self._prepare(config)
        self.next_at: dict[int, int] = {}
        self.choice: list[int | None] = [None] * m
        for i, k in forced:
            q = self.moves[i][k][1]
            if q in self.next_at or self._swaps(i, q):
                return None
            self._claim(i, k)
        for i in order:
            if self.choice[i] is None:
                self._decide(i, None)
        nxt = tuple(self.moves[i][k][1] for i, k in enumerate(self.choice))
        if len(set(nxt)) < m or any(self.here.get(q, i) != i and nxt[self.here[q]] == config[i]
                                    for i, q in enumerate(nxt)):
            return None  # the forced moves left a robot nowhere to go
        return tuple(self.moves[i][k][0] for i, k in enumerate(self.choice)), nxt

    def _claim(self, i: int, k: int) -> None:
        self.choice[i] = k
        self.next_at[self.moves[i][k][1]] = i

    def _swaps(self, i: int, q: int) -> bool:
        """Whether robot ``i`` moving to ``q`` swaps with a decided robot standing on ``q``."""
        j = self.here.get(q)
        if j is None or j == i or self.choice[j] is None:
            return False
        return self.moves[j][self.choice[j]][1] == self.config[i]

    def _decide(self, i: int, pusher: int | None) -> bool:
        dist = self.problem.dist_lists[i]
        here, rand = self.here, self.rng.random
        moves = self.moves[i]
        # the next cell of its SUO path first; then by distance, then cells nobody stands on,
        # then at random (one float keeps that order)
        prefer = self.prefer[i].get(self.config[i], -1) if self.prefer else -1
        ranked = sorted(((-1 if q == prefer else 4 * dist[q] + (2 if q in here and here[q] != i else 0)) + rand(), k)
                        for k, (_, q, _) in enumerate(moves))
        puller = self._swap_partner(i, moves[ranked[0][1]][1])
        if puller is not None:
            ranked.reverse()  # make way first: the partner follows into i's cell
        for rank, (_, k) in enumerate(ranked):
            q = moves[k][1]
            if q in self.next_at:
                continue
            if pusher is not None and q == self.config[pusher]:
                continue  # no swap with the robot that pushes
            if self._swaps(i, q):
                continue  # the robot at q already moves into i's cell
            j = here.get(q)
            self._claim(i, k)
            if j is not None and j != i and self.choice[j] is None:
                if not self._decide(j, i):  # j stays where i wanted to go
                    self.next_at[q] = j
                    self.choice[i] = None
                    continue
            if rank == 0 and puller is not None:
                self._pull(puller, i)
            return True
        self.choice[i] = 0  # nowhere to go: it stays (a forced move into its cell fails above)
        self.next_at.setdefault(self.config[i], i)
        return False

    # ---- the swap emulation ---------------------------------------------------------------------

    def _pull(self, j: int, i: int) -> None:
        """Robot ``j``, undecided, follows into the cell ``i`` leaves, if nobody takes it."""
        v = self.config[i]
        if self.choice[j] is not None or v in self.next_at or self.moves[i][self.choice[i]][1] == self.config[j]:
            return
        k = next((k for k, (_, q, _) in enumerate(self.moves[j]) if q == v), None)
        if k is not None:
            self._claim(j, k)

    def _swap_partner(self, i: int, best: int) -> int | None:
        """The robot that should pass ``i`` by being pulled along, if any: the robot on ``i``'s
        best next cell when the two must pass each other and a branch ahead allows it; or (a
        *clear* move, after push and swap) a neighbour that must pass ``i`` on its way to
        ``best``."""
        here, v = self.here, self.config[i]
        j = here.get(best)
        if (j is not None and j != i and self.choice[j] is None and self._must_pass(i, j, v, best)
                and self._can_pass(best, v)):
            return j
        if best != v:
            dists = self.problem.dist_lists
            for u in self.nbrs[v]:
                k = here.get(u)
                # k must pass i only if best brings k closer (else the corridor walk stops at once)
                if (k is not None and u != best and dists[k][best] < dists[k][v]
                        and self._must_pass(k, i, v, best) and self._can_pass(best, v)):
                    return k
        return None

    def _through(self, at: int, came: int) -> tuple[int, int | None]:
        """How many ways lead on from ``at`` (not back to ``came``, nor into a dead end where a
        robot rests at its goal), and one of them."""
        n, way = 0, None
        nbrs, here, at_goal = self.nbrs, self.here, self.problem.at_goal
        for u in nbrs[at]:
            if u == came:
                continue
            if len(nbrs[u]) == 1:
                k = here.get(u)
                if k is not None and at_goal(k, u):
                    continue
            n, way = n + 1, u
        return n, way

    def _must_pass(self, pusher: int, puller: int, v_pusher: int, v_puller: int) -> bool:
        """Whether ``pusher`` (at ``v_pusher``) and ``puller`` (at ``v_puller``) want to pass each
        other along a corridor with no room to step aside before the pusher's way improves."""
        d_push, d_pull = self.problem.dist_lists[pusher], self.problem.dist_lists[puller]
        a, b = v_pusher, v_puller
        while d_push[b] < d_push[a]:
            n, way = self._through(b, a)
            if n >= 2:
                return False  # room to step aside at b: no swap needed
            if n == 0:
                break
            a, b = b, way
        return d_pull[a] < d_pull[b] and (d_push[a] == 0 or d_push[b] < d_push[a])

    def _can_pass(self, v_pusher: int, v_puller: int) -> bool:
        """Whether pulling back from ``v_puller`` away from ``v_pusher`` reaches a branch."""
        a, b, origin = v_pusher, v_puller, v_pusher
        while b != origin:
            n, way = self._through(b, a)
            if n >= 2:
                return True
            if n == 0:
                return False
            a, b = b, way
        return False
