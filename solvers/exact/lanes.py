"""The makespan search on several horizons at once.

One CP-SAT worker proves a horizon infeasible about as fast as two on these models, so with
``threads`` workers the search runs ``threads`` horizons side by side, one worker each, from the
lower bound upward: ``T, T + 1, ...``. Every answer is the answer of that horizon's model alone,
so the proof is the sequential one: the optimum is the smallest satisfiable horizon once every
horizon below it (down to the lower bound) is proved infeasible. A satisfiable horizon stops the
solves above it; the ones below go on, since one of them may still be satisfiable.
"""
from __future__ import annotations

from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.model import OutOfTime
from bille.encodings.solution import decode
from bille.instances.result import Result

from .horizons import incumbent_proved
from .search import Search


def parallel(search: Search) -> Result:
    """The search of the module docstring on ``search``'s state (``job.threads`` lanes); its result."""
    job, inst = search.job, search.instance
    lanes = job.threads
    next_T = search.proved_below  # the next horizon to start
    answers: dict[int, str] = {}
    found: dict[int, tuple] = {}  # T -> (model, backend, outcome)
    running: dict = {}  # future -> (T, model, backend)
    stopped: set[int] = set()  # horizons stopped because a lower one was satisfiable
    pool = ThreadPoolExecutor(lanes)
    try:
        while True:
            if answers.get(search.proved_below) == SAT:
                break
            if not found and incumbent_proved(search):
                return search.proved_incumbent()
            best = min(found, default=None)
            while len(running) < lanes and next_T <= search.cap and (best is None or next_T < best):
                try:
                    model = job.model(inst, next_T, next_T, search.budget)
                    backend = job.open(model, inst, search.budget, threads=1)
                except OutOfTime:
                    return search.timeout()
                search.stats["horizons"].append({"T": next_T, **backend.size()})
                running[pool.submit(_lane, backend, search.budget)] = (next_T, model, backend)
                next_T += 1
            if not running:
                return search.infeasible()
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                T, model, backend = running.pop(future)
                outcome, spent = future.result()
                search.stats["cuts"] += outcome.cuts
                if outcome.status != UNKNOWN:
                    answers[T] = outcome.status
                while answers.get(search.proved_below) == UNSAT:  # before the news goes out
                    search.proved_below += 1
                row = next(h for h in search.stats["horizons"] if h["T"] == T and "answer" not in h)
                row.update(answer=outcome.status, time_s=round(spent, 3))
                search.report(row)
                if outcome.status == UNKNOWN:
                    if T in stopped:
                        continue  # a lower horizon was satisfiable
                    return search.timeout()
                if outcome.status == SAT:
                    found[T] = (model, backend, outcome)
                    for U, _, b in running.values():
                        if U > T:
                            stopped.add(U)
                            b.stop()
    finally:
        _stop(search, pool, running, stopped)
    T = search.proved_below
    model, backend, outcome = found[T]
    search.incumbent = decode(model, inst, outcome.value)  # kept if the minimization is interrupted
    backend.tune(threads=lanes)  # the minimization of tiles traveled gets every worker
    return search.optimal(T, model, backend, outcome)


def _stop(search: Search, pool, running: dict, stopped: set[int]) -> None:
    """Stop the lanes still running and wait for them; mark each horizon left undecided."""
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
    for row in search.stats["horizons"]:  # the horizons left undecided when the search ended
        row.setdefault("answer", "stopped" if row["T"] in stopped else UNKNOWN)


def _lane(backend, budget) -> tuple:
    """Decide one horizon: its outcome and the seconds it took."""
    began = budget.now()
    outcome = backend.solve(budget=budget)
    return outcome, budget.now() - began
