"""The SAT back end's makespan search (a part of :mod:`.exact`): one model for a range of
``chunk`` horizons, searched incrementally by assumptions (``done[k]``: every robot waits after
step ``k``), learned clauses kept within the range; then tiles traveled are minimized at the
optimal makespan.
"""
from __future__ import annotations

import time

from bille.encodings import SAT, UNKNOWN, UNSAT
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
            backend = self.open(model)
            try:
                while k <= T:
                    if self.incumbent is not None and k >= self.incumbent.shape[1]:
                        return self._proved_incumbent(k)
                    began = time.perf_counter()
                    outcome = self.solved(backend, [model.done[k]])
                    status = outcome.status
                    self.stats["horizons"].append({"T": k, "model_horizon": T, **backend.size(), "answer": status,
                                                   "time_s": round(time.perf_counter() - began, 3)})
                    self._report()
                    if status == UNKNOWN:
                        return self.timeout(k)
                    if status == SAT:
                        self.stats["makespan_s"] = round(time.perf_counter() - self.start, 3)
                        ids = decode(model, self.instance, outcome.value)[:, :k]
                        ids = self.travel(backend, model, k, ids, outcome.values)
                        self.stats["solver"] = backend.stats
                        return self.result("optimal", ids, lower=k)
                    k += 1
            finally:
                backend.close()
        return self._infeasible()
