"""LaCAM* over whole states (tiles, poses, loads): a complete planner for reconfiguration.

The search of :mod:`.lacam` over a space whose configurations are whole states of the world
(docs/rules.md): the tile set, every robot's pose and whether it carries a tile. A robot's moves
are all its candidate actions in that state, picks and places included
(:func:`~bille.instances.successors.candidate_actions`), so the lazy constraints eventually
pin every joint action of every reachable state, and the canonical rules
(:func:`~bille.instances.rules.apply`) judge each one. The space is finite, so the search is
**complete**: it returns a schedule whenever one exists (given time and memory), and when it
exhausts the space without reaching the goal it has visited every reachable state: a proof that
no schedule exists (status ``infeasible``).

**The generator** completes a constraint greedily. Every robot without a pinned action takes,
in priority order, its best action whose collision set is free (the cells other robots stand on
are theirs: rule 3 puts them in every one of their collision sets): a pick of a tile that must
go, a place on a cell that must be filled, or else the walking move that gets it closest to
the poses facing such a cell (it carries: a cell to fill; it does not: a tile to take away;
nothing left to move: its goal cell), on the current structure. Picks and places elsewhere (a
tile set aside, a relay) come last: the constraints reach them. A joint action the rules
reject (a pick that would cut the structure, say) loses the offending robot's choice for a
wait, a few times, before the generator gives up on the constraint.

Objective: makespan (every step costs 1); the estimate ``h`` is admissible: each step changes
at most ``m`` cells (one pick or place per robot), so the cells that differ from the goal take
at least ``ceil(differ / m)`` steps; a robot with a goal cell needs at least its relaxed
distance to it.
"""
from __future__ import annotations

import dataclasses
import random

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.distances import relaxed_for
from bille.instances.grid import articulation_points
from bille.instances.moveset import Kind
from bille.instances.rules import State, apply, goal_violation
from bille.instances.run import Run
from bille.instances.successors import candidate_actions, collision_cells
from bille.instances.walking import UNREACHABLE, walk_for

from ..joint import to_result
from .search import search

RETRIES = 3  # rejected joint actions repaired (a robot's choice turned into a wait) per constraint
ROBOT_BYTES = 3_000  # stored per state and robot (node, key, candidate lists): measured 2.7 kB
MEMORY = 400 << 20  # the states the search may keep, in bytes


def plan(instance: Instance, *, run: Run | None = None, improve: float = 0.0,
         max_nodes: int = 2_000_000, seed: int = 0, method: str = "lacam"):
    """LaCAM* over whole states (module docstring); a :class:`~bille.instances.result.Result`.

    Status ``feasible`` (a schedule; ``optimal`` if ``improve`` exhausts the space), ``infeasible``
    (the space is exhausted: no schedule exists), ``timeout``, or ``unsolved`` at the node cap
    (``max_nodes``, at most what :data:`MEMORY` holds: about 30,000 states of four robots).
    """
    if instance.collisions == "classic":  # the generator's cell ownership is rule 3's
        raise OptionError(f"{method}: the search over whole states plans under the Bill-E rule only")
    rng = random.Random(seed)
    space = StateSpace(instance, rng)
    per_state = instance.width * instance.height + ROBOT_BYTES * max(1, instance.num_robots)
    cap = min(max_nodes, MEMORY // per_state)
    status, steps, stats = search(space, rng, budget=(run or Run()).budget, improve=improve, max_nodes=cap,
                                  stats={"search": "whole states"})
    if status == "exhausted":
        status = "infeasible"
    result = to_result(instance, method, status, steps, stats=stats, failure=stats.pop("failure", None))
    if status == "optimal":  # every schedule searched: the makespan found is the least there is
        result = dataclasses.replace(result, lower_bound=len(steps))
    return result


class StateSpace:
    """Whole states as LaCAM*'s configurations: keys ``State.key()``, states kept beside."""

    def __init__(self, instance: Instance, rng: random.Random) -> None:
        self.instance, self.world, self.rng = instance, instance.world, rng
        self.m = instance.num_robots
        self.goal_tiles, self.goal_cells = instance.goal_tiles, instance.goal_cells
        root = instance.start_state
        self.root = root.key()
        self.states: dict[tuple, State] = {self.root: root}
        self._options: dict[tuple, list] = {}
        relaxed = [relaxed_for(g) for g in self.world.graphs]
        self._to_goal = [r.to_front(c).tolist() if c >= 0 else None for r, c in zip(relaxed, self.goal_cells)]

    # ---- the space ------------------------------------------------------------------------------

    def start(self) -> tuple:
        return self.root

    def unreachable(self) -> list[int]:
        return []  # a goal cell may become reachable once tiles move: the search finds out

    def branches(self, config: tuple, forced: tuple, i: int) -> list[int]:
        return list(range(len(self.options(config)[i])))

    def is_goal(self, config: tuple) -> bool:
        return goal_violation(self.world, self.states[config], self.goal_tiles, self.goal_cells, 0) is None

    def resting_all(self, config: tuple) -> list[bool]:
        state = self.states[config]
        return [not carrying and (cell < 0 or int(g.feet[p, 0]) == cell)
                for g, p, carrying, cell in zip(self.world.graphs, state.poses, state.carrying, self.goal_cells)]

    def first_priorities(self, config: tuple) -> list[float]:
        return [0.0] * self.m

    def h(self, config: tuple) -> int:
        state = self.states[config]
        differ = int((state.tiles != self.goal_tiles).sum())
        walk = max((d[p] for d, p in zip(self._to_goal, state.poses) if d is not None), default=0)
        return max(-(-differ // max(1, self.m)), walk)

    def cost(self, a: tuple, b: tuple) -> int:
        return 1

    # ---- the generator --------------------------------------------------------------------------

    def options(self, config: tuple) -> list[list[tuple[int, frozenset]]]:
        """Per robot, its candidate actions with their collision sets, best first (module
        docstring); the lazy constraints index into these lists."""
        got = self._options.get(config)
        if got is None:
            state = self.states[config]
            got = [self._ranked(state, i) for i in range(self.m)]
            self._options[config] = got
        return got

    def _ranked(self, state: State, i: int) -> list[tuple[int, frozenset]]:
        g, p = self.world.graphs[i], state.poses[i]
        tiles = state.tiles
        must_go = tiles & ~self.goal_tiles
        must_fill = self.goal_tiles & ~tiles
        dist = self._distances(state, i, must_go, must_fill)
        ranked = []
        for a in candidate_actions(self.instance, state, i):
            kind, target = int(g.kind[a]), int(g.target[p, a])  # plain ints: numpy meets no enum
            if kind == Kind.PICK:
                score = -1 if must_go[target] else UNREACHABLE + 1
            elif kind == Kind.PLACE:
                score = -1 if must_fill[target] else UNREACHABLE + 1
            else:
                score = UNREACHABLE if dist is None else int(dist[g.succ[p, a]])
            ranked.append((score, a != g.wait, self.rng.random(), a))
        ranked.sort()
        return [(a, collision_cells(self.instance, state, i, a)) for *_, a in ranked]

    def _distances(self, state: State, i: int, must_go: np.ndarray, must_fill: np.ndarray):
        """Robot ``i``'s distances on the current structure to the poses facing the cells it
        should work on next (module docstring), or to its goal cell; None: anywhere will do."""
        g = self.world.graphs[i]
        carrying = state.carrying[i]
        walk = walk_for(g, state.tiles, carrying)
        if carrying:
            cells = np.flatnonzero(must_fill)
        else:
            cut = articulation_points(state.tiles, self.world.width, self.world.height)
            cells = np.flatnonzero(must_go & ~cut)
            if not len(cells):
                cells = np.flatnonzero(must_go)
        if len(cells):
            key = ("work", carrying, cells.tobytes())
            return walk.distances_to(key, lambda: walk.facing_any(cells))
        cell = self.goal_cells[i]
        return walk.distances(cell) if cell >= 0 else None

    def generate(self, config: tuple, order: list[int], forced: tuple, first: bool):
        state = self.states[config]
        options = self.options(config)
        m = self.m
        mine = {}  # the cells robots stand on (their wait's collision set): nobody else's
        for i in range(m):
            wait = self.world.graphs[i].wait
            mine.update(dict.fromkeys(next(cells for a, cells in options[i] if a == wait), i))
        choice: list[int | None] = [None] * m
        used: set[int] = set()
        pinned = set()
        for i, k in forced:
            a, cells = options[i][k]
            if not used.isdisjoint(cells) or any(mine.get(c, i) != i for c in cells):
                return None
            choice[i] = a
            used |= cells
            pinned.add(i)
        for i in order:
            if choice[i] is not None:
                continue
            for a, cells in options[i]:
                if used.isdisjoint(cells) and all(mine.get(c, i) == i for c in cells):
                    choice[i] = a
                    used |= cells
                    break
            else:
                return None  # even its wait collides with a pinned robot
        for _ in range(RETRIES + 1):
            nxt = apply(self.world, state, choice)
            if isinstance(nxt, State):
                key = nxt.key()
                self.states.setdefault(key, nxt)
                return tuple(choice), key
            culprit = self._culprit(nxt, choice, pinned, order)
            if culprit is None:
                return None
            choice[culprit] = self.world.graphs[culprit].wait
            pinned.add(culprit)
        return None

    def _culprit(self, violation, choice: list[int], pinned: set[int], order: list[int]) -> int | None:
        """The robot whose choice to undo after ``violation``: the one it names, or (a cut
        structure names none) the last in ``order`` that picks or places."""
        if violation.robot is not None:
            return None if violation.robot in pinned else violation.robot
        for i in reversed(order):
            g = self.world.graphs[i]
            if i not in pinned and int(g.kind[choice[i]]) in (Kind.PICK, Kind.PLACE):
                return i
        return None
