"""A back end by the solver's name (:func:`open_backend`): CP-SAT (:mod:`.cpsat`) or a SAT solver
of python-sat (:mod:`.cnf`), behind the one interface of :mod:`.interface` (:class:`Backend`,
:class:`Objective`, :class:`Outcome`; they are imported from here too), with the connectivity
cuts (:mod:`.connectivity`) that its model's encoding needs.

Example: the shortest schedule of a window, as the anytime search asks for it (``done[k]``: the
schedule is over after step ``k``; a schedule over after ``k`` is over after ``k + 1``)::

    model = build(instance, L, Options(), min_done=1)
    with open_backend("minisat22", model, instance) as backend:
        done = [model.done[k] for k in range(1, L + 1)]
        outcome = backend.solve(budget=window_budget, objective=Objective(done, maximize=True, chain=True,
                                                                   at_most=L - 1))
"""
from __future__ import annotations

from typing import Callable

from bille.instances import Instance
from bille.instances.run import Budget

from . import SAT, UNKNOWN, UNSAT
from .connectivity import connectivity_cuts, separator_cuts
from .interface import SAT_SOLVERS, SOLVERS, THREAD_ROOM, Backend, Objective, Outcome, interruptible
from .model import Model
from .solution import tiles_at


def open_backend(solver: str, model: Model, instance: Instance, *, connectivity: str = "eager", threads: int = 1,
                 seed: int = 0, presolve: bool = False, budget: Budget | None = None) -> Backend:
    """A back end for ``model`` (of ``instance``): ``solver`` is ``cpsat`` (with ``threads``
    workers, ``seed``, ``presolve``) or a python-sat solver of :data:`SAT_SOLVERS`.
    ``connectivity`` is the model's encoding (which cuts a broken solution gets). Loading the
    model into the solver raises :class:`~.model.OutOfTime` once ``budget`` expires."""
    cuts = _cut_finder(model, instance, connectivity)
    if solver == "cpsat":
        from .cpsat import CpSatBackend

        return CpSatBackend(model, cuts, threads=threads, seed=seed, presolve=presolve, budget=budget)
    if solver not in SAT_SOLVERS:
        raise ValueError(f"unknown solver {solver!r} (expected one of: {', '.join(SOLVERS)})")
    from .cnf import SatBackend

    return SatBackend(model, cuts, solver, budget)


def _cut_finder(model: Model, instance: Instance, connectivity: str) -> Callable:
    """value -> the cuts that exclude an assignment's disconnected steps (none if it has none)."""

    def cuts(value) -> list[list[int]]:
        masks = tiles_at(model, instance, value)
        if connectivity == "cuts":
            return separator_cuts(model, instance, masks, model.candidates)
        return connectivity_cuts(model, instance, masks)

    return cuts


__all__ = ["Backend", "Objective", "Outcome", "SAT", "SAT_SOLVERS", "SOLVERS", "THREAD_ROOM", "UNKNOWN", "UNSAT",
           "interruptible", "open_backend"]
