"""Iterative refinement of a classic MAPF schedule, as lacam3's anytime mode uses it beside the
LaCAM* search (Okumura, "Engineering LaCAM*", AAMAS 2024; large neighbourhood search for MAPF,
Li et al., IJCAI 2021): take a few robots out of the schedule, plan each again, one after the
other, by space-time A* around the others' paths (vertex and swap conflicts, and robots resting
at their goals), and keep the new paths when their summed cost is not higher.

Classic collisions, point robots (a pose is a cell). A path is a list of cells, one per step,
ending when the robot reaches its goal for good; the cost of a path is its number of steps.
"""
from __future__ import annotations

import heapq
import random

from bille.instances.run import Budget

class Paths:
    """Every robot's path and who is where when: ``at[t * P + v]`` the robot at ``v`` at step
    ``t`` (a robot rests on its goal after its path ends: ``rest[v]`` the step from which)."""

    def __init__(self, paths: list[list[int]], size: int) -> None:
        self.paths, self.P = paths, size
        self.at: dict[int, int] = {}
        self.rest: dict[int, int] = {}
        self.times: dict[int, list[int]] = {}  # the steps at which each cell is passed
        for i, path in enumerate(paths):
            self.add(i, path)

    def add(self, i: int, path: list[int]) -> None:
        P = self.P
        for t, v in enumerate(path):
            self.at[t * P + v] = i
            self.times.setdefault(v, []).append(t)
        self.rest[path[-1]] = len(path) - 1
        self.paths[i] = path

    def remove(self, i: int) -> None:
        P, path = self.P, self.paths[i]
        for t, v in enumerate(path):
            del self.at[t * P + v]
            self.times[v].remove(t)
        del self.rest[path[-1]]


def refine_once(paths: Paths, nbrs: list[list[int]], dists: list[list[int]], goals: list[int],
                rng: random.Random, budget: Budget | None) -> int:
    """One neighbourhood: up to 30 robots (at most a quarter) planned again; the saving in the
    sum of costs (0 when the old paths stay)."""
    m = len(goals)
    size = max(1, min(rng.randint(1, 30), m // 4))
    chosen = rng.sample(range(m), size)
    old = {i: paths.paths[i] for i in chosen}
    old_cost = sum(len(p) - 1 for p in old.values())
    for i in chosen:
        paths.remove(i)
    new_cost, done = 0, []
    for k, i in enumerate(chosen):
        rest = sum(dists[j][old[j][0]] for j in chosen[k + 1:])
        path = _plan(paths, nbrs, dists[i], old[i][0], goals[i], old_cost - new_cost - rest, budget)
        if path is None:
            break
        paths.add(i, path)
        done.append(i)
        new_cost += len(path) - 1
    if len(done) == len(chosen) and new_cost <= old_cost:
        return old_cost - new_cost
    for i in done:
        paths.remove(i)
    for i in chosen:
        paths.add(i, old[i])
    return 0


def _plan(paths: Paths, nbrs, dist, start: int, goal: int, bound: int, budget: Budget | None) -> list[int] | None:
    """Space-time A* from ``start`` to ``goal`` (resting there for good) in at most ``bound``
    steps, around the robots of ``paths``; None if there is none (or once ``budget`` expires)."""
    P, at, rest = paths.P, paths.at, paths.rest
    passed = paths.times.get(goal)
    free_from = max(passed) + 1 if passed else 0  # the goal is passed by nobody from then on
    if goal in rest or dist[start] > bound:
        return None  # another robot rests on it
    heap = [(dist[start], 0, start, -1)]
    parent: dict[int, int] = {}  # t * P + v -> (t - 1) * P + u
    pop, push = heapq.heappop, heapq.heappush
    n = 0
    while heap:
        f, neg_t, v, came = pop(heap)
        t = -neg_t
        key = t * P + v
        if key in parent:
            continue
        parent[key] = came
        if v == goal and t >= free_from:
            path = []
            while key >= 0:
                path.append(key % P)
                key = parent[key]
            return path[::-1]
        n += 1
        if budget is not None and n % 256 == 0 and budget.expired():
            return None
        t1 = t + 1
        for u in nbrs[v] + [v]:
            f1 = t1 + dist[u]
            if f1 > bound or (t1 * P + u) in parent:
                continue
            if (t1 * P + u) in at or rest.get(u, t1 + 1) <= t1:
                continue  # vertex conflict
            j = at.get(t * P + u)
            if j is not None and at.get(t1 * P + v) == j:
                continue  # swap conflict
            push(heap, (f1, -t1, u, key))
    return None
