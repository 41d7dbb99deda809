"""Robots and their legs in the reconfiguration loop (paper, Methods, "Load transfer").

Each robot of the loop (:mod:`.reconfigure`) holds a list of *legs*: ``pick c`` (walk to a pose
facing ``c``, pick the tile) or ``place c`` (carry the tile to a pose facing ``c``, place it).
A load transfer (:mod:`.transfer`) rewrites two robots' legs.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances.moveset import Kind
from bille.instances.walking import UNREACHABLE, Walk


def nearest(walk: Walk, pose: int, cell: int) -> tuple[int, int]:
    """Steps from ``pose`` to the nearest pose facing ``cell`` plus one, and that pose."""
    facing = walk.facing_poses(cell)
    if len(facing) == 0 or not walk.standing[pose]:
        return UNREACHABLE, -1
    dist = walk.from_pose(pose)[facing]
    k = int(np.argmin(dist))
    if dist[k] >= UNREACHABLE:
        return UNREACHABLE, -1
    return int(dist[k]) + 1, int(facing[k])



@dataclass(frozen=True)
class Leg:
    """Pick (``kind`` PICK) or place (PLACE) at ``cell``, for job ``job`` of the sequence.
    ``relay`` marks the two legs of a load transfer (the drop at the transfer cell and the
    pick-up from it)."""

    kind: Kind
    cell: int
    job: int
    relay: bool = False



@dataclass(frozen=True)
class Transfer:
    """One load transfer chosen at a step: ``kind`` ``relay`` (equation 2: ``giver`` drops its
    tile at ``cell`` for ``taker``, and takes the taker's pick) or ``swap`` (equation 3: two
    carrying robots exchange drop-off cells); ``saving`` = old cost - new cost."""

    kind: str
    giver: int
    taker: int
    saving: int
    cell: int | None = None


def facing_feet(world) -> dict[int, list[np.ndarray]]:
    """For each cell, per moveset, the feet ``int[k, 2]`` of the poses that pick or place there."""
    out: dict[int, list[np.ndarray]] = {}
    for graph, _ in world.groups:
        kinds = graph.kind.tolist()
        manip = [a for a in range(graph.num_actions) if kinds[a] in (Kind.PICK, Kind.PLACE)]
        cells, poses = [], []
        for a in manip:
            p = np.flatnonzero(graph.valid & (graph.target[:, a] >= 0))
            cells.append(graph.target[p, a])
            poses.append(p)
        if not cells:
            continue
        cells, poses = np.concatenate(cells), np.concatenate(poses)
        order = np.argsort(cells, kind="stable")
        cells, poses = cells[order], poses[order]
        bounds = np.flatnonzero(np.diff(cells)) + 1
        for c, group in zip(cells[np.r_[0, bounds]], np.split(poses, bounds)):
            out.setdefault(int(c), []).append(graph.feet[np.unique(group)])
    return out
