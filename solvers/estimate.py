"""The size of a joint state space, estimated, not counted (:mod:`.auto` says how it is used and
measured): what ``auto`` and the joint search's choice of engine decide by."""
from __future__ import annotations

import math

import numpy as np

from bille.instances import Instance


def joint_states(instance: Instance) -> float:
    """An estimate of the joint states the brute force may meet (module docstring); ``inf``
    beyond what a float holds (a thousand robots)."""
    tiles = instance.start.tiles
    log = 0.0  # summed in logarithms: the product overflows a float from about 150 robots on
    for graph in instance.world.graphs:
        feet = graph.feet
        on_tiles = graph.valid & np.all((feet < 0) | tiles[np.maximum(feet, 0)], axis=1)
        log += math.log(2 * max(1, int(on_tiles.sum())))
    free = int((~instance.start.obstacles).sum())
    moving = int((instance.start.tiles & ~instance.goal_tiles).sum()) + int(sum(instance.start_state.carrying))
    k = min(free, moving + 1)
    log += math.lgamma(free + 1) - math.lgamma(k + 1) - math.lgamma(free - k + 1)
    return math.exp(log) if log < 700 else math.inf
