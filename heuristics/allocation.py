"""Task allocation, step 1 of the reconfiguration loop (paper, Methods, "Load transfer").

The jobs of the reconfiguration sequence (:mod:`.sequence`) are handed out in order: the next
job goes to the idle robot (no legs, no tile) nearest to its pick by pose-graph distance
(walking to a pose facing the pick on the current structure; ties to the lower robot id); when
no idle robot can reach it, allocation waits for the next step. Only the loop's ``active`` robots
take jobs.
"""
from __future__ import annotations

from bille.instances.moveset import Kind
from bille.instances.walking import UNREACHABLE

from .legs import Leg


class Allocation:
    """The loop's allocation (a part of :class:`.reconfigure.Loop`)."""

    def _pending_picks(self) -> set[int]:
        cells = {leg.cell for legs in self.legs for leg in legs if leg.kind == Kind.PICK}
        return cells | {j.pick for j in self.jobs[self.next_job:] if j.pick is not None}

    def _pending_cells(self) -> set[int]:
        cells = {leg.cell for legs in self.legs for leg in legs}
        return cells | {c for j in self.jobs[self.next_job:] for c in (j.pick, j.place) if c is not None}

    def allocate(self) -> None:
        """Hand out the next jobs in order to the nearest idle robots (module docstring)."""
        poses = self.state.poses
        while self.next_job < len(self.jobs):
            job = self.jobs[self.next_job]
            idle = [i for i in self.active if not self.legs[i] and not self.state.carrying[i]]
            best = None
            for i in idle:
                d = int(self.walk(i).facing_distances(job.pick)[poses[i]])
                if d < UNREACHABLE and (best is None or d < best[0]):
                    best = (d, i)
            if best is None:
                return
            self.legs[best[1]] = [Leg(Kind.PICK, job.pick, self.next_job), Leg(Kind.PLACE, job.place, self.next_job)]
            self.next_job += 1

