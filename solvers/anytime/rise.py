"""Raising the lower bound of anytime solving (:mod:`.method`): the exact makespan search from the bound up, one
model per horizon (its pruning is tightest there), in slices between the other parts of the
search (:class:`Rise`) or in a child process on a core of its own (:class:`Background`).

An infeasible horizon ``k`` proves that no schedule is shorter than ``k + 1``; a satisfiable one
is an optimal schedule. A python-sat solver keeps what it learned on an undecided horizon for the
next slice.

A horizon's model admits every schedule of at most ``k`` steps (robots wait once done), so an
infeasible horizon proves every horizon below it infeasible too: a horizon may be decided out of
turn. :class:`Ahead` does so in the parent while the neighbourhood search finds nothing: it
decides one horizon above the child's, the highest whose proof it expects to see before the end
(each horizon taken to cost at least twice the one below it, as measured on bridge-2 from horizon
17 up), and the child, if the proof passes it, starts again above it.
"""
from __future__ import annotations

import multiprocessing
import signal

import numpy as np

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.backend import open_backend
from bille.encodings.model import Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance
from bille.instances.run import Budget
from bille.instances.schedule import Schedule

from ..incumbent import from_schedule
from .bracket import Bracket

try:  # the bound search runs in a forked child process where the platform has fork
    FORK = multiprocessing.get_context("fork")
except ValueError:
    FORK = None


class Rise:
    """The search from ``bracket``'s lower bound up with the back end ``solver``, within the run's
    ``budget``: bounds proved and an optimal schedule go to ``bracket``."""

    def __init__(self, instance: Instance, solver: str, bracket: Bracket, budget: Budget) -> None:
        self.instance, self.solver, self.bracket, self.budget = instance, solver, bracket, budget
        self.k = max(1, bracket.lower)
        self.model = self.backend = None
        self.finished = False  # an optimal schedule was found
        self.began = None  # when the horizon k began, and the seconds each horizon decided took
        self.seconds: dict[int, float] = {}

    def step(self, part: Budget) -> None:
        """Search until ``part`` (a child of the run's budget) expires or the bracket closes."""
        inst, bracket = self.instance, self.bracket
        while not part.expired() and not bracket.closed:
            if self.backend is None:
                self.began = self.began or part.now()
                try:  # the run's budget, not the part's: a model may take longer than one slice to load
                    self.model = build(inst, self.k, Options(), budget=self.budget)
                    self.backend = open_backend(self.solver, self.model, inst, budget=self.budget)
                except OutOfTime:
                    return
            outcome = self.backend.solve(budget=part)
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
            self.seconds[self.k] = part.now() - self.began
            self.began = None
            bracket.prove(self.k + 1)
            self.close()
            self.k = max(self.k + 1, bracket.lower)

    def close(self) -> None:
        if self.backend is not None:
            self.backend.close()
        self.model = self.backend = None


class Background:
    """:class:`Rise` in a child process: it sends each proved bound (with the seconds its horizon
    took), or an optimal schedule, through a pipe; :meth:`step` reads them into ``bracket``. ``k``
    is the horizon the child is on, ``seconds`` what each horizon it refuted took. The child runs
    until the run's ``budget`` ends or the parent stops it."""

    def __init__(self, instance: Instance, solver: str, bracket: Bracket, budget: Budget) -> None:
        self.instance, self.solver, self.bracket, self.budget = instance, solver, bracket, budget
        self.seconds: dict[int, float] = {}
        self._start()

    def _start(self) -> None:
        self.k = self.bracket.lower
        self.child, self.inbox = _fork(_rise_child, self.instance, self.solver, self.k, self.budget)

    def catch_up(self) -> None:
        """Start again from the bracket's bound if a proof made elsewhere passed the child's
        horizon (it would only refute a horizon already refuted)."""
        if self.k < self.bracket.lower:
            self.close()
            self._start()

    def step(self, part: Budget) -> None:
        """Read what the child sent, waiting for news until ``part`` expires (a cancelled run's
        part reads what is there and returns)."""
        inst, bracket = self.instance, self.bracket
        while not bracket.closed:
            if not self.inbox.poll(min(part.left(), 3600.0)):
                return
            try:
                kind, value = self.inbox.recv()
            except EOFError:
                return
            if kind == "lower":
                value, seconds = value
                if seconds is not None:
                    self.seconds[value - 1] = seconds
                self.k = max(self.k, value)
                bracket.prove(value)
            else:
                found = from_schedule(inst, Schedule.from_ids(inst, np.array(value)), "exact")
                if found is None:
                    raise RuntimeError("anytime: the exact model gave an invalid schedule")
                bracket.offer(found)
                bracket.prove(found.makespan)

    def close(self) -> None:
        _stop(self.child, self.inbox)


def _fork(target, *args) -> tuple:
    """``target(*args, outbox)`` in a child process, and the end of the pipe it sends on. The
    terminal's Ctrl-C goes to the whole process group: the child ignores it (the parent stops
    it), and is born with it held back, so that none lands before it is ignored."""
    inbox, outbox = FORK.Pipe(duplex=False)
    child = FORK.Process(target=target, args=(*args, outbox), daemon=True)
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        try:
            child.start()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)  # a Ctrl-C held back lands here
    except BaseException:
        _stop(child, inbox)
        raise
    finally:
        outbox.close()
    return child, inbox


def _stop(child, inbox) -> None:
    if child.pid is not None:
        if child.is_alive():
            child.terminate()
        child.join()
    inbox.close()


def _ignore_ctrl_c() -> None:
    """In a child of :func:`_fork`: the parent stops it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


class Scaffold:
    """The static bound's scaffold scenarios (:class:`bille.solvers.bounds.scaffold.Scenarios`) taken
    further, where its share of the static bound's time cut the search short or the per-robot
    integer program of its least scenario is not solved yet: once, while the neighbourhood search
    finds nothing and :class:`Ahead` has no horizon to decide, for up to a quarter of the time
    limit (at least 10 s). It runs in a child process, since the integer program cannot be
    interrupted: the parent waits for it, reads each value it raises, and stops it at the end of
    its time or at Ctrl-C. ``proved`` lists ``[seconds, value]`` of each bound it raised."""

    def __init__(self, search, bracket: Bracket, budget: Budget, total: float) -> None:
        self.search, self.bracket, self.budget, self.total = search, bracket, budget, total
        self.proved: list = []

    @property
    def pending(self) -> bool:
        return self.search is not None

    def run(self) -> None:
        part = self.budget.child(max(10.0, 0.25 * self.total))
        child, inbox = _fork(_scaffold_child, self.search, part)
        self.search = None
        try:
            while not part.expired():
                if not inbox.poll(min(part.left(), 0.25)):  # short waits: a Ctrl-C is seen at once
                    continue
                try:
                    value = inbox.recv()
                except EOFError:
                    break  # the child is done
                if self.bracket.prove(value):
                    self.proved.append([round(self.bracket.elapsed(), 3), value])
        finally:
            _stop(child, inbox)


def _scaffold_child(search, budget: Budget, outbox) -> None:
    _ignore_ctrl_c()
    search.advance(budget, split=True, on_value=outbox.send)
    outbox.close()


class Ahead:
    """One horizon above the :class:`Background` child's, decided in this process (module
    docstring); ``tried`` lists ``[horizon, answer, seconds]``."""

    GROWTH = 2.0  # each horizon's proof is taken to cost at least this many times the one below

    def __init__(self, instance: Instance, solver: str, bracket: Bracket, child: Background, budget: Budget) -> None:
        self.instance, self.solver, self.bracket, self.child, self.budget = instance, solver, bracket, child, budget
        self.tried: list = []

    def pick(self) -> tuple[int, float] | None:
        """The highest horizon above the child's, below the best schedule's makespan and not tried
        yet, whose proof is expected within most of the time left, with the seconds expected; None
        before the child refuted two horizons."""
        bracket, seconds = self.bracket, self.child.seconds
        done = sorted(k for k in seconds if k < bracket.lower)
        if len(done) < 2 or bracket.best is None:
            return None
        k, last = done[-1], max(seconds[done[-1]], 1e-3)
        growth = max(self.GROWTH, last / max(seconds[done[-2]], 1e-3))
        left, tried = self.budget.left(), {h for h, _, _ in self.tried}
        pick = None
        for h in range(max(self.child.k, bracket.lower) + 1, bracket.best.makespan):
            expected = last * growth ** (h - k)
            if expected > 0.8 * left:
                break
            if h not in tried:
                pick = (h, expected)
        return pick

    def run(self, h: int, expected: float) -> None:
        """Decide horizon ``h``, for at most twice the seconds expected (at least 5)."""
        inst, bracket = self.instance, self.bracket
        part = self.budget.child(max(2 * expected, 5.0))
        answer = UNKNOWN
        try:
            model = build(inst, h, Options(), budget=part)
            with open_backend(self.solver, model, inst, budget=part) as backend:
                outcome = backend.solve(budget=part)
            answer = outcome.status
        except OutOfTime:
            pass
        finally:
            self.tried.append([h, answer, round(part.elapsed(), 3)])
        if answer == UNSAT:  # no schedule of h steps or fewer
            bracket.prove(h + 1)
            self.child.catch_up()
        elif answer == SAT:
            found = from_schedule(inst, Schedule.from_ids(inst, decode(model, inst, outcome.value)), "exact")
            if found is None:
                raise RuntimeError(f"anytime: the exact model gave an invalid schedule at horizon {h}")
            bracket.offer(found)


def _rise_child(instance: Instance, solver: str, lower: int, budget: Budget, outbox) -> None:
    """The child's loop: raise the bound until ``budget`` ends (its copy of the parent's: the
    parent's cancel does not reach it, the parent stops it) or an optimal schedule, sending each
    news."""
    _ignore_ctrl_c()
    bracket = Bracket(lower)
    rise = Rise(instance, solver, bracket, budget)
    bracket.on_bound.append(lambda value: outbox.send(("lower", (value, rise.seconds.get(value - 1)))))
    bracket.on_schedule.append(lambda found: outbox.send(("optimal", found.ids.tolist())))
    while not budget.expired():
        rise.step(budget)
        if rise.finished:
            break
    rise.close()
    outbox.close()
