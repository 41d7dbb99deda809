"""LaCAM*'s configuration generators: PIBT (priority inheritance with backtracking, Okumura et
al., AIJ 2022) for robots whose moves occupy collision sets (DESIGN §3 rule 3), and the original
PIBT for classic collisions.

Under rule 3 a robot's collision set contains its cells before the step, so no robot ever enters
a cell another robot stands on *in the same step*: the classic "push the robot ahead and follow
it" is not a move here. Priority inheritance therefore acts one step ahead: a robot whose best
move is blocked by robots still to be decided *pushes* them (they are decided now, preferring
moves that leave the cells it wants), then takes its best move that is free (waiting, at worst,
which is always free). With classic collisions (point robots) a pushed robot must leave the
cell its pusher wants, and a push that fails makes the pusher try its next cell.

A generator completes a *constraint* (some robots' moves fixed) to a next configuration, or says
that it cannot; :mod:`.lacam` searches over configurations with it.
"""
from __future__ import annotations

import random
from dataclasses import dataclass

Poses = tuple[int, ...]


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

    def generate(self, config: Poses, order: list[int], forced: tuple, pinned: dict[int, frozenset],
                 wants: dict[int, frozenset] | None = None) -> tuple[tuple[int, ...], Poses] | None:
        problem = self.problem
        m = len(config)
        self.config = config
        self.moves = [problem.moves(i, p) for i, p in enumerate(config)]
        self.owner: dict[int, int] = {}
        for i, moves in enumerate(self.moves):
            for c in moves[0][2]:  # waiting: the cells the robot stands on (and its tile hovers over)
                self.owner[c] = i
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
                    self._decide(j, frozenset(cells))
        for i in order:
            if self.choice[i] is None:
                self._decide(i, None)
        actions = tuple(self.moves[i][k][0] for i, k in enumerate(self.choice))
        return actions, tuple(self.moves[i][k][1] for i, k in enumerate(self.choice))

    def _free(self, i: int, cells) -> bool:
        owner = self.owner
        return all(c not in self.taken and owner.get(c, i) == i for c in cells)

    def _claim(self, i: int, k: int) -> None:
        self.choice[i] = k
        self.taken.update(self.moves[i][k][2])

    def _decide(self, i: int, avoid: frozenset | None) -> None:
        """Choose robot ``i``'s move; ``avoid``: the cells its pusher wants (leave them)."""
        self.active.add(i)
        dist = self.problem.dist_lists[i]
        walk = self.problem.walks[i]
        ranked = []
        for k, (a, q, cells) in enumerate(self.moves[i]):
            stays = avoid is not None and not avoid.isdisjoint(walk.moves(q)[0][2])
            ranked.append((stays, dist[q], k != 0, self.rng.random(), k))  # ties: rather wait
        ranked.sort()
        here = dist[self.config[i]]
        pushed = False
        for stays, d, _, _, k in ranked:
            cells = self.moves[i][k][2]
            if any(c in self.taken for c in cells):
                continue
            blockers = {self.owner[c] for c in cells if self.owner.get(c, i) != i}
            if not blockers:
                self._claim(i, k)
                return
            if not pushed and (d < here or avoid is not None):
                pushed = True
                for j in sorted(blockers):
                    if self.choice[j] is None and j not in self.active:
                        self._decide(j, frozenset(cells))
        self._claim(i, 0)  # waiting is always free: nobody claims cells another robot stands on


class Classic(_Generator):
    """PIBT with classic collisions (point robots): vertex and swap conflicts only."""

    def generate(self, config: Poses, order: list[int], forced: tuple,
                 pinned: dict[int, frozenset]) -> tuple[tuple[int, ...], Poses] | None:
        m = len(config)
        self.config = config
        self.moves = [self.problem.moves(i, p) for i, p in enumerate(config)]
        self.here = {p: i for i, p in enumerate(config)}
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
        here = self.here
        ranked = sorted((dist[q], q in here and here[q] != i, self.rng.random(), k)
                        for k, (_, q, _) in enumerate(self.moves[i]))
        for *_, k in ranked:
            q = self.moves[i][k][1]
            if q in self.next_at:
                continue
            if pusher is not None and q == self.config[pusher]:
                continue  # no swap with the robot that pushes
            if self._swaps(i, q):
                continue  # the robot at q already moves into i's cell
            j = self.here.get(q)
            self._claim(i, k)
            if j is not None and j != i and self.choice[j] is None:
                if not self._decide(j, i):  # j stays where i wanted to go
                    self.next_at[q] = j
                    self.choice[i] = None
                    continue
            return True
        self.choice[i] = 0  # nowhere to go: it stays (a forced move into its cell fails above)
        self.next_at.setdefault(self.config[i], i)
        return False
