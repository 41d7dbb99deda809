"""Joint A* over all robots' poses at once (paper, Methods, "Graph representation", eq. (1)).

Every expansion tries every combination of the robots' walking actions whose collision sets are
pairwise disjoint, so the branching factor grows exponentially with the number of robots: the
paper's baseline. ``f = g + epsilon * h`` with ``g`` the sum of costs so far and ``h`` the sum of
the robots' breadth-first distances to their goals (admissible and consistent); ties are broken
by makespan. With ``epsilon = 1`` the result is optimal; with ``epsilon > 1`` its sum of costs is
at most ``epsilon`` times the optimum.
"""
from __future__ import annotations

import heapq
import itertools
from dataclasses import dataclass

from bille.instances import Instance
from bille.instances.failure import CANNOT_REACH, cap
from bille.instances.options import MethodOptions, option
from bille.instances.run import Run

from .joint import CLAIM, NO_WALK, JointProblem, OutOfTime, to_result, unwind


@dataclass(frozen=True)
class Options(MethodOptions):
    """``epsilon``: weight of the heuristic (1 gives optimal plans); ``max_expansions``:
    expansions before giving up with status ``unsolved``."""

    METHOD = "astar"
    epsilon: float = option(1.0, at_least=1,
                            help="weight of the heuristic: plans cost at most epsilon times optimal; 1 is "
                                 "optimal", aliases=("eps",))
    max_expansions: int = option(5_000_000, at_least=1, help="expansions before giving up (status unsolved)")


def plan(instance: Instance, options: Options | None = None, run: Run | None = None):
    """Joint A*: minimum sum of costs (then makespan) on a fixed structure (:class:`Options`);
    when the run's budget expires, status ``timeout`` (no run: no limit).

    A search that runs out of walking states says ``unsolved``, not ``infeasible``: a schedule
    that picks and places tiles (to make room, and back) is outside its search space.
    """
    options = options or Options()
    epsilon, max_expansions = options.epsilon, options.max_expansions
    budget = (run or Run()).budget
    problem = JointProblem.of(instance, "astar")
    stats = {"epsilon": epsilon, "expanded": 0, "generated": 0}
    if problem.unreachable():
        stats["unreachable"] = problem.unreachable()
        return to_result(instance, "astar", "unsolved", None, stats=stats, claim=CLAIM, failure=CANNOT_REACH)

    m = instance.num_robots
    root = (problem.start, (0,) * m)
    best = {root: (0, 0)}
    parent: dict = {root: None}
    closed: set = set()
    counter = itertools.count()
    h0 = problem.h(problem.start)
    frontier = [(epsilon * h0[0], h0[1], next(counter), root)]
    while frontier:
        _, _, _, key = heapq.heappop(frontier)
        if key in closed:
            continue
        closed.add(key)
        poses, debts = key
        g_soc, g_t = best[key]
        if problem.is_goal(poses):
            stats["sum_of_costs"] = g_soc
            status = "optimal" if epsilon == 1 else "feasible"
            return to_result(instance, "astar", status, unwind(parent, key), stats=stats, claim=CLAIM)
        stats["expanded"] += 1
        if stats["expanded"] > max_expansions:
            return to_result(instance, "astar", "unsolved", None, stats=stats, claim=CLAIM,
                             failure=cap("expansion cap"))
        try:
            if budget.expired():
                raise OutOfTime
            options = [problem.moves(i, p) for i, p in enumerate(poses)]
            for actions, nxt in problem.joint_moves(poses, options, budget):
                cost, new_debts = problem.transition(poses, debts, nxt)
                child = (nxt, new_debts)
                g = (g_soc + cost, g_t + 1)
                if child in closed or (child in best and best[child] <= g):
                    continue
                best[child] = g
                parent[child] = (key, actions)
                h = problem.h(nxt)
                stats["generated"] += 1
                heapq.heappush(frontier, (g[0] + epsilon * h[0], g[1] + h[1], next(counter), child))
        except OutOfTime:  # before the expansion, or within it (many robots: millions of children)
            return to_result(instance, "astar", "timeout", None, stats=stats, claim=CLAIM, failure=budget.why())
    return to_result(instance, "astar", "unsolved", None, stats=stats, claim=CLAIM, failure=NO_WALK)
