"""Schedule metrics (docs/rules.md, "Metrics").

*Makespan*: number of steps, trailing all-``wait`` steps dropped. *Tiles traveled*: number of
motion actions (everything but wait, pick and place) over all robots. *Waits*, *picks*, *places*:
counts of those actions within the makespan.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .instance import Instance
from .moveset import Kind


@dataclass(frozen=True)
class Metrics:
    makespan: int
    tiles_traveled: int
    waits: int
    picks: int
    places: int

    def to_json(self) -> dict:
        return asdict(self)


def action_kinds(instance: Instance, ids: np.ndarray) -> np.ndarray:
    """``int8[m, L]``: the :class:`Kind` of every action of a bound schedule."""
    kinds = np.zeros(ids.shape, dtype=np.int8)
    for i, g in enumerate(instance.world.graphs):
        kinds[i] = g.kind[ids[i]]
    return kinds


def metrics(instance: Instance, ids: np.ndarray) -> Metrics:
    """Metrics of a bound schedule (action ids ``int[m, L]``)."""
    kinds = action_kinds(instance, ids)
    active = np.flatnonzero((kinds != int(Kind.WAIT)).any(axis=0))
    makespan = int(active[-1]) + 1 if len(active) else 0
    kinds = kinds[:, :makespan]
    return Metrics(
        makespan=makespan,
        tiles_traveled=int((kinds == int(Kind.MOTION)).sum()),
        waits=int((kinds == int(Kind.WAIT)).sum()),
        picks=int((kinds == int(Kind.PICK)).sum()),
        places=int((kinds == int(Kind.PLACE)).sum()),
    )
