"""The pruning of the time-expanded model (:mod:`.model`): which poses each robot may have at
each time, which cells may ever hold a tile, and when each cell may change. The arguments that no
schedule of makespan at most ``T`` is lost are in :mod:`.model`'s docstring; :func:`prune` returns
what the model's variables are then made from.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import Instance
from bille.instances.distances import INF, relaxed_for
from bille.instances.moveset import Kind

from .ends import end_poses
from .reach import Reach, reach_in_time


@dataclass
class Pruning:
    """What the pruning leaves of a model over horizon ``T``."""

    poses: list[list[np.ndarray]]  # poses[i][t]: bool mask of the poses robot i may have at t
    cand: np.ndarray  # bool mask of the cells that may hold a tile at some time
    cells: list[int]  # those cells, in order
    timed: Reach | None  # the reachability in time with the tiles (prune_tiles), else None


def prune(instance: Instance, T: int, options, end=None, roles=None) -> Pruning:
    """The pruning of the model of ``instance`` over ``T`` with ``options`` (:class:`.model.Options`);
    ``end`` and ``roles`` as in :func:`.model.build` (a window's end state, and per robot the
    robots whose end state it may take)."""
    timed = reach_in_time(instance, T, end, roles) if options.prune_tiles else None
    poses = reachable_poses(instance, T, options, timed, end, roles)
    cand = candidate_cells(instance, poses, options)
    # a pose whose feet can never stand on tiles is never used
    for i, g in enumerate(instance.world.graphs):
        stands = cand[np.maximum(g.feet, 0)].all(axis=1) & g.valid
        for t in range(1, T + 1):
            poses[i][t] &= stands
    return Pruning(poses, cand, np.flatnonzero(cand).tolist(), timed)


def reachable_poses(instance: Instance, T: int, options, timed: Reach | None, end=None,
                    roles=None) -> list[list[np.ndarray]]:
    """Per robot and time, the bool mask of the poses it may have."""
    goals = instance.goal_cells
    if end is not None:
        goals = [-1] * len(goals)
    out = []
    for i, g in enumerate(instance.world.graphs):
        start = instance.start_state.poses[i]
        if options.prune_reach:
            relaxed = relaxed_for(g)
            fwd = relaxed.from_pose(start)
            bwd = relaxed.to_front(goals[i]) if goals[i] >= 0 else np.zeros(g.num_poses, np.int64)
        else:
            fwd = np.where(g.valid, 0, INF)
            bwd = np.zeros(g.num_poses, np.int64)
        masks = []
        for t in range(T + 1):
            mask = g.valid & (fwd <= t) & (bwd <= T - t)
            if t == 0:
                mask = np.zeros(g.num_poses, bool)
                mask[start] = True
            if t == T and goals[i] >= 0:
                mask &= g.feet[:, 0] == goals[i]
            if t == T and end is not None:
                mask &= np.isin(np.arange(g.num_poses), end_poses(end, roles[i]))
            if timed is not None:
                mask &= timed.poses[i][t]
            masks.append(mask)
        out.append(masks)
    return out


def candidate_cells(instance: Instance, poses: list[list[np.ndarray]], options) -> np.ndarray:
    """Cells that may hold a tile at some time."""
    world = instance.world
    cand = instance.start.tiles | instance.goal_tiles  # with a restriction (Options.restricted), all of them
    if options.prune_cells and not options.restricted:
        for i, g in enumerate(world.graphs):
            seen = np.zeros(g.num_poses, bool)
            for mask in poses[i]:
                seen |= mask
            places = np.flatnonzero(g.kind == int(Kind.PLACE))
            if len(places):
                t = g.target[seen][:, places]
                cand[t[t >= 0]] = True
    elif not options.restricted:
        cand = ~world.obstacles.copy()
    return cand & ~world.obstacles


def change_window(instance: Instance, poses: list[list[np.ndarray]], T: int) -> dict[int, tuple[int, int]]:
    """Per candidate cell, the first and last step at which a robot could pick or place on
    it (from the poses it may have); outside that window the cell keeps its start value
    before and its goal value after."""
    window = {}
    for i, g in enumerate(instance.world.graphs):
        manip = np.flatnonzero(np.isin(g.kind, (int(Kind.PICK), int(Kind.PLACE))))
        if not len(manip):
            continue
        for t in range(1, T + 1):
            targets = g.target[poses[i][t - 1]][:, manip]
            for c in np.unique(targets[targets >= 0]).tolist():
                lo, hi = window.get(c, (t, t))
                window[c] = (min(lo, t), max(hi, t))
    return window
