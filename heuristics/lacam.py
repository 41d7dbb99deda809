"""LaCAM*: a complete, anytime search over joint configurations (Okumura, AAAI 2023, IJCAI 2023).

The high level is a depth-first search over *configurations* (one pose per robot). Each node
lazily enumerates *constraints*: "robot ``order[0]`` makes move ``k0``", then also "robot
``order[1]`` makes move ``k1``", and so on, one robot deeper each time a constraint is taken
(a breadth-first tree of constraints under every node). A constraint is handed to the
*configuration generator*, which completes it to a next configuration or says it cannot. The
first successor of a node is the generator's free choice; as the search comes back to a node,
ever more robots are pinned, until every joint move has been tried. A configuration seen before
is not a new node: the search goes back to it (and, LaCAM*, records the edge and rewires the
cheaper parent with a Dijkstra update). So the search is **complete** on its finite space:
every joint walking move of every reachable configuration is eventually generated, and the
search ends only when a goal configuration is found or the space is exhausted. After the first
schedule it keeps going (**anytime**): nodes whose cost plus an admissible estimate cannot beat
the best schedule are dropped, and when nothing is left the best schedule is optimal for the
objective (among walking schedules).

**The configuration generator** is PIBT (priority inheritance with backtracking, Okumura et al.,
AIJ 2022) adapted to robots whose moves occupy collision sets (DESIGN §3, rule 3: two feet,
swept cells, carried tiles). Under rule 3 a robot's collision set contains its cells before the
step, so no robot ever enters a cell another robot stands on *in the same step*: the classic
"push the robot ahead and follow it" is not a move here. Priority inheritance therefore acts
one step ahead: a robot whose best move is blocked by robots still to be decided *pushes* them
(they are decided now, preferring moves that leave the cells it wants), then takes its best
move that is free (waiting, at worst, which is always free). Robots are decided in the order of
the node's priorities: a robot away from its goal gains priority every step, one that arrives
drops back (LaCAM's rule), so no robot is starved.

With ``collisions: classic`` (point robots, DESIGN §3) the generator is the original PIBT:
a robot may follow into a cell vacated in the same step, a pushed robot must leave the cell
its pusher wants, and a push that fails makes the pusher try its next cell.

Objectives (``objective``): ``makespan`` (every step costs 1; estimate: the largest distance
to a goal) or ``sum-of-loss`` (every step costs the number of robots not resting at their goal;
estimate: the summed distances), both over walking schedules (no pick or place).
"""
from __future__ import annotations

import random
import time
from collections import deque
from dataclasses import dataclass, field

from bille.instances import Instance, OptionError

from .joint import NO_WALK, JointProblem, to_result

OBJECTIVES = ("makespan", "sum-of-loss")
RESTART = 0.001  # chance per iteration, while improving, to go back to the start configuration
Poses = tuple[int, ...]


@dataclass(eq=False)
class _Node:
    """A configuration in the high-level search."""

    config: Poses
    parent: "_Node | None"
    actions: tuple[int, ...] | None  # the joint action from the parent
    g: int
    h: int
    priority: list[float]
    order: list[int]
    tree: deque = field(default_factory=deque)  # constraints still to try: tuples of (robot, move)
    edges: dict = field(default_factory=dict)  # successor node -> (joint action, cost)


def plan(instance: Instance, *, objective: str = "makespan", time_limit: float | None = None,
         improve: float = 1.0, max_nodes: int = 2_000_000, seed: int = 0):
    """LaCAM* on a fixed structure (the method ``lacam`` hands an instance that moves tiles to
    the reconfiguration loop with LaCAM* as its motion layer).

    Parameters
    ----------
    objective : ``makespan`` or ``sum-of-loss`` (module docstring).
    time_limit : seconds for the whole run; without a first schedule by then, status ``timeout``.
    improve : seconds spent improving the first schedule (0: stop at the first one), within
        ``time_limit``.
    max_nodes : configurations stored before giving up (``unsolved``) or stopping the improvement.
    seed : the generator's tie-breaking (results are repeatable for a seed).

    Status ``optimal`` (with ``stats["objective"]``) when the improvement exhausts the search
    space, ``feasible`` otherwise; ``unsolved`` when the space holds no walking schedule (a
    schedule that moves tiles out of the way and back is outside it).
    """
    problem = JointProblem.of(instance, "lacam")
    status, steps, stats = joint_plan(problem, objective=objective, time_limit=time_limit, improve=improve,
                                      max_nodes=max_nodes, seed=seed)
    return to_result(instance, "lacam", status, steps, stats=stats)


def joint_plan(problem: JointProblem, *, objective: str = "makespan", time_limit: float | None = None,
               improve: float = 0.0, max_nodes: int = 2_000_000, seed: int = 0,
               pinned: dict[int, frozenset] | None = None) -> tuple[str, list | None, dict]:
    """LaCAM* on any :class:`JointProblem`: ``(status, joint actions or None, stats)``.

    ``pinned``: robots that wait in the first step while holding the given cells (the
    reconfiguration loop's picks and places, which replace those waits); the search space is
    then the schedules that start so."""
    if objective not in OBJECTIVES:
        raise OptionError(f"lacam: unknown objective '{objective}' (expected one of: {', '.join(OBJECTIVES)})")
    if improve < 0:
        raise OptionError(f"lacam: improve must be >= 0 seconds, got {improve}")
    return _LaCAM(problem, objective, time_limit, improve, max_nodes, seed, pinned or {}).run()


def next_configuration(walks: list, dist_lists: list[list[int]], config: Poses, order: list[int],
                       pinned: dict[int, frozenset], rng: random.Random,
                       wants: dict[int, frozenset] | None = None) -> tuple[tuple[int, ...], Poses]:
    """One free step of the configuration generator (PIBT for collision sets, module docstring):
    robots on ``walks`` at ``config``, each drawn towards lower ``dist_lists[i]``, decided in
    ``order``; ``pinned`` robots wait holding the given cells; ``wants``: robots that wait for
    the given cells, whose occupants are pushed off them first. Returns ``(joint action, next
    poses)``; never fails (waiting is always free) unless the pinned cells overlap."""
    step = _Step(walks, dist_lists)
    got = _Bille(_Search(step, rng)).generate(config, order, (), pinned, wants)
    if got is None:
        raise ValueError("pinned cells overlap another robot")
    return got


@dataclass
class _Step:
    """The part of a :class:`JointProblem` the generator reads, built from ready lists."""

    walks: list
    dist_lists: list

    def moves(self, i: int, pose: int):
        return self.walks[i].moves(pose)


@dataclass
class _Search:
    problem: _Step
    rng: random.Random


class _LaCAM:
    def __init__(self, problem: JointProblem, objective, time_limit, improve, max_nodes, seed, pinned) -> None:
        self.problem, self.pinned = problem, pinned
        self.m = len(problem.walks)
        self.makespan = objective == "makespan"
        self.start = time.perf_counter()
        self.deadline = None if time_limit is None else self.start + time_limit
        self.improve, self.max_nodes = improve, max_nodes
        self.rng = random.Random(seed)
        self.classic = problem.instance.collisions == "classic"
        self.generator = _Classic(self) if self.classic else _Bille(self)
        self.stats: dict = {"objective": f"{objective}, walking only (no pick or place)", "nodes": 0,
                            "generated": 0, "improvements": []}

    # ---- costs ----------------------------------------------------------------------------------

    def h(self, config: Poses) -> int:
        ds = [d[p] for d, p in zip(self.problem.dist_lists, config)]
        return max(ds, default=0) if self.makespan else sum(ds)

    def cost(self, a: Poses, b: Poses) -> int:
        if self.makespan:
            return 1
        at = self.problem.at_goal
        return sum(1 for i, (p, q) in enumerate(zip(a, b)) if not (p == q and at(i, q)))

    def node(self, config: Poses, parent: _Node | None, actions, g: int) -> _Node:
        if parent is None:
            dist = self.problem.dist_lists
            priority = [d[p] / 10_000 for d, p in zip(dist, config)]
        else:
            at = self.problem.at_goal
            priority = [v - int(v) if at(i, p) else v + 1 for i, (v, p) in enumerate(zip(parent.priority, config))]
        order = sorted(range(self.m), key=lambda i: -priority[i])
        node = _Node(config, parent, actions, g, self.h(config), priority, order)
        node.tree.append(())
        self.stats["nodes"] += 1
        return node

    # ---- the search -------------------------------------------------------------------------------

    def run(self) -> tuple[str, list | None, dict]:
        if self.problem.unreachable():
            self.stats["unreachable"] = self.problem.unreachable()
            self.stats["failure"] = "unreachable"
            return "unsolved", None, self.stats
        root = self.node(tuple(self.problem.start), None, None, 0)
        explored = {root.config: root}
        self.open: list[_Node] = [root]
        self.best: _Node | None = None
        stop_at = self.deadline
        exhausted = True
        while self.open:
            if stop_at is not None and time.perf_counter() > stop_at:
                exhausted = False
                break
            if self.best is not None and self.rng.random() < RESTART:
                self.open.append(root)  # lacam3's random insertion: search again from the start
            node = self.open[-1]
            if self.best is not None and node.g + node.h >= self.best.g:
                self.open.pop()
                continue
            if self.problem.is_goal(node.config):
                self._found(node)
                self.open.pop()
                if self.improve == 0:
                    exhausted = False
                    break
                stop_at = self._improvement_deadline()
                continue
            if not node.tree:
                self.open.pop()
                continue
            forced = node.tree.popleft()
            if len(forced) < self.m:
                i = node.order[len(forced)]
                moves = list(range(len(self.problem.moves(i, node.config[i]))))
                self.rng.shuffle(moves)
                node.tree.extend(forced + ((i, k),) for k in moves)
            got = self.generator.generate(node.config, node.order, forced, self.pinned if node is root else {})
            if got is None:
                continue
            actions, nxt = got
            self.stats["generated"] += 1
            cost = self.cost(node.config, nxt)
            known = explored.get(nxt)
            if known is None:
                if len(explored) >= self.max_nodes:
                    exhausted = False
                    if self.best is None:
                        self.stats["failure"] = "node cap"
                    break
                child = self.node(nxt, node, actions, node.g + cost)
                node.edges[child] = (actions, cost)
                explored[nxt] = child
                self.open.append(child)
            else:
                node.edges.setdefault(known, (actions, cost))
                self._rewire(node)
                self.open.append(known)
        self.stats["time_s"] = round(time.perf_counter() - self.start, 6)
        if self.best is None:
            if "failure" in self.stats:
                return "unsolved", None, self.stats
            if exhausted:
                self.stats["failure"] = NO_WALK
                return "unsolved", None, self.stats
            self.stats["failure"] = "time limit"
            return "timeout", None, self.stats
        self.stats["cost"] = self.best.g
        return ("optimal" if exhausted else "feasible"), self._steps(self.best), self.stats

    def _improvement_deadline(self) -> float:
        end = time.perf_counter() + self.improve
        return end if self.deadline is None else min(end, self.deadline)

    def _found(self, node: _Node) -> None:
        if self.best is None or node.g < self.best.g:
            elapsed = round(time.perf_counter() - self.start, 6)
            if self.best is None:
                self.stats["first_s"], self.stats["first_cost"] = elapsed, node.g
            self.best = node
            self.stats["improvements"].append([elapsed, node.g])

    def _rewire(self, root: _Node) -> None:
        """LaCAM*'s Dijkstra update: lower the cost of every node reachable from ``root`` through
        known edges where ``root``'s path is cheaper, re-parenting it; a node whose estimate now
        beats the best schedule goes back on the stack."""
        queue = deque([root])
        while queue:
            node = queue.popleft()
            for child, (actions, cost) in node.edges.items():
                if node.g + cost < child.g:
                    child.g, child.parent, child.actions = node.g + cost, node, actions
                    queue.append(child)
                    if self.best is not None and child.g + child.h < self.best.g:
                        self.open.append(child)
                    if self.problem.is_goal(child.config):
                        self._found(child)

    @staticmethod
    def _steps(node: _Node) -> list[tuple[int, ...]]:
        steps = []
        while node.parent is not None:
            steps.append(node.actions)
            node = node.parent
        return steps[::-1]


class _Bille:
    """PIBT for rule 3 (module docstring): the pushed robots move now, the pusher next step."""

    def __init__(self, search: _LaCAM) -> None:
        self.problem, self.rng = search.problem, search.rng

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


class _Classic:
    """PIBT with classic collisions (point robots): vertex and swap conflicts only."""

    def __init__(self, search: _LaCAM) -> None:
        self.problem, self.rng = search.problem, search.rng

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
            j = self.here.get(q)
            if q in self.next_at or (j is not None and j != i and self.choice[j] is not None
                                     and self.moves[j][self.choice[j]][1] == config[i]):
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
            j = self.here.get(q)
            if j is not None and j != i and self.choice[j] is not None and self.moves[j][self.choice[j]][1] == self.config[i]:
                continue  # j already moves into i's cell: a swap
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
