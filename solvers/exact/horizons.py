"""The makespan search one horizon at a time.

From the lower bound upward, ``T = LB, LB + 1, ...`` until a model is satisfiable: that schedule
is optimal, since every horizon below was proved infeasible (a schedule of ``T`` steps also fits
``T + 1``, padded with waits). From a guess (``first_horizon``) the search goes down while
satisfiable and up while not: one infeasible horizon just below a satisfiable one is the proof.

An incremental job (SAT) builds one model for ``chunk`` horizons and decides each under the
assumption ``done[k]``, keeping what the solver learned within the range; otherwise each horizon
has a model of its own.
"""
from __future__ import annotations

from bille.encodings import UNKNOWN, UNSAT
from bille.encodings.model import OutOfTime
from bille.encodings.solution import decode
from bille.instances.result import Result

from .search import Search


def sequential(search: Search) -> Result:
    """The search of the module docstring on ``search``'s state; its result."""
    job = search.job
    T = search.proved_below
    if job.first_horizon is not None:
        T = min(max(T, job.first_horizon), search.cap)
    span = None  # (model, backend, first, last): the model open for horizons first..last
    found = None  # (T, model, backend, outcome) of the smallest satisfiable horizon so far
    try:
        while T <= search.cap:
            if found is None and incumbent_proved(search):
                return search.proved_incumbent()
            if span is None or not span[2] <= T <= span[3]:
                if span is not None and (found is None or span[1] is not found[2]):
                    span[1].close()
                span = None
                try:
                    span = _open(search, T)
                except OutOfTime:
                    return search.timeout()
            model, backend = span[0], span[1]
            began = search.budget.now()
            outcome = search.solve(backend, [model.done[T]] if job.incremental else [])
            if outcome.status == UNSAT:
                search.proved_below = T + 1  # before the news goes out: a listener may stop the search
            search.record(T, backend, outcome.status, search.budget.now() - began,
                          model_horizon=span[3] if job.incremental else None)
            if outcome.status == UNKNOWN:
                return search.timeout()
            if outcome.status == UNSAT:
                if found is not None:
                    break
                T += 1
                continue
            found = (T, model, backend, outcome)
            search.incumbent = decode(model, search.instance, outcome.value)[:, :T]
            if T <= search.proved_below:
                break
            T -= 1
        if found is None:
            return search.infeasible()
        return search.optimal(*found)
    finally:
        for backend in {id(b): b for b in (span and span[1], found and found[2]) if b}.values():
            backend.close()


def incumbent_proved(search: Search) -> bool:
    """Whether every horizon below the incumbent's makespan is proved to have no schedule."""
    return search.incumbent is not None and search.proved_below >= search.incumbent.shape[1]


def _open(search: Search, T: int) -> tuple:
    """``(model, backend, first, last)``: a model open for horizons ``T`` .. ``last`` (one
    horizon, or ``chunk`` of them for an incremental back end). Raises OutOfTime."""
    job, inst = search.job, search.instance
    last = min(search.cap, T + job.chunk - 1) if job.incremental else T
    model = job.model(inst, last, T, search.budget)
    return model, job.open(model, inst, search.budget), T, last

