"""Bill-E planners at scale (``bille bench scale``): S7 bipeds on a 64x64 map with 10 % or 20 %
of its cells obstacles (at random, seeded; the largest 4-connected rest is tiles), each robot
bound for a random cell it can reach, the goals' feet disjoint so that all robots can stand at
their goals at once. The complete planner, LaCAM* (``lacam``, first schedule),
against the static lower bound on the makespan (``bille.solvers.bounds``: for robots that only
walk, the farthest robot's relaxed distance to its goal), beside Temporal A*'s time per
replanning step (the paper's planner, a few steps of it: it replans every step).
"""
from __future__ import annotations

import random

import numpy as np

from bille.instances import Grid, Instance, check_instance, load_moveset
from bille.instances.grid import detached_cells
from bille.instances.walking import UNREACHABLE, walk_for

from ..tables import text_table
from .core import north_facing

ROBOTS = (50, 100, 200, 500)
OBSTACLES = (0.1, 0.2)
TARGETS = {200: 10.0, 500: 60.0}  # seconds to LaCAM*'s first schedule
TEMPORAL_STEPS = 5  # Temporal A* steps measured per instance


def scale_instance(size: int, robots: int, obstacles: float, seed: int = 0) -> Instance:
    """``robots`` S7 robots heading north on a ``size`` square with that share of obstacles."""
    rnd = random.Random(seed)
    n = size * size
    blocked = np.zeros(n, dtype=bool)
    blocked[rnd.sample(range(n), int(obstacles * n))] = True
    tiles = ~blocked
    tiles[detached_cells(tiles, size, size)] = False
    grid = Grid.from_masks(size, size, blocked, tiles)
    ms = load_moveset("S7")
    placed = north_facing(tiles, size, robots, rnd)
    probe = Instance("probe", ms, grid, tuple(placed))
    walk = walk_for(probe.world.graphs[0], tiles)
    free = np.flatnonzero(tiles).tolist()
    feet = walk.graph.feet
    goals, taken = [], set()
    for pose in probe.start_state.poses:
        reach = walk.from_pose(pose)
        for _ in range(10_000):
            cell = rnd.choice(free)
            if cell in taken:
                continue
            # a goal pose whose feet are no other robot's goal cells: every robot can stand at its
            # goal at once (goal cells alone may surround one, and the instance has no schedule)
            ends = [g for g in walk.goal_poses(cell).tolist()
                    if reach[g] < UNREACHABLE and not taken.intersection(feet[g].tolist())]
            if ends:
                goals.append(grid.xy(cell))
                taken.update(feet[rnd.choice(ends)].tolist())
                break
        else:
            goals.append(None)  # boxed in: no goal
    return check_instance(Instance(f"scale-{size}-{robots}-{round(obstacles * 100)}", ms, grid, tuple(placed),
                                   robot_goals=tuple(goals)))


def scale_rows(size: int = 64, robot_counts=ROBOTS, obstacles=OBSTACLES, seed: int = 0, time_limit: float = 120.0,
               temporal_steps: int = TEMPORAL_STEPS):
    """One row per density and robot count, as soon as it is measured."""
    from bille.solvers import solve, validate
    from bille.solvers.bounds import lower_bound

    for share in obstacles:
        for robots in robot_counts:
            inst = scale_instance(size, robots, share, seed)
            result = solve(inst, "lacam", improve=0.0, time_limit=time_limit)
            row = dict(obstacles=share, robots=robots, status=result.status, time_s=result.time_s,
                       nodes=result.counters.nodes, bound=lower_bound(inst).lower)
            if result.schedule is not None:
                report = validate(inst, result.schedule)
                row.update(makespan=report.metrics.makespan, valid=report.valid)
            ta = solve(inst, "temporal-astar", max_steps=temporal_steps, time_limit=time_limit)
            row["temporal_ms"] = ta.counters.plan_ms_mean
            yield row


def scale_table(rows: list[dict]) -> list[str]:
    table = []
    for r in rows:
        done = "makespan" in r
        target = TARGETS.get(r["robots"])
        table.append([f"{round(r['obstacles'] * 100)} %", str(r["robots"]),
                      r["status"] + ("" if not done or r["valid"] else " (INVALID)"), f"{r['time_s']:.2f}",
                      "-" if target is None else f"< {target:.0f}", str(r["makespan"]) if done else "-",
                      str(r["bound"]), f"{r['makespan'] / max(1, r['bound']):.2f}" if done else "-",
                      "-" if r["temporal_ms"] is None else f"{r['temporal_ms']:.0f}"])
    columns = ["obstacles", "robots", "lacam", "first schedule [s]", "target [s]", "makespan", "lower bound",
               "ratio", "Temporal A* [ms/step]"]
    return text_table(columns, table, right=set(columns) - {"lacam"})
