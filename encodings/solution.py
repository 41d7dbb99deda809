"""Reading a solution of the time-expanded model: the schedule's action ids and the tiles at
every time point."""
from __future__ import annotations

import numpy as np

from bille.instances import Instance

from .model import Model


def decode(model: Model, instance: Instance, value) -> np.ndarray:
    """Action ids ``int[m, T]`` from a solution (``value(var) -> bool``)."""
    ids = np.zeros((instance.num_robots, model.T), dtype=np.int64)
    for (i, t), group in model.y.items():
        for v, _, a in group:
            if value(v):
                ids[i, t - 1] = a
                break
    return ids


def tiles_at(model: Model, instance: Instance, value) -> list[np.ndarray]:
    """The tile mask of every time point of a solution."""
    n = instance.width * instance.height
    out = []
    for t in range(model.T + 1):
        mask = np.zeros(n, dtype=bool)
        for (tt, c), lit in model.tile.items():
            if tt == t and (value(lit) if lit > 0 else not value(-lit)):
                mask[c] = True
        out.append(mask)
    return out
