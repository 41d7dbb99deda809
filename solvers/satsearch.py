"""The SAT back end's makespan search (a part of :mod:`.exact`): one model for a range of
``chunk`` horizons, searched incrementally by assumptions (``done[k]``: every robot waits after
step ``k``), learned clauses kept within the range; then tiles traveled are minimized at the
optimal makespan with a totalizer over the motion variables.
"""
from __future__ import annotations

import time

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.cnf import SatBackend
from bille.encodings.model import OutOfTime, build
from bille.encodings.solution import decode
from bille.instances.result import Result


class SatSearch:
    """The SAT makespan search of :class:`.exact._Search` (method ``sat``)."""

    def _sat(self) -> Result:
        k = max(1, self.bounds.lower)
        while k <= self.cap:
            T = min(self.cap, k + self.kw["chunk"] - 1)
            try:
                model = build(self.instance, T, self.options, min_done=k, deadline=self.deadline)
            except OutOfTime:
                return self.timeout(k)
            backend = SatBackend(model, self.kw["solver"])
            try:
                while k <= T:
                    if self.incumbent is not None and k >= self.incumbent.shape[1]:
                        return self._proved_incumbent(k)
                    began = time.perf_counter()
                    status = self._sat_solve(backend, model, [model.done[k]])
                    self.stats["horizons"].append({"T": k, "model_horizon": T, "variables": backend.top,
                                                   "clauses": backend.num_clauses, "answer": status,
                                                   "time_s": round(time.perf_counter() - began, 3)})
                    self._report()
                    if status == UNKNOWN:
                        return self.timeout(k)
                    if status == SAT:
                        self.stats["makespan_s"] = round(time.perf_counter() - self.start, 3)
                        ids = decode(model, self.instance, backend.value)[:, :k]
                        ids = self._sat_travel(backend, model, k, ids)
                        self.stats["solver"] = backend.stats
                        return self.result("optimal", ids, lower=k)
                    k += 1
            finally:
                backend.delete()
        return self._infeasible()

    def _sat_solve(self, backend, model, assumptions) -> str:
        while True:
            status = backend.solve(assumptions, self.deadline)
            if status != SAT or self._check(backend, model):
                return status

    def _sat_travel(self, backend, model, k, ids):
        self.stats["tiles_traveled_optimal"] = False
        if not self.minimize_travel:
            return ids
        # motions after step k are excluded by done[k]: count only those up to k
        steps = {v: t for (_, t), group in model.y.items() for v, _, _ in group}
        motion = [v for v in model.motion if steps[v] <= k]
        best = sum(backend.value(v) for v in motion)
        with self.travel_time():
            while best > 0:
                status = self._sat_solve(backend, model, [model.done[k], backend.at_most(motion, best - 1)])
                if status == UNKNOWN:
                    return ids
                if status == UNSAT:
                    break
                ids = decode(model, self.instance, backend.value)[:, :k]
                best = sum(backend.value(v) for v in motion)
        self.stats["tiles_traveled_optimal"] = True
        return ids
