"""Reachability in time with the tiles: which poses, loads and tiles a schedule can have at each
time point, for the pruning of the time-expanded model (:mod:`.model`).

The relaxed distances of :mod:`bille.instances.distances` let a robot walk on any cell that is
not an obstacle. Here a robot walks only where a tile may lie at that time: on the start tiles,
and on a cell that is empty at the start only after some robot, carrying a tile, could have
placed it there. Two passes over the steps give over-approximations of every schedule with
makespan at most ``T`` (a shorter one is padded with waits):

*forward* (from the start state), by induction on ``t``:

- ``tiles[t]``: the cells that may hold a tile at ``t``. A tile at ``t`` lay there at ``t - 1`` or
  was placed at step ``t`` by a robot that stood at ``t - 1`` at a pose of ``poses[t - 1]`` and
  carried a tile (``carry[t - 1]``), facing the cell.
- ``carry[i, t]``: robot ``i`` may carry at ``t``: it carried at ``t - 1``, or picked at step ``t``
  a cell of ``tiles[t - 1]`` from a pose of ``poses[i, t - 1]``.
- ``poses[i, t]``: a successor of a pose of ``poses[i, t - 1]`` whose feet lie in ``tiles[t]``
  (every pose at ``t >= 1`` stands on tiles of time ``t``: rule 4 for new feet; a foot that stays
  keeps its tile, since a pick's target lies in its own robot's collision set, which excludes
  every other robot's feet, and ahead of its own).

*backward* (from the goal), the same argument with time reversed, where a pick becomes the place
of a tile and a place the pick of one: at ``T`` the tiles are the goal tiles, no robot carries,
a robot with a goal cell has its front foot there; a tile at ``t`` lies there at ``t + 1`` or is
picked at step ``t + 1`` by a robot that carries at ``t + 1``; a robot may carry at ``t`` if it
may at ``t + 1`` or may place at step ``t + 1``; a pose at ``t`` has a successor in the poses
at ``t + 1`` and its feet in the tiles of ``t``.

A valid schedule satisfies both, so the model keeps only the intersection.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import Instance
from bille.instances.moveset import Kind


@dataclass
class Reach:
    """``poses[i][t]`` (bool per pose), ``tiles[t]`` (bool per cell), ``carry[i][t]`` (bool)."""

    poses: list[list[np.ndarray]]
    tiles: np.ndarray
    carry: np.ndarray


def _kinds(g, kind) -> np.ndarray:
    return np.flatnonzero(g.kind == int(kind))


def _targets(g, poses: np.ndarray, actions: np.ndarray) -> np.ndarray:
    t = g.target[np.flatnonzero(poses)][:, actions]
    return np.unique(t[t >= 0])


def _standing(g, tiles: np.ndarray) -> np.ndarray:
    return g.valid & tiles[np.maximum(g.feet, 0)].all(axis=1)


def reach_in_time(instance: Instance, T: int, end=None, roles=None) -> Reach:
    """Forward and backward reachability of the instance over ``T`` steps, intersected. With
    ``end`` (a :class:`~bille.instances.State`), the poses and loads at ``T`` are those of ``end``
    instead of the goal's (the tiles at ``T`` are the goal tiles either way); with ``roles``
    (per robot, the robots whose end state it may take), any of theirs."""
    fwd = _forward(instance, T)
    bwd = _backward(instance, T, end, roles or [(i,) for i in range(instance.num_robots)])
    poses = [[f & b for f, b in zip(fi, bi)] for fi, bi in zip(fwd.poses, bwd.poses)]
    return Reach(poses, fwd.tiles & bwd.tiles, fwd.carry & bwd.carry)


def _forward(instance: Instance, T: int) -> Reach:
    graphs, state = instance.world.graphs, instance.start_state
    n, cells = len(graphs), instance.width * instance.height
    tiles = np.zeros((T + 1, cells), bool)
    tiles[0] = instance.start.tiles
    carry = np.zeros((n, T + 1), bool)
    poses = []
    for i, g in enumerate(graphs):
        first = np.zeros(g.num_poses, bool)
        first[state.poses[i]] = True
        poses.append([first])
        carry[i, 0] = state.carrying[i]
    for t in range(1, T + 1):
        tiles[t] = tiles[t - 1]
        for i, g in enumerate(graphs):
            now = poses[i][t - 1]
            picked = _targets(g, now, _kinds(g, Kind.PICK))
            carry[i, t] = carry[i, t - 1] or bool(tiles[t - 1][picked].any())
            if carry[i, t - 1]:
                tiles[t][_targets(g, now, _kinds(g, Kind.PLACE))] = True
        for i, g in enumerate(graphs):
            succ = g.succ[np.flatnonzero(poses[i][t - 1])]
            nxt = np.zeros(g.num_poses, bool)
            nxt[succ[succ >= 0]] = True
            poses[i].append(nxt & _standing(g, tiles[t]))
    return Reach(poses, tiles, carry)


def _backward(instance: Instance, T: int, end, roles) -> Reach:
    graphs, goals = instance.world.graphs, instance.goal_cells
    n, cells = len(graphs), instance.width * instance.height
    tiles = np.zeros((T + 1, cells), bool)
    tiles[T] = instance.goal_tiles
    carry = np.zeros((n, T + 1), bool)
    poses = [[None] * (T + 1) for _ in graphs]
    for i, g in enumerate(graphs):
        last = _standing(g, tiles[T])
        if end is not None:
            last &= np.isin(np.arange(g.num_poses), [end.poses[j] for j in roles[i]])
            carry[i, T] = any(end.carrying[j] for j in roles[i])
        elif goals[i] >= 0:
            last &= g.feet[:, 0] == goals[i]
        poses[i][T] = last
    for t in range(T - 1, -1, -1):
        tiles[t] = tiles[t + 1]
        for i, g in enumerate(graphs):
            later = poses[i][t + 1]
            # a pick or place leaves the pose alone: it is taken from a pose of t + 1
            placed = _targets(g, later, _kinds(g, Kind.PLACE))
            carry[i, t] = carry[i, t + 1] or len(placed) > 0
            if carry[i, t + 1]:
                tiles[t][_targets(g, later, _kinds(g, Kind.PICK))] = True
        for i, g in enumerate(graphs):
            succ = g.succ
            ok = (succ >= 0) & poses[i][t + 1][np.maximum(succ, 0)]
            poses[i][t] = ok.any(axis=1) & _standing(g, tiles[t])
    return Reach(poses, tiles, carry)
