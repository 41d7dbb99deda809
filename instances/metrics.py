"""Schedule metrics (docs/rules.md, "Metrics").

*Makespan*: number of steps, trailing all-``wait`` steps dropped. *Tiles traveled*: number of
motion actions (everything but wait, pick and place) over all robots. *Waits*, *picks*, *places*:
counts of those actions within the makespan. *Sum of costs* (only where robots have goal cells):
each such robot's cost is the step after which its front foot stays on its goal cell (0 if it
never leaves it), the MAPF convention; robots without a goal cell cost nothing.
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
    sum_of_costs: int | None = None

    def to_json(self) -> dict:
        out = asdict(self)
        if self.sum_of_costs is None:
            del out["sum_of_costs"]
        return out


def action_kinds(instance: Instance, ids: np.ndarray) -> np.ndarray:
    """``int8[m, L]``: the :class:`Kind` of every action of a bound schedule."""
    kinds = np.zeros(ids.shape, dtype=np.int8)
    for i, g in enumerate(instance.world.graphs):
        kinds[i] = g.kind[ids[i]]
    return kinds


def makespan(instance: Instance, ids: np.ndarray) -> int:
    """The makespan of a bound schedule: its last step in which some robot does not wait."""
    return _makespan(action_kinds(instance, ids))


def _makespan(kinds: np.ndarray) -> int:
    active = np.flatnonzero((kinds != int(Kind.WAIT)).any(axis=0))
    return int(active[-1]) + 1 if len(active) else 0


def metrics(instance: Instance, ids: np.ndarray) -> Metrics:
    """Metrics of a bound schedule (action ids ``int[m, L]``)."""
    kinds = action_kinds(instance, ids)
    makespan = _makespan(kinds)
    kinds = kinds[:, :makespan]
    return Metrics(
        makespan=makespan,
        tiles_traveled=int((kinds == int(Kind.MOTION)).sum()),
        waits=int((kinds == int(Kind.WAIT)).sum()),
        picks=int((kinds == int(Kind.PICK)).sum()),
        places=int((kinds == int(Kind.PLACE)).sum()),
        sum_of_costs=sum_of_costs(instance, ids),
    )


def sum_of_costs(instance: Instance, ids: np.ndarray) -> int | None:
    """The sum of costs of a bound schedule (module docstring), None when no robot has a goal cell."""
    goals = np.array(instance.goal_cells, dtype=np.int64)
    if not (goals >= 0).any():
        return None
    poses = np.array(instance.start_state.poses, dtype=np.int64)
    groups = [(g, np.array(robots, dtype=np.int64)) for g, robots in instance.world.groups]
    cost = np.zeros(len(goals), dtype=np.int64)

    def away(t: int) -> None:
        for g, robots in groups:
            off = g.feet[poses[robots], 0] != goals[robots]
            cost[robots[off]] = t + 1

    away(0)
    for t in range(ids.shape[1]):
        for g, robots in groups:
            poses[robots] = g.succ[poses[robots], ids[robots, t]]
        away(t + 1)
    return int(cost[goals >= 0].sum())
