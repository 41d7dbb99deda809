"""Brute-force optimal sum of costs by a formulation independent of the planners' debts.

A robot's cost is the step at which it reaches its goal for the last time. Equivalently: after
any step, a robot standing on its goal may *commit* to stay there for good; every uncommitted
robot pays 1 per step, and a committed robot must keep its front foot on its goal. A uniform-cost
search over (poses, committed robots), with every joint walking action checked by the rules,
returns the minimum (sum of costs, makespan).
"""
from __future__ import annotations

import heapq
import itertools

from bille.instances.moveset import Kind
from bille.instances.rules import State, apply
from bille.instances.successors import candidate_actions


def optimal_soc(instance, max_states: int = 200_000) -> tuple[int, int] | None:
    world = instance.world
    goals = instance.goal_cells
    m = instance.num_robots

    def home(i, pose):
        return goals[i] < 0 or int(world.graphs[i].feet[pose, 0]) == goals[i]

    def commits(poses, committed):
        free = [i for i in range(m) if i not in committed and home(i, poses[i])]
        for k in range(len(free) + 1):
            for extra in itertools.combinations(free, k):
                yield committed | frozenset(extra)

    start = instance.start_state
    frontier, best = [], {}
    for c in commits(start.poses, frozenset()):
        best[(start.poses, c)] = (0, 0)
        heapq.heappush(frontier, (0, 0, start.poses, tuple(sorted(c)), start))
    while frontier:
        cost, t, poses, c, state = heapq.heappop(frontier)
        c = frozenset(c)
        if best.get((poses, c)) != (cost, t):
            continue
        if len(c) == m:
            return cost, t
        if len(best) > max_states:
            raise RuntimeError("brute force: too many states")
        for joint in itertools.product(*walking_options(instance, state)):
            nxt = apply(world, state, joint)
            if not isinstance(nxt, State):
                continue
            if any(not home(i, nxt.poses[i]) for i in c):
                continue
            step_cost = cost + (m - len(c))
            for c2 in commits(nxt.poses, c):
                key = (nxt.poses, c2)
                if (step_cost, t + 1) < best.get(key, (1 << 60, 0)):
                    best[key] = (step_cost, t + 1)
                    heapq.heappush(frontier, (step_cost, t + 1, nxt.poses, tuple(sorted(c2)), nxt))
    return None


def walking_makespan(instance, max_states: int = 200_000) -> int | None:
    """Brute-force minimum makespan over walking schedules (no pick or place): a breadth-first
    search over joint poses, every joint walking action checked by the rules; None when no
    walking schedule exists."""
    world, goals = instance.world, instance.goal_cells

    def done(poses):
        return all(c < 0 or int(world.graphs[i].feet[p, 0]) == c for i, (c, p) in enumerate(zip(goals, poses)))

    start = instance.start_state
    layer, seen, depth = [start], {start.poses}, 0
    while layer:
        if any(done(s.poses) for s in layer):
            return depth
        nxt_layer = []
        for state in layer:
            for joint in itertools.product(*walking_options(instance, state)):
                nxt = apply(world, state, joint)
                if isinstance(nxt, State) and nxt.poses not in seen:
                    seen.add(nxt.poses)
                    nxt_layer.append(nxt)
        if len(seen) > max_states:
            raise RuntimeError("brute force: too many states")
        layer, depth = nxt_layer, depth + 1
    return None


def walking_options(instance, state) -> list[list[int]]:
    """Per robot, its walking actions (wait and motions) that pass its own rules on ``state``."""
    graphs = instance.world.graphs
    return [[a for a in candidate_actions(instance, state, i) if graphs[i].kind[a] in (Kind.WAIT, Kind.MOTION)]
            for i in range(instance.num_robots)]
