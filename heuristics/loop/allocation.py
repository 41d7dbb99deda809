"""Task allocation, step 1 of the reconfiguration loop (paper, Methods, "Load transfer").

The jobs of the reconfiguration sequence (:mod:`.sequence`) are handed out in order: the next
job goes to the idle robot (no legs, no tile) nearest to its pick by pose-graph distance
(walking to a pose facing the pick on the current structure; ties to the lower robot id); when
no idle robot can reach it, allocation waits for the next step. Only the ``active`` robots take
jobs.
"""
from __future__ import annotations

from bille.instances.walking import UNREACHABLE

from .loopstate import LoopState


class Allocation:
    """Hands out the next jobs; :meth:`decide` says to whom, the loop applies it
    (:meth:`.LoopState.assign`)."""

    def __init__(self, active: list[int]) -> None:
        self.active = list(active)

    def decide(self, s: LoopState) -> list[tuple[int, int]]:
        """``[(robot, job index)]``: the next jobs in order, each to the nearest idle active robot
        (module docstring); it stops at the first job that no idle robot can reach."""
        out: list[tuple[int, int]] = []
        taken: set[int] = set()
        poses = s.poses
        for k in range(s.next_job, len(s.jobs)):
            pick = s.jobs[k].pick
            best = None
            for i in self.active:
                if i in taken or s.legs[i] or s.state.carrying[i]:
                    continue
                d = int(s.walk(i).facing_distances(pick)[poses[i]])
                if d < UNREACHABLE and (best is None or d < best[0]):
                    best = (d, i)
            if best is None:
                break
            out.append((best[1], k))
            taken.add(best[1])
        return out
