"""First schedules from the heuristics, for the exact solvers and the anytime method to start from.

A schedule found here is an *upper* bound: it caps the makespan search and is what a solver
returns when its time runs out. Each candidate is checked by the validator before it is used, so
a heuristic's mistake can never become a claimed makespan.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from bille.heuristics import lacam, reconfigure, temporal_astar
from bille.instances import Instance
from bille.instances.metrics import metrics
from bille.instances.schedule import Schedule, bind

from .validate import validate

# the heuristics tried for a first schedule, in order, with the share of the budget each may use
PATH_PLANNING = (("lacam", 0.5), ("temporal-astar", 0.5))
RECONFIGURATION = (("lacam", 0.5), ("temporal-astar", 0.25), ("mstar", 0.25))


@dataclass
class Incumbent:
    """A validated schedule as action ids ``int64[m, makespan]`` (trailing waits trimmed)."""

    ids: np.ndarray
    makespan: int
    method: str


def from_schedule(instance: Instance, schedule: Schedule, method: str) -> Incumbent | None:
    """The schedule as an incumbent if it is valid for ``instance``, else None."""
    report = validate(instance, schedule)
    if not report.valid:
        return None
    makespan = report.metrics.makespan
    return Incumbent(bind(instance, schedule)[:, :makespan], makespan, method)


def first_schedule(instance: Instance, budget: float, improve: bool = True) -> Incumbent | None:
    """The shortest valid schedule the heuristics find within ``budget`` seconds, or None.

    Path planning: LaCAM* (complete on a fixed structure), improving for up to a quarter of the
    budget (at most 1 s) if ``improve``, then Temporal A*. Reconfiguration: the loop with each
    motion layer (LaCAM*, Temporal A*, M*).
    """
    end = time.perf_counter() + budget
    best = None
    for method, share in (RECONFIGURATION if instance.is_reconfiguration else PATH_PLANNING):
        left = end - time.perf_counter()
        if left <= 0:
            break
        limit = max(0.01, min(left, share * budget))
        found = _run(instance, method, limit, improve)
        if found is None or found.schedule is None:
            continue
        candidate = from_schedule(instance, found.schedule, method)
        if candidate is not None and (best is None or candidate.makespan < best.makespan):
            best = candidate
    return best


def _run(instance: Instance, method: str, limit: float, improve: bool):
    if instance.is_reconfiguration:
        if instance.collisions == "classic":
            return None
        return reconfigure.plan(instance, motion=method, time_limit=limit, method=method)
    if method == "lacam":
        return lacam.plan(instance, time_limit=limit, improve=min(1.0, limit / 2) if improve else 0.0)
    if instance.collisions == "classic":
        return None
    return temporal_astar.plan(instance, time_limit=limit)


def makespan_of(instance: Instance, ids: np.ndarray) -> int:
    """The makespan of an action-id matrix (its last step in which some robot does not wait)."""
    return metrics(instance, ids).makespan
