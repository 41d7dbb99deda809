"""Anytime certified solving: a schedule at once, then a shorter schedule and a higher proved lower
bound in turn, until they meet (``optimal``) or the time runs out (``feasible``, both numbers).

1. **First schedule**: the one given (``incumbent``), or the shortest the heuristics find in a
   fifth of the time limit (:func:`.incumbent.first_schedule`): milliseconds on most instances.
   Where they find none, the loop with fewer robots taking jobs (:func:`.incumbent.fewer_robots`),
   the runs their share cut short, again with more time (:func:`.incumbent.retry`), and then the
   complete planner (LaCAM* over whole states,
   :func:`.incumbent.complete_search`) seeks one with the time left; when it exhausts the
   reachable states, no schedule exists and the answer is ``infeasible``.
2. Then two searches run side by side, the first in a child process on a second core
   (``parallel``; without it they take turns in slices of ``slice`` seconds). With ``parallel``
   the bound search starts before the first schedule is sought, so it has the whole time limit:

   - **Raising the bound**: the exact makespan search of :mod:`.exact` from the static lower
     bound up, one model per horizon (its pruning is tightest there). An infeasible horizon ``k``
     proves that no schedule is shorter than ``k + 1``; a satisfiable one is an optimal schedule.
     One CP-SAT worker decides each horizon (``bound_solver``; a python-sat solver instead keeps
     what it learned on an undecided horizon for the next slice).
   - **Shortening the schedule**: large neighbourhood search over time windows (after MAPF-LNS,
     Li et al., IJCAI 2021). A window ``[a, b]`` of the schedule is re-solved exactly with the
     time-expanded model: from the state at ``a`` (tiles, poses, loads) to exactly the state at
     ``b`` in fewer than ``b - a`` steps. A solution fits back in place (the rest of the schedule
     starts from the same state), so the schedule stays valid; the spliced schedule is checked by
     the validator all the same. The last window ends at the goal instead of the state at ``b``
     (robots end anywhere the goal allows). A window proved not to shorten is not tried again
     on the same schedule; when every window of the current length is, the length grows by half,
     up to the whole schedule. That window is the exact search at horizon ``makespan - 1``
     from the start to the goal: proved infeasible, it is a lower bound of its own, equal to the
     makespan, and so is the shortest schedule it finds when it proves that none is shorter; the
     run ends ``optimal`` (``windows.proved_bound``), proved from the top while the bound search
     climbs from below.

Robots subsets as neighbourhoods (fix the other robots' paths) cannot shorten a makespan unless the
robots they leave out already finish early, so only time windows are searched.

``stats``: ``first`` (method, makespan, seconds), ``improvements`` ([seconds, makespan] for every
shorter schedule), ``lower_bounds`` ([seconds, bound] for every rise), ``windows`` (tried,
shortened, proved not to shorten, undecided; ``proved_bound`` where the whole schedule's window
proved it optimal), and the seconds spent on each search.
"""
from __future__ import annotations

import multiprocessing
import time
from typing import Callable

import numpy as np

from bille.encodings import SAT, UNKNOWN
from bille.encodings.backend import SOLVERS, open_backend
from bille.encodings.model import Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance, OptionError
from bille.instances.result import Result
from bille.instances.rules import goal_violation
from bille.instances.schedule import Schedule

from .bounds import Bounds, lower_bound
from .incumbent import EXHAUSTED, Incumbent, complete_search, fewer_robots, first_schedule, from_schedule, retry
from .windows import Windows

try:  # the bound search runs in a forked child process where the platform has fork
    _FORK = multiprocessing.get_context("fork")
except ValueError:
    _FORK = None


def plan(instance: Instance, *, time_limit: float = 60.0, window: int = 8, slice: float = 2.0,
         parallel: bool = True, solver: str = "minisat22", bound_solver: str = "cpsat", swap: bool = True,
         incumbent: Schedule | None = None, bounds: Bounds | None = None,
         progress: Callable | None = None) -> Result:
    """Anytime certified solving (module docstring).

    Parameters
    ----------
    time_limit : seconds for the whole run (default 60).
    window : the first window length of the neighbourhood search, in steps (default 8).
    slice : seconds the first window may take (each undecided window gives the next half as much
        again); without ``parallel``, also the seconds each search runs before the other takes its
        turn (default 2).
    parallel : raise the bound in a child process, on a second core, while the parent searches
        windows (default; where the platform cannot fork, the two take turns).
    solver : the neighbourhood search's solver: a python-sat name (default ``minisat22``: on the
        lt maps it reaches the same schedules as ``glucose42`` sooner, both decide more windows
        than ``cadical195``, and it stops at its deadline) or ``cpsat`` (one worker, the part's
        length minimized in one solve; measured no better).
    bound_solver : the bound search's solver: ``cpsat`` (the default: one CP-SAT worker, measured
        3 to 4 times faster than CaDiCaL on these models, bridge-2 at T = 14 to 16: 2.5 / 3.6 /
        7.7 s against 11 / 19 / 29 s) or a python-sat solver name.
    swap : a window may end with interchangeable robots (one moveset, no goal cell) in one
        another's end states, the rest of the schedule permuted to match (default true).
    incumbent : a schedule to start from instead of the heuristics' (must be valid).
    progress : called with ``{"lower": ..., "best": ..., "elapsed": ...}`` whenever either
        number changes (the command line draws a live line from it).
    """
    for name, value in (("solver", solver), ("bound_solver", bound_solver)):
        if value not in SOLVERS:
            raise OptionError(f"anytime: unknown {name} {value!r} (expected one of: {', '.join(SOLVERS)})")
    if window < 2 or slice <= 0:
        raise OptionError(f"anytime: window must be at least 2 and slice positive, got {window} and {slice}")
    return _Anytime(instance, time_limit, window, slice, parallel, (solver, bound_solver), swap, incumbent, bounds,
                    progress).run()


class _Anytime:
    def __init__(self, instance, time_limit, window, slice_s, parallel, solvers, swap, incumbent, bounds,
                 progress):
        self.instance, self.window, self.slice, self.swap = instance, window, slice_s, swap
        self.solver, self.bound_solver = solvers
        self.parallel = parallel
        self.start = time.perf_counter()
        self.end = self.start + time_limit
        self.bounds = bounds or lower_bound(instance)
        self.lower = self.bounds.lower
        self.progress = progress
        self.given = incumbent
        self.cut: list = []  # the first schedule's runs that ran out of their share
        self.best: Incumbent | None = None
        self.stats = {"improvements": [], "lower_bounds": [],
                      "windows": {"tried": 0, "shortened": 0, "swapped": 0, "not_shorter": 0, "undecided": 0},
                      "bound_s": 0.0, "search_s": 0.0}

    def elapsed(self) -> float:
        return time.perf_counter() - self.start

    def left(self) -> float:
        return self.end - time.perf_counter()

    def closed(self) -> bool:
        return self.best is not None and self.lower >= self.best.makespan

    def report(self) -> None:
        if self.progress is not None:
            self.progress({"lower": self.lower, "best": None if self.best is None else self.best.makespan,
                           "elapsed": self.elapsed()})

    def improve(self, found: Incumbent) -> bool:
        if self.best is not None and found.makespan >= self.best.makespan:
            return False
        self.best = found
        self.stats["improvements"].append([round(self.elapsed(), 3), found.makespan])
        self.report()
        return True

    def raise_lower(self, value: int) -> None:
        if value > self.lower:
            self.lower = value
            self.stats["lower_bounds"].append([round(self.elapsed(), 3), value])
            self.report()

    # ---- the run -----------------------------------------------------------------------------

    def run(self) -> Result:
        inst = self.instance
        if self.bounds.impossible:
            self.stats["reason"] = "; ".join(self.bounds.impossible)
            return self.result("infeasible")
        if goal_violation(inst.world, inst.start_state, inst.goal_tiles, inst.goal_cells, 0) is None:
            self.best, self.lower = Incumbent(np.zeros((inst.num_robots, 0), np.int64), 0, "none"), 0
            return self.result("optimal")
        given = self._given()
        background = self.parallel and _FORK is not None
        rise = _Background(self) if background else None  # the bound search starts at once, beside the heuristics
        try:
            self._first(given)
            rise = rise or _Rise(self)
            windows = Windows(self)
            seek = _Seek(self)
            while not self.closed() and self.left() > 0 and not seek.infeasible:
                began = time.perf_counter()
                rise.step(min(self.end, began + (0 if background else self.slice)))
                self.stats["bound_s"] += time.perf_counter() - began
                if self.best is None and not self.closed():
                    seek.step()
                    continue
                if self.closed():
                    continue
                began = time.perf_counter()
                windows.step(min(self.end, began + self.slice))
                self.stats["search_s"] += time.perf_counter() - began
            rise.step(time.perf_counter())  # what the bound search sent while the last part ran
        finally:
            if rise is not None:
                rise.close()
        if seek.infeasible:
            self.stats["reason"] = EXHAUSTED
            return self.result("infeasible")
        if self.best is None:
            return self.result("timeout")
        return self.result("optimal" if self.closed() else "feasible")

    def _given(self) -> Incumbent | None:
        """The schedule given to start from, checked by the validator (None if none was given)."""
        if self.given is None:
            return None
        found = from_schedule(self.instance, self.given, "given")
        if found is None:
            raise OptionError(f"anytime: the incumbent schedule is not valid for instance "
                              f"'{self.instance.name}' (bille check says why)")
        return found

    def _first(self, given: Incumbent | None) -> None:
        found = given or first_schedule(self.instance, max(0.01, min(10.0, 0.2 * self.left())), cut=self.cut)
        if found is not None:
            self.start_from(found)
        else:
            self.report()

    def start_from(self, found: Incumbent) -> None:
        """``found`` is the first schedule: ``stats.first`` names it."""
        self.stats["first"] = {"method": found.method, "makespan": found.makespan, "s": round(self.elapsed(), 3)}
        self.improve(found)

    def result(self, status: str) -> Result:
        for key in ("bound_s", "search_s"):
            self.stats[key] = round(self.stats[key], 3)
        schedule = None if self.best is None else Schedule.from_ids(self.instance, self.best.ids,
                                                                    meta={"method": "anytime"})
        lower = None if status == "infeasible" else self.lower
        return Result("anytime", status, schedule, lower_bound=lower, stats=self.stats, time_s=self.elapsed())


class _Seek:
    """No schedule yet: the reconfiguration loop with fewer robots taking jobs
    (:func:`.incumbent.fewer_robots`) for a fifth of the time limit (at least 4 s); the runs of the
    first schedule that their share cut short, again with twice the time in turn
    (:func:`.incumbent.retry`: a run that ends before its time drops out), for up to three tenths
    (at least 6 s); then the complete planner (:func:`.incumbent.complete_search`) for a tenth (at
    least 2 s), so that what the bound search found beside it is read soon on small instances,
    and then once more, from the start, with all the time left: its search is deterministic and
    heavy-tailed (on a random 10x8 instance with four robots and ten moved tiles, 17 s to a
    schedule with seed 0, 37 and 39 s with seeds 1 and 3, none in 40 s with seed 2), so it is
    not cut into restarts."""

    def __init__(self, run: _Anytime) -> None:
        self.run, self.infeasible = run, False
        tenth = max(2.0, 0.1 * (run.end - run.start))
        self.stages = [("fewer robots", 2 * tenth)]  # (stage, seconds), in turn
        self.stages += [("retry", 3 * tenth)] if run.cut else []
        self.stages += [("complete", tenth)]

    def step(self) -> None:
        run = self.run
        began = time.perf_counter()
        stage, seconds = self.stages.pop(0) if self.stages else ("complete", float("inf"))
        budget = max(0.01, min(seconds, run.left()))
        if stage == "retry":
            found = retry(run.instance, run.cut, budget)
        elif stage == "fewer robots":
            found = fewer_robots(run.instance, budget)
        else:
            found, self.infeasible = complete_search(run.instance, budget)
        run.stats["seek_s"] = round(run.stats.get("seek_s", 0.0) + time.perf_counter() - began, 3)
        if found is not None:
            run.start_from(found)


class _Rise:
    """The exact makespan search from the lower bound up, in slices (module docstring)."""

    def __init__(self, run: _Anytime) -> None:
        self.run, self.k = run, max(1, run.lower)
        self.model = self.backend = None
        self.finished = False  # an optimal schedule was found

    def step(self, until: float) -> None:
        run, inst = self.run, self.run.instance
        while time.perf_counter() < until and not run.closed():
            if self.backend is None:
                try:
                    self.model = build(inst, self.k, Options(), deadline=run.end)
                except OutOfTime:
                    return
                self.backend = open_backend(run.bound_solver, self.model, inst)
            outcome = self.backend.solve(deadline=until)
            status = outcome.status
            if status == UNKNOWN:
                return
            if status == SAT:  # every horizon below k is infeasible: optimal
                found = from_schedule(inst, Schedule.from_ids(inst, decode(self.model, inst, outcome.value)), "exact")
                if found is None:
                    raise RuntimeError(f"anytime: the exact model gave an invalid schedule at horizon {self.k}")
                run.improve(found)
                run.raise_lower(found.makespan)
                self.finished = True
                self.close()
                return
            run.raise_lower(self.k + 1)
            self.close()
            self.k = max(self.k + 1, run.lower)

    def close(self) -> None:
        if self.backend is not None:
            self.backend.close()
        self.model = self.backend = None


class _Background:
    """The same search in a child process, on a core of its own: it sends each proved bound, or
    an optimal schedule, through a pipe; the parent reads them between windows."""

    def __init__(self, run: _Anytime) -> None:
        self.run = run
        self.inbox, outbox = _FORK.Pipe(duplex=False)
        self.child = _FORK.Process(target=_rise_child, args=(run, outbox), daemon=True)
        self.child.start()
        outbox.close()

    def step(self, until: float) -> None:
        self.wait(until)

    def wait(self, until: float) -> None:
        run = self.run
        while not run.closed():
            if not self.inbox.poll(max(0.0, until - time.perf_counter())):
                return
            try:
                kind, value = self.inbox.recv()
            except EOFError:
                return
            if kind == "lower":
                run.raise_lower(value)
            else:
                found = from_schedule(run.instance, Schedule.from_ids(run.instance, np.array(value)), "exact")
                if found is None:
                    raise RuntimeError("anytime: the exact model gave an invalid schedule")
                run.improve(found)
                run.raise_lower(found.makespan)

    def close(self) -> None:
        if self.child.is_alive():
            self.child.terminate()
        self.child.join()
        self.inbox.close()


def _rise_child(run: _Anytime, outbox) -> None:
    """The child's loop: raise the bound until the time limit or an optimal schedule."""
    run.progress = None
    sent = run.lower

    def send_lower(value):
        nonlocal sent
        if value > sent:
            sent = value
            outbox.send(("lower", value))

    run.raise_lower = send_lower
    run.improve = lambda found: outbox.send(("optimal", found.ids.tolist())) or True
    rise = _Rise(run)
    while run.left() > 0:
        rise.step(run.end)
        if rise.finished:
            break
    rise.close()
    outbox.close()
