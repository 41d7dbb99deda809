"""The pruning of the time-expanded model (:mod:`.model`): which poses each robot may have at
each time, which cells may ever hold a tile, and when each cell may change. The arguments that no
schedule of makespan at most ``T`` is lost are in :mod:`.model`'s docstring; each function fills in
the fields of the model's builder that the variables are then made from.
"""
from __future__ import annotations

import numpy as np

from bille.instances.distances import INF, relaxed_for
from bille.instances.moveset import Kind

from .ends import end_poses
from .reach import reach_in_time


def reachable_poses(builder) -> None:
    """R[i][t]: bool mask of the poses robot i may have at time t."""
    T, goals = builder.T, builder.inst.goal_cells
    builder.timed = reach_in_time(builder.inst, T, builder.end, builder.roles) if builder.opt.prune_tiles else None
    if builder.end is not None:
        goals = [-1] * len(goals)
    builder.R = []
    for i, g in enumerate(builder.world.graphs):
        start = builder.state.poses[i]
        if builder.opt.prune_reach:
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
            if t == T and builder.end is not None:
                mask &= np.isin(np.arange(g.num_poses), end_poses(builder.end, builder.roles[i]))
            if builder.timed is not None:
                mask &= builder.timed.poses[i][t]
            masks.append(mask)
        builder.R.append(masks)


def candidate_cells(builder) -> None:
    """Cells that may hold a tile at some time."""
    inst = builder.inst
    cand = inst.start.tiles | inst.goal_tiles  # with a restriction (Options.kept), all of them
    if builder.opt.prune_cells and not builder.opt.kept:
        for i, g in enumerate(builder.world.graphs):
            seen = np.zeros(g.num_poses, bool)
            for mask in builder.R[i]:
                seen |= mask
            places = np.flatnonzero(g.kind == Kind.PLACE)
            if len(places):
                t = g.target[seen][:, places]
                cand[t[t >= 0]] = True
    elif not builder.opt.kept:
        cand = ~builder.world.obstacles.copy()
    cand &= ~builder.world.obstacles
    builder.cand = cand
    builder.m.candidates = cand
    builder.cells = np.flatnonzero(cand).tolist()
    # a pose whose feet can never stand on tiles is never used
    for i, g in enumerate(builder.world.graphs):
        stands = cand[np.maximum(g.feet, 0)].all(axis=1) & g.valid
        for t in range(1, builder.T + 1):
            builder.R[i][t] &= stands


def change_window(builder) -> dict[int, tuple[int, int]]:
    """Per candidate cell, the first and last step at which a robot could pick or place on
    it (from the poses it may have); outside that window the cell keeps its start value
    before and its goal value after."""
    window = {}
    for i, g in enumerate(builder.world.graphs):
        manip = np.flatnonzero(np.isin(g.kind, (Kind.PICK, Kind.PLACE)))
        if not len(manip):
            continue
        for t in range(1, builder.T + 1):
            targets = g.target[builder.R[i][t - 1]][:, manip]
            for c in np.unique(targets[targets >= 0]).tolist():
                lo, hi = window.get(c, (t, t))
                window[c] = (min(lo, t), max(hi, t))
    return window
