"""Raising the lower bound of :mod:`.anytime`: the exact makespan search from the bound up, one
model per horizon (its pruning is tightest there), in slices between the other parts of the
search (:class:`Rise`) or in a child process on a core of its own (:class:`Background`).

An infeasible horizon ``k`` proves that no schedule is shorter than ``k + 1``; a satisfiable one
is an optimal schedule. A python-sat solver keeps what it learned on an undecided horizon for the
next slice.
"""
from __future__ import annotations

import multiprocessing
import signal
import time

import numpy as np

from bille.encodings import SAT, UNKNOWN
from bille.encodings.backend import open_backend
from bille.encodings.model import Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance
from bille.instances.schedule import Schedule

from .bracket import Bracket
from .incumbent import from_schedule

try:  # the bound search runs in a forked child process where the platform has fork
    FORK = multiprocessing.get_context("fork")
except ValueError:
    FORK = None


class Rise:
    """The search from ``bracket``'s lower bound up with the back end ``solver``, until ``end``:
    bounds proved and an optimal schedule go to ``bracket``."""

    def __init__(self, instance: Instance, solver: str, bracket: Bracket, end: float) -> None:
        self.instance, self.solver, self.bracket, self.end = instance, solver, bracket, end
        self.k = max(1, bracket.lower)
        self.model = self.backend = None
        self.finished = False  # an optimal schedule was found

    def step(self, until: float) -> None:
        """Search until ``until`` (or the bracket closes)."""
        inst, bracket = self.instance, self.bracket
        while time.perf_counter() < until and not bracket.closed:
            if self.backend is None:
                try:
                    self.model = build(inst, self.k, Options(), deadline=self.end)
                except OutOfTime:
                    return
                self.backend = open_backend(self.solver, self.model, inst)
            outcome = self.backend.solve(deadline=until)
            if outcome.status == UNKNOWN:
                return
            if outcome.status == SAT:  # every horizon below k is infeasible: optimal
                found = from_schedule(inst, Schedule.from_ids(inst, decode(self.model, inst, outcome.value)), "exact")
                if found is None:
                    raise RuntimeError(f"anytime: the exact model gave an invalid schedule at horizon {self.k}")
                bracket.offer(found)
                bracket.prove(found.makespan)
                self.finished = True
                self.close()
                return
            bracket.prove(self.k + 1)
            self.close()
            self.k = max(self.k + 1, bracket.lower)

    def close(self) -> None:
        if self.backend is not None:
            self.backend.close()
        self.model = self.backend = None


class Background:
    """:class:`Rise` in a child process: it sends each proved bound, or an optimal schedule,
    through a pipe; :meth:`step` reads them into ``bracket`` until ``until``."""

    def __init__(self, instance: Instance, solver: str, bracket: Bracket, end: float) -> None:
        self.instance, self.bracket = instance, bracket
        self.inbox, outbox = FORK.Pipe(duplex=False)
        self.child = FORK.Process(target=_rise_child, args=(instance, solver, bracket.lower, end, outbox), daemon=True)
        # the terminal's Ctrl-C goes to the whole process group: the child ignores it (the parent
        # stops it), and is born with it held back, so that none lands before it is ignored
        held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            try:
                self.child.start()
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, held)  # a Ctrl-C held back lands here
        except BaseException:
            self.close()
            raise
        finally:
            outbox.close()

    def step(self, until: float) -> None:
        inst, bracket = self.instance, self.bracket
        while not bracket.closed:
            if not self.inbox.poll(max(0.0, until - time.perf_counter())):
                return
            try:
                kind, value = self.inbox.recv()
            except EOFError:
                return
            if kind == "lower":
                bracket.prove(value)
            else:
                found = from_schedule(inst, Schedule.from_ids(inst, np.array(value)), "exact")
                if found is None:
                    raise RuntimeError("anytime: the exact model gave an invalid schedule")
                bracket.offer(found)
                bracket.prove(found.makespan)

    def close(self) -> None:
        if self.child.pid is not None:
            if self.child.is_alive():
                self.child.terminate()
            self.child.join()
        self.inbox.close()


def _rise_child(instance: Instance, solver: str, lower: int, end: float, outbox) -> None:
    """The child's loop: raise the bound until ``end`` or an optimal schedule, sending each news."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    bracket = Bracket(lower)
    bracket.on_bound.append(lambda value: outbox.send(("lower", value)))
    bracket.on_schedule.append(lambda found: outbox.send(("optimal", found.ids.tolist())))
    rise = Rise(instance, solver, bracket, end)
    while time.perf_counter() < end:
        rise.step(end)
        if rise.finished:
            break
    rise.close()
    outbox.close()
