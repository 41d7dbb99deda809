"""Where the schedules considered stand and work: the cells their feet, picks and places may use
(:class:`Ground`), for the bounds (:mod:`.static`, :mod:`.routing`, :mod:`.scaffold`) within a
class of schedules (:mod:`.classes`) or a scenario of scaffold."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import PoseGraph
from bille.instances.distances import relaxed_for
from bille.instances.moveset import Kind


@dataclass(frozen=True, eq=False)
class Ground:
    """Where the schedules considered can stand and work: ``feet`` the cells a foot may stand
    on, ``picks`` and ``places`` the cells those actions may target (masks over the cells;
    None: every cell). :data:`EVERYWHERE` is every schedule's."""

    feet: np.ndarray | None = None
    picks: np.ndarray | None = None
    places: np.ndarray | None = None

    def relaxed(self, graph: PoseGraph):
        """The relaxed pose graph of ``graph`` on the ground."""
        return relaxed_for(graph, self.feet)

    def targets(self, graph: PoseGraph, kind: Kind, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Pairs ``(pose, cell)``: from a pose of the ground, an action of ``kind`` targets a
        cell it may target."""
        poses, cells = by_target(graph, kind, n)
        keep = self.relaxed(graph).poses[poses]
        allowed = self.picks if kind == Kind.PICK else self.places
        if allowed is not None:
            keep &= allowed[cells]
        return poses[keep], cells[keep]


EVERYWHERE = Ground()


def by_target(graph: PoseGraph, kind: Kind, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Pairs ``(pose, cell)``: from the valid ``pose``, an action of ``kind`` targets ``cell``."""
    acts = np.flatnonzero(graph.kind == kind)
    if not len(acts):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    ok = (graph.target[:, acts] >= 0) & (graph.succ[:, acts] >= 0) & graph.valid[:, None]
    p, a = np.nonzero(ok)
    return p.astype(np.int64), graph.target[p, acts[a]].astype(np.int64)
