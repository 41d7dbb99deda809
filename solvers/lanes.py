"""CP-SAT's makespan search on several horizons at once (a part of :mod:`.exact`).

One CP-SAT worker proves a horizon infeasible about as fast as two on these models (reconfig-30,
T = 11: 2.7 s with one, 3.0 s with two), so with ``threads`` workers the search runs ``threads``
horizons side by side, one worker each, from the lower bound upward: ``T, T + 1, ...``. Every
answer is the answer of that horizon's model alone, so the proof is the sequential one: the
optimum is the smallest satisfiable horizon once every horizon below it (down to the lower
bound) is proved infeasible. A satisfiable horizon stops the solves above it; the ones below go
on, since one of them may still be satisfiable.
"""
from __future__ import annotations

import threading
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.model import OutOfTime, build
from bille.encodings.solution import decode


class Lanes:
    """The parallel horizon search of :class:`.exact._Search` (``threads`` >= 2)."""

    def _cpsat_lanes(self):
        lanes = self.kw["threads"]
        lower = max(1, self.bounds.lower)
        proved_below, next_T = lower, lower  # no schedule below proved_below; next horizon to start
        answers: dict[int, str] = {}
        found: dict[int, tuple] = {}
        running: dict = {}  # future -> (T, model, backend)
        stopped: set[int] = set()  # horizons stopped because a lower one was satisfiable
        self._lock = threading.Lock()
        pool = ThreadPoolExecutor(lanes)
        try:
            while True:
                while answers.get(proved_below) == UNSAT:
                    proved_below += 1
                if answers.get(proved_below) == SAT:
                    break
                if self.incumbent is not None and proved_below >= self.incumbent.shape[1] and not found:
                    return self._proved_incumbent(proved_below)
                best = min(found, default=None)
                while len(running) < lanes and next_T <= self.cap and (best is None or next_T < best):
                    try:
                        model = build(self.instance, next_T, self.options, deadline=self.deadline)
                        backend = self.open(model, threads=1)
                    except OutOfTime:
                        return self.timeout(proved_below)
                    with self._lock:
                        self.stats["horizons"].append({"T": next_T, **backend.size()})
                    running[pool.submit(self._lane, backend, model)] = (next_T, model, backend)
                    next_T += 1
                if not running:
                    return self._infeasible()
                done, _ = wait(running, return_when=FIRST_COMPLETED)
                for future in done:
                    T, model, backend = running.pop(future)
                    outcome, spent = future.result()
                    status = outcome.status
                    self.stats["cuts"] += outcome.cuts
                    with self._lock:
                        row = next(h for h in self.stats["horizons"] if h["T"] == T and "answer" not in h)
                        row.update(answer=status, time_s=round(spent, 3))
                    self._report(row)
                    if status == UNKNOWN:
                        if T in stopped:
                            continue  # a lower horizon was satisfiable
                        return self.timeout(proved_below)
                    answers[T] = status
                    if status == SAT:
                        found[T] = (model, backend, outcome)
                        for U, _, b in running.values():
                            if U > T:
                                stopped.add(U)
                                b.stop()
        finally:
            for T, _, backend in running.values():
                stopped.add(T)
                backend.stop()
            while running:  # a stop may land before its solve began: repeat it until all are done
                done, _ = wait(running, timeout=0.05)
                for future in done:
                    running.pop(future)
                for _, _, backend in running.values():
                    backend.stop()
            pool.shutdown(wait=True)
            for row in self.stats["horizons"]:  # the horizons left undecided when the search ended
                row.setdefault("answer", "stopped" if row["T"] in stopped else UNKNOWN)
        model, backend, outcome = found[proved_below]
        self.incumbent = decode(model, self.instance, outcome.value)
        self.stats["makespan_s"] = round(time.perf_counter() - self.start, 3)
        backend.tune(threads=lanes)  # the minimization of tiles traveled gets every worker
        ids = self.travel(backend, model, model.T, self.incumbent, outcome.values)
        self.stats["solver"] = backend.stats
        return self.result("optimal", ids, lower=model.T)

    def _lane(self, backend, model) -> tuple:
        """Decide one horizon: its outcome and the seconds it took."""
        began = time.perf_counter()
        outcome = backend.solve(deadline=self.deadline)
        return outcome, time.perf_counter() - began
