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


def class_optimum(instance, rule: str, max_states: int = 5_000):
    """Brute-force minimum makespan over the schedules of one class (``no-scaffold``,
    ``keep-structure``, ``single-carry``; their definitions written again here from the
    tiles' configurations, independently of bille.solvers.bounds.classes): a breadth-first search over
    (state, cells changed so far) that never enters a configuration outside the class. Returns
    ``(makespan, action ids [m, L])``, ``(None, None)`` when the class has no schedule, or
    raises RuntimeError beyond ``max_states``."""
    import numpy as np

    from bille.instances.rules import goal_violation

    world, start = instance.world, instance.start_state
    S, G = instance.start.tiles, instance.goal_tiles
    both, same = S | G, S == G

    def admits(tiles, changed) -> bool:
        if rule == "no-scaffold":
            return not (tiles & ~both).any()
        if (tiles[same] != S[same]).any():
            return False
        return rule == "keep-structure" or not (changed & (tiles == S)).any()  # changed back

    none = np.zeros(len(S), bool)
    parent = {(start.key(), none.tobytes()): None}
    layer, depth = [(start, none)], 0
    while layer:
        for state, changed in layer:
            if goal_violation(world, state, G, instance.goal_cells, depth) is None:
                steps, key = [], (state.key(), changed.tobytes())
                while parent[key] is not None:
                    key, joint = parent[key]
                    steps.append(joint)
                ids = np.array(steps[::-1], dtype=np.int64).T.reshape(instance.num_robots, len(steps))
                return depth, ids
        nxt = []
        for state, changed in layer:
            if len(parent) > max_states:
                raise RuntimeError("brute force: too many states")
            options = [candidate_actions(instance, state, i) for i in range(instance.num_robots)]
            for joint in itertools.product(*options):
                new = apply(world, state, joint)
                if not isinstance(new, State):
                    continue
                now = changed | (new.tiles != S) if rule == "single-carry" else changed
                if not admits(new.tiles, now):
                    continue
                key = (new.key(), now.tobytes())
                if key not in parent:
                    parent[key] = ((state.key(), changed.tobytes()), joint)
                    nxt.append((new, now))
        if len(parent) > max_states:
            raise RuntimeError("brute force: too many states")
        layer, depth = nxt, depth + 1
    return None, None
