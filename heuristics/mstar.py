"""M*: subdimensional expansion (Wagner & Choset; paper, Methods, "Graph representation").

Each robot follows its individually optimal policy (a shortest walk to its goal, waiting there)
until robots collide. A vertex's *collision set* names the robots that must be planned jointly
there; it starts empty, so expanding a vertex usually generates one neighbour. When a move from
vertex ``v`` makes robots collide (their collision sets meet: a swap, a follow, a sweep), those
robots join ``v``'s collision set, and the growth is *back-propagated* to every vertex that
reaches ``v``, which is then expanded again with the larger set. On crowded maps most vertices
end up coupling every robot and M* becomes joint A*.

Collisions here happen on transitions, so a transition's colliding robots join the collision set
of the vertex the transition leaves: that is where their choices must differ.

*Operator decomposition* (``od=True``, Standley; ODrM* of Ferner, Wagner & Choset) expands the
coupled robots one at a time through intermediate nodes, so a fully coupled vertex of ``k``
robots with ``b`` moves each has ``b`` children instead of ``b**k``, and the heuristic prunes
partial assignments early.

The objective is the sum of costs, ties broken by makespan, as for joint A*; ``epsilon``
inflates the heuristic (``f = g + epsilon * h``) for a sum of costs within ``epsilon`` times the
optimum.
"""
from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

from bille.instances import Instance
from bille.instances.failure import CANNOT_REACH, Failure, cap
from bille.instances.options import option
from bille.instances.run import Budget, Run

from .joint import CLAIM, NO_WALK, JointProblem, OutOfTime, to_result, unwind
from .loop.loop_options import LoopOptions

INF = (1 << 60, 0)


@dataclass(frozen=True)
class Options(LoopOptions):
    """``epsilon``: inflation of the heuristic (1 gives optimal plans); ``od``: expand coupled
    robots one at a time (operator decomposition); ``max_expansions``: expansions (of vertices
    and intermediate nodes) before ``unsolved``. The loop's options are for instances that move
    tiles."""

    METHOD = "mstar"
    epsilon: float = option(1.0, at_least=1,
                            help="inflation of the heuristic (1 gives optimal plans)", aliases=("eps",))
    od: bool = option(True, help="expand coupled robots one at a time (operator decomposition)")
    max_expansions: int = option(5_000_000, at_least=1,
                                 help="expansions (vertices and intermediate nodes) before giving up")


def method(instance: Instance, options: Options | None = None, run: Run | None = None):
    """The method ``mstar``: M* (:func:`plan`) on a fixed structure; on an instance that moves
    tiles, the reconfiguration loop with M* as its motion layer (not optimal)."""
    from .loop import reconfigure

    o = options or Options()
    if instance.is_reconfiguration:
        return reconfigure.plan(instance, o, run, motion="mstar")
    return plan(instance, o, run)


def plan(instance: Instance, options: Options | None = None, run: Run | None = None):
    """M*: minimum sum of costs (then makespan) on a fixed structure (:class:`Options`; the method
    ``mstar`` hands an instance that moves tiles to the reconfiguration loop, :mod:`.reconfigure`,
    with M* as its motion layer, which is not optimal). When the run's budget expires, status
    ``timeout`` (no run: no limit).
    """
    o = options or Options()
    budget = (run or Run()).budget
    return _MStar(JointProblem.of(instance, "mstar"), o.epsilon, o.od, budget, o.max_expansions).run()


def joint_plan(problem: JointProblem, *, epsilon: float = 1.0, od: bool = True, budget: Budget | None = None,
               max_expansions: int = 5_000_000) -> tuple[str, list | None, dict]:
    """M* on any :class:`JointProblem` within ``budget`` (None: no limit): ``(status, joint
    actions or None, stats)``."""
    search = _MStar(problem, epsilon, od, budget or Budget(), max_expansions)
    status, steps = search.search()
    return status, steps, search.stats


class _MStar:
    def __init__(self, problem: JointProblem, epsilon, od, budget: Budget, max_expansions):
        self.instance, self.epsilon, self.od = problem.instance, epsilon, od
        self.budget = budget
        self.max_expansions = max_expansions
        self.problem = problem
        self.policy = [_policy(self.problem, i) for i in range(len(problem.walks))]
        self.stats = {"epsilon": epsilon, "od": od,
                      "expanded": 0, "generated": 0, "largest_collision_set": 0}
        self.g: dict = {}
        self.parent: dict = {}
        self.collision: dict = {}
        self.back: dict = {}
        self.expanded_as: dict = {}
        self.counter = itertools.count()
        self.frontier: list = []
        self.failure: Failure | None = None

    # ---- bookkeeping -------------------------------------------------------------------------

    def push(self, node, g, h):
        heapq.heappush(self.frontier, (g[0] + self.epsilon * h[0], g[1] + h[1], next(self.counter), node))

    def push_vertex(self, key):
        self.push(key, self.g[key], self.problem.h(key[0]))

    def backprop(self, key, robots: frozenset):
        todo = [(key, robots)]
        while todo:
            v, c = todo.pop()
            if c <= self.collision[v]:
                continue
            self.collision[v] = self.collision[v] | c
            self.stats["largest_collision_set"] = max(self.stats["largest_collision_set"], len(self.collision[v]))
            self.push_vertex(v)
            todo.extend((u, self.collision[v]) for u in self.back[v])

    def reach(self, root, actions, nxt, new_debts, new_g):
        """Record a transition from vertex ``root`` to the vertex ``(nxt, new_debts)``."""
        child = (nxt, new_debts)
        if child not in self.g:
            self.g[child], self.collision[child], self.back[child] = INF, frozenset(), set()
        self.back[child].add(root)
        if self.collision[child]:
            self.backprop(root, self.collision[child])
        if new_g < self.g[child]:
            self.g[child] = new_g
            self.parent[child] = (root, actions)
            self.stats["generated"] += 1
            self.push_vertex(child)

    # ---- search ------------------------------------------------------------------------------

    def run(self):
        problem, stats, instance = self.problem, self.stats, self.instance
        if problem.unreachable():
            stats["unreachable"] = problem.unreachable()
            return to_result(instance, "mstar", "unsolved", None, stats=stats, claim=CLAIM, failure=CANNOT_REACH)
        status, steps = self.search()
        return to_result(instance, "mstar", status, steps, stats=stats, claim=CLAIM, failure=self.failure)

    def search(self) -> tuple[str, list | None]:
        """``(status, joint actions or None)``; without a schedule, why in :attr:`failure`."""
        problem, stats = self.problem, self.stats
        root = (problem.start, (0,) * len(problem.walks))
        self.g[root], self.parent[root], self.collision[root], self.back[root] = (0, 0), None, frozenset(), set()
        self.push_vertex(root)
        while self.frontier:
            *_, node = heapq.heappop(self.frontier)
            if node[0] == "od":  # a partial step: many of them per state with many coupled robots
                if self.budget.expired():
                    self.failure = self.budget.why()
                    return "timeout", None
                self.expand_partial(node)
                continue
            state = (self.g[node], self.collision[node])
            if self.expanded_as.get(node) == state:
                continue  # stale: already expanded with this cost and collision set
            self.expanded_as[node] = state
            if problem.is_goal(node[0]):
                stats["sum_of_costs"] = self.g[node][0]
                return ("optimal" if self.epsilon == 1 else "feasible"), unwind(self.parent, node)
            stats["expanded"] += 1
            if stats["expanded"] > self.max_expansions:
                self.failure = cap("expansion cap")
                return "unsolved", None
            try:
                if self.budget.expired():
                    raise OutOfTime
                self.expand(node)
            except OutOfTime:
                self.failure = self.budget.why()
                return "timeout", None
        self.failure = NO_WALK
        return "unsolved", None

    def expand(self, key):
        problem = self.problem
        poses, debts = key
        coupled = self.collision[key]
        options = [problem.moves(i, p) if i in coupled else self.policy[i](p) for i, p in enumerate(poses)]
        psi = _colliding(options, coupled)
        if psi:
            self.backprop(key, psi)
        g_soc, g_t = self.g[key]
        if not self.od or len(coupled) <= 1:
            for actions, nxt in problem.joint_moves(poses, options, self.budget):
                cost, new_debts = problem.transition(poses, debts, nxt)
                self.reach(key, actions, nxt, new_debts, (g_soc + cost, g_t + 1))
            return
        # operator decomposition: the uncoupled robots move by policy now, the coupled ones
        # are assigned one at a time by expand_partial
        order = tuple(sorted(coupled))
        fixed = {i: options[i][0] for i in range(len(poses)) if i not in coupled and options[i]}
        if len(fixed) + len(coupled) < len(poses):
            return  # an uncoupled robot has no move at all (cannot happen: waiting is a move)
        partial = ("od", key, order, ())
        self.push(partial, (g_soc, g_t + 1), self._partial_h(poses, order, (), {}))

    def expand_partial(self, node):
        """Assign the next coupled robot's move (operator decomposition)."""
        _, root, order, assigned = node
        if self.collision[root] != frozenset(order):
            return  # the root's collision set grew: it was expanded again with the larger set
        problem, poses, debts = self.problem, root[0], root[1]
        self.stats["expanded"] += 1
        j = len(assigned)
        robot = order[j]
        taken = [cells for (_, _, cells) in assigned]
        coupled = frozenset(order)
        uncoupled = {i: self.policy[i](p)[0] for i, p in enumerate(poses) if i not in coupled}
        for a, q, cells in problem.moves(robot, poses[robot]):
            if any(not cells.isdisjoint(t) for t in taken):
                continue
            hit = frozenset(i for i, m in uncoupled.items() if not cells.isdisjoint(m[2]))
            if hit:
                self.backprop(root, hit | {robot})
                continue
            now = assigned + ((a, q, cells),)
            if len(now) < len(order):
                g = self._partial_g(root, order, now, uncoupled)
                self.push(("od", root, order, now), g, self._partial_h(poses, order, now, uncoupled))
                continue
            actions = [0] * len(poses)
            nxt = list(poses)
            for r, (aa, qq, _) in zip(order, now):
                actions[r], nxt[r] = aa, qq
            for i, m in uncoupled.items():
                actions[i], nxt[i] = m[0], m[1]
            nxt = tuple(nxt)
            cost, new_debts = problem.transition(poses, debts, nxt)
            g_soc, g_t = self.g[root]
            self.reach(root, tuple(actions), nxt, new_debts, (g_soc + cost, g_t + 1))

    def _partial_h(self, poses, order, assigned, uncoupled):
        """Heuristic of a partial step: moved robots from their new pose; a robot still to be
        assigned has this step ahead of it, so it counts its distance for the sum of costs and
        one less for the makespan (both admissible and consistent along the chain)."""
        dist = self.problem.dist_lists
        moved = {r: q for r, (_, q, _) in zip(order, assigned)}
        moved.update((i, m[1]) for i, m in uncoupled.items())
        soc, span = 0, 0
        for i, p in enumerate(poses):
            if i in moved:
                d = dist[i][moved[i]]
                soc, span = soc + d, max(span, d)
            else:
                d = dist[i][p]
                soc, span = soc + d, max(span, d - 1)
        return soc, span

    def _partial_g(self, root, order, assigned, uncoupled):
        """Cost so far of a partial step: the root's cost plus the moves assigned (and the
        uncoupled robots' policy moves)."""
        problem, (poses, debts) = self.problem, root
        g_soc, g_t = self.g[root]
        for r, (_, q, _) in zip(order, assigned):
            g_soc += problem.step_cost(r, poses[r], q, debts[r])[0]
        for i, m in uncoupled.items():
            g_soc += problem.step_cost(i, poses[i], m[1], debts[i])[0]
        return g_soc, g_t + 1


def _policy(problem: JointProblem, i: int):
    """Robot ``i``'s individually optimal move from a pose, as a one-element move list."""
    walk, goal, dist, cache = problem.walks[i], problem.goals[i], problem.dists[i], {}

    def move(pose: int):
        if pose not in cache:
            nxt = walk.towards(pose, dist) if goal >= 0 else pose
            cache[pose] = problem.moves(i, pose, only=nxt)
        return cache[pose]

    return move


def _colliding(options: list[list], coupled: frozenset) -> frozenset:
    """Robots that collide in some limited neighbour, where at least one of a colliding pair is
    not yet coupled (pairs inside the collision set are already planned jointly)."""
    hit: set[int] = set()
    for i, j in itertools.combinations(range(len(options)), 2):
        if i in coupled and j in coupled:
            continue
        if any(not a[2].isdisjoint(b[2]) for a in options[i] for b in options[j]):
            hit.update((i, j))
    return frozenset(hit)
