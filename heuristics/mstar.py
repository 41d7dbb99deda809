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

The objective is the sum of costs, ties broken by makespan, as for joint A*; ``epsilon``
inflates the heuristic (``f = g + epsilon * h``) for a sum of costs within ``epsilon`` times the
optimum.
"""
from __future__ import annotations

import heapq
import itertools
import time

from bille.instances import Instance, OptionError

from .joint import JointProblem, makespan_bound, to_result


def plan(instance: Instance, *, epsilon: float = 1.0, time_limit: float | None = None,
         max_expansions: int = 5_000_000):
    """M*: minimum sum of costs (then makespan) on a fixed structure.

    Parameters
    ----------
    epsilon : inflation of the heuristic (>= 1); 1 gives optimal plans.
    time_limit : seconds before giving up with status ``timeout``.
    max_expansions : expansions before giving up with status ``timeout``.
    """
    if epsilon < 1:
        raise OptionError(f"mstar: epsilon must be >= 1, got {epsilon}")
    start_time = time.perf_counter()
    deadline = None if time_limit is None else start_time + time_limit
    problem = JointProblem.of(instance)
    bound = makespan_bound(problem)
    stats = {"objective": "sum of costs, then makespan", "epsilon": epsilon, "expanded": 0,
             "generated": 0, "largest_collision_set": 0}
    if problem.unreachable():
        stats["unreachable"] = problem.unreachable()
        return to_result(instance, "mstar", "infeasible", None, lower_bound=None, stats=stats)

    m = instance.num_robots
    policy = [_policy(problem, i) for i in range(m)]
    root = (problem.start, (0,) * m)
    g = {root: (0, 0)}
    parent: dict = {root: None}
    collision: dict = {root: frozenset()}
    back: dict = {root: set()}
    expanded_as: dict = {}  # vertex -> (g, collision set) of its last expansion
    counter = itertools.count()
    frontier: list = []

    def push(key):
        h = problem.h(key[0])
        gk = g[key]
        heapq.heappush(frontier, (gk[0] + epsilon * h[0], gk[1] + h[1], next(counter), key))

    def backprop(key, robots: frozenset):
        todo = [(key, robots)]
        while todo:
            v, c = todo.pop()
            if c <= collision[v]:
                continue
            collision[v] = collision[v] | c
            stats["largest_collision_set"] = max(stats["largest_collision_set"], len(collision[v]))
            push(v)
            todo.extend((u, collision[v]) for u in back[v])

    push(root)
    while frontier:
        _, _, _, key = heapq.heappop(frontier)
        state = (g[key], collision[key])
        if expanded_as.get(key) == state:
            continue  # stale: already expanded with this cost and collision set
        expanded_as[key] = state
        poses, debts = key
        if problem.is_goal(poses):
            stats["sum_of_costs"] = g[key][0]
            status = "optimal" if epsilon == 1 else "feasible"
            return to_result(instance, "mstar", status, _unwind(parent, key), lower_bound=bound, stats=stats)
        stats["expanded"] += 1
        if stats["expanded"] > max_expansions or (deadline is not None and time.perf_counter() > deadline):
            return to_result(instance, "mstar", "timeout", None, lower_bound=bound, stats=stats)

        coupled = collision[key]
        options = [problem.moves(i, p) if i in coupled else policy[i](p) for i, p in enumerate(poses)]
        psi = _colliding(problem, options, coupled)
        if psi:
            backprop(key, psi)
        g_soc, g_t = g[key]
        for actions, nxt in problem.joint_moves(poses, options):
            cost, new_debts = problem.transition(poses, debts, nxt)
            child = (nxt, new_debts)
            if child not in g:
                g[child], collision[child], back[child] = (1 << 60, 0), frozenset(), set()
            back[child].add(key)
            if collision[child]:
                backprop(key, collision[child])
            new_g = (g_soc + cost, g_t + 1)
            if new_g < g[child]:
                g[child] = new_g
                parent[child] = (key, actions)
                stats["generated"] += 1
                push(child)
    return to_result(instance, "mstar", "infeasible", None, lower_bound=None, stats=stats)


def _policy(problem: JointProblem, i: int):
    """Robot ``i``'s individually optimal move from a pose, as a one-element move list."""
    walk, goal, cache = problem.walks[i], problem.goals[i], {}

    def move(pose: int):
        if pose not in cache:
            nxt = walk.policy(pose, goal) if goal >= 0 else pose
            cache[pose] = problem.moves(i, pose, only=nxt)
        return cache[pose]

    return move


def _colliding(problem: JointProblem, options: list[list], coupled: frozenset) -> frozenset:
    """Robots that collide in some limited neighbour, where at least one of a colliding pair is
    not yet coupled (pairs inside the collision set are already planned jointly)."""
    hit: set[int] = set()
    m = len(options)
    for i, j in itertools.combinations(range(m), 2):
        if i in coupled and j in coupled:
            continue
        if any(not a[2].isdisjoint(b[2]) for a in options[i] for b in options[j]):
            hit.update((i, j))
    return frozenset(hit)


def _unwind(parent: dict, key) -> list:
    steps = []
    while parent[key] is not None:
        key, actions = parent[key]
        steps.append(actions)
    return steps[::-1]
