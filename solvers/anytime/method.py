"""Anytime certified solving: a schedule at once, then a shorter schedule and a higher proved lower
bound in turn, until they meet (``optimal``) or the time runs out (``feasible``, both numbers).

1. **First schedule**: the one given (``incumbent``), or the shortest the heuristics find in a
   fifth of the time limit (:func:`bille.solvers.incumbent.first_schedule`): milliseconds on most instances.
   Where they find none, the loop with fewer robots taking jobs (:func:`bille.solvers.incumbent.fewer_robots`),
   the runs their share cut short, again with more time (:func:`bille.solvers.incumbent.retry`), and then the
   complete planner (LaCAM* over whole states,
   :func:`bille.solvers.incumbent.complete_search`) seeks one with the time left; when it exhausts the
   reachable states, no schedule exists and the answer is ``infeasible``.
2. Then two searches run side by side, the first in a child process on a second core
   (``parallel``; without it they take turns in slices of ``slice`` seconds). With ``parallel``
   the bound search starts before the first schedule is sought, so it has the whole time limit:

   - **Raising the bound**: the exact makespan search of :mod:`bille.solvers.exact` from the static lower
     bound up, one model per horizon (its pruning is tightest there). An infeasible horizon ``k``
     proves that no schedule is shorter than ``k + 1``; a satisfiable one is an optimal schedule.
     One CP-SAT worker decides each horizon (``bound_solver``; a python-sat solver instead keeps
     what it learned on an undecided horizon for the next slice). While the neighbourhood search
     has shortened nothing for a tenth of the time limit, this process helps: it decides a
     horizon above the child's, the highest it expects to decide in time (:class:`.rise.Ahead`;
     an infeasible horizon proves the ones below it infeasible too); where there is none (the
     child has not refuted two horizons yet), it takes the static bound's scaffold scenarios
     further, once, where their share of the static bound's time left them undone
     (:class:`.rise.Scaffold`, with the per-robot integer program of
     :mod:`bille.solvers.bounds.routing`).
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
     climbs from below. A second, *kept* search takes turns with it (the one that shortened the
     schedule in its last slice keeps the turn): the same windows, twice as long to start with,
     re-solved among the parts that pick and place only where the window's first and last states
     differ; its models are a fraction of the size, it proves nothing (:mod:`.windows`).

Robots subsets as neighbourhoods (fix the other robots' paths) cannot shorten a makespan unless the
robots they leave out already finish early, so only time windows are searched.

Ctrl-C cancels the run's budget: every part ends as when time runs out, what the bound search's
child sent is read, and ``solve()`` returns status ``interrupted`` with the best schedule and the
bound proved so far, within a second or two. (A ``KeyboardInterrupt``, from a second Ctrl-C or a
``progress``, ``on_schedule`` or ``on_bound`` callback, ends it with the same.) The child process
ignores the terminal's Ctrl-C and is stopped by the parent.

``stats``: ``first`` (method, makespan, seconds), ``improvements`` ([seconds, makespan] for every
shorter schedule), ``lower_bounds`` ([seconds, bound] for every rise), ``windows`` (tried,
shortened, proved not to shorten, undecided; ``proved_bound`` where the whole schedule's window
proved it optimal), ``kept_windows`` (the same counts of the kept search), ``bound_search``
(where the bound search ran), ``ahead`` ([horizon, answer, seconds] decided out of turn),
``scaffold`` ([seconds, bound] raised by the scaffold scenarios taken further), and the seconds
spent on each search.
"""
from __future__ import annotations

import multiprocessing
from dataclasses import dataclass
from typing import Callable

import numpy as np

from bille.encodings.backend import SOLVERS
from bille.instances import Instance, OptionError
from bille.instances.options import MethodOptions, option
from bille.instances.result import Result
from bille.instances.rules import goal_violation
from bille.instances.run import Budget, Run
from bille.instances.schedule import Schedule

from ..bounds import Bounds, lower_bound
from ..incumbent import EXHAUSTED, Incumbent, complete_search, fewer_robots, first_schedule, from_schedule, retry
from .bracket import Bracket
from .rise import FORK, Ahead, Background, Rise, Scaffold
from .windows import Windows


@dataclass(frozen=True)
class AnytimeOptions(MethodOptions):
    """Options of anytime certified solving.

    ``window``: the first window length of the neighbourhood search, in steps. ``slice``:
    seconds the first window may take (each undecided window gives the next half as much again);
    without ``parallel``, also the seconds each search runs before the other takes its turn.
    ``parallel``: raise the bound in a child process, on a second core, while the parent searches
    windows (where the platform cannot fork, or in a daemonic process, which may not start one,
    the two take turns; ``stats.bound_search`` says which). ``solver``: the neighbourhood
    search's back end: a python-sat name (``minisat22``, which can be interrupted when a window's
    budget ends) or ``cpsat`` (one worker, the part's length minimized in one solve);
    docs/decisions.md has the measurements behind the defaults. ``bound_solver``: the bound
    search's back end: ``cpsat`` (one worker) or a python-sat name. ``swap``: a window may end
    with interchangeable robots (one moveset, no goal cell) in one another's end states, the
    rest of the schedule permuted to match. ``incumbent``: a schedule to start from instead of
    the heuristics' (must be valid). ``keep_class``: the exact joint search among the schedules
    that keep the structure after the first schedule (:meth:`_Anytime._keep_class`); ``ladder``:
    then, up to :data:`LADDER_SHARE` of the time limit, the same search over that class widened
    cell by cell below the best schedule (:mod:`.ladder`; ``stats.ladder`` says what each rung
    proved)."""

    METHOD = "anytime"
    window: int = option(8, at_least=2, help="first window length of the neighbourhood search, in steps")
    slice: float = option(2.0, above=0,
                          help="seconds the first window may take (each undecided window gives the next half as much "
                               "again)")
    parallel: bool = option(True,
                            help="raise the bound in a child process on a second core while the windows are searched")
    solver: str = option("minisat22", choices=SOLVERS,
                         help="the neighbourhood search's back end: a python-sat name or cpsat")
    bound_solver: str = option("cpsat", choices=SOLVERS, help="the bound search's back end: cpsat or a python-sat name")
    swap: bool = option(True, help="a window may end with interchangeable robots in one another's end states")
    incumbent: Schedule | None = option(None,
                                        help="a valid schedule to start from instead of the heuristics' (--incumbent "
                                             "FILE)")
    keep_class: bool = option(True, help="first decide the class that keeps the structure by the exact joint search")
    ladder: bool = option(True, help="then widen that class cell by cell below the best schedule (up to 75 % of the "
                                     "time limit)")


def plan(instance: Instance, options: AnytimeOptions | None = None, run: Run | None = None, *,
         bounds: Bounds | None = None) -> Result:
    """Anytime certified solving (module docstring, :class:`AnytimeOptions`) within the run's
    budget (``solve()`` gives 60 s unless told otherwise; no run: no limit). The run's events
    hear of each shorter schedule found (an :class:`~.incumbent.Incumbent`), each higher bound
    proved, and progress ``{"lower", "best", "elapsed"}`` whenever either changes (the command
    line draws a live line from it). ``bounds``: the static bound, if already computed.
    """
    o = options or AnytimeOptions()
    run = run or Run()
    budget = run.budget.child()  # started now: the run's own clock
    bounds = bounds or lower_bound(instance)
    bracket = Bracket(bounds.lower, budget)
    events = run.events
    report = _reporter(bracket, events.on_progress) if events.on_progress is not None else None
    for tell, subscribers in ((report, bracket.on_schedule), (report, bracket.on_bound), (events.on_schedule,
                              bracket.on_schedule), (events.on_bound, bracket.on_bound)):
        if tell is not None:
            subscribers.append(tell)
    search = _Anytime(instance, bracket, budget, o.window, o.slice, o.parallel, o.solver, o.bound_solver, o.swap,
                      report, o.keep_class, o.ladder)
    return search.run(bounds, o.incumbent)


def _reporter(bracket: Bracket, progress: Callable) -> Callable:
    def report(*_) -> None:
        progress({"lower": bracket.lower, "best": None if bracket.best is None else bracket.best.makespan,
                  "elapsed": bracket.elapsed()})

    return report


# of the time limit, at most, for the exact search among the schedules that keep the structure
# (lt-1 to lt-4 and bridge-2 decide it in 0.2-2 s on a 2-core machine; lt-5, lt-7 and lt-8, with
# three robots, not within a minute: there it takes this share for a bound of the class), and its
# state cap
CLASS_SHARE = 0.25
CLASS_STATES = 20_000_000
# of the time limit, at most, counted from the keep class's start, for the widening ladder after
# it (it runs where that class was decided; lt-1's second rung takes 25-27 s, docs/decisions.md)
LADDER_SHARE = 0.75


class _Anytime:
    """One run: the bracket, the parts that narrow it, and the statistics."""

    def __init__(self, instance, bracket, budget: Budget, window, slice_s, parallel, solver, bound_solver, swap,
                 report, keep_class: bool = True, ladder: bool = True) -> None:
        self.instance, self.bracket, self.slice, self.keep_class = instance, bracket, slice_s, keep_class
        self.ladder = ladder
        self.rise = None  # the bound search, once started (the ladder reads what it sent: _closed)
        self.parallel, self.bound_solver, self.report = parallel, bound_solver, report
        self.budget, self.total = budget, budget.left()  # the run's, and its seconds (inf: no limit)
        self.cut: list = []  # the first schedule's runs that ran out of their share
        # the free and the kept neighbourhood search, in turn after a slice that shortened nothing;
        # the kept one's windows twice as long
        self.windows = [Windows(instance, bracket, solver, window, slice_s, swap, budget),
                        Windows(instance, bracket, solver, 2 * window, slice_s, swap, budget, kept=True)]
        self.stats = {"improvements": bracket.improvements, "lower_bounds": bracket.lower_bounds,
                      "windows": self.windows[0].counts, "kept_windows": self.windows[1].counts,
                      "bound_s": 0.0, "search_s": 0.0}

    def run(self, bounds: Bounds, given: Schedule | None) -> Result:
        inst, bracket = self.instance, self.bracket
        if bounds.impossible:
            self.stats["reason"] = "; ".join(bounds.impossible)
            return self.result("infeasible")
        if goal_violation(inst.world, inst.start_state, inst.goal_tiles, inst.goal_cells, 0) is None:
            bracket.best, bracket.lower = Incumbent(np.zeros((inst.num_robots, 0), np.int64), 0, "none"), 0
            return self.result("optimal")
        first = self._given(given)
        why = self._in_turns()
        background = why is None
        self.stats["bound_search"] = "child process" if background else f"in turns: {why}"
        rise, ahead, scaffold, seek, stopped, budget = None, None, None, None, False, self.budget
        try:
            if background:  # the bound search starts at once, beside the heuristics
                rise = Background(inst, self.bound_solver, bracket, budget)
                ahead = Ahead(inst, self.bound_solver, bracket, rise, budget)
                self.stats["ahead"] = ahead.tried
                if bounds.scaffold is not None:
                    scaffold = Scaffold(bounds.scaffold, bracket, budget, self.total)
                    self.stats["scaffold"] = scaffold.proved
            self._first(first)
            self.rise = rise
            self._keep_class()
            rise = rise or Rise(inst, self.bound_solver, bracket, budget)
            seek = _Seek(inst, self.cut, budget, self.total)
            while not bracket.closed and not budget.expired() and not seek.infeasible:
                self._round(rise, seek, ahead, scaffold, background)
            rise.step(budget.child(0))  # what the bound search sent while the last part ran
        except KeyboardInterrupt:  # a second Ctrl-C, or a subscriber that raised it: keep what is held
            stopped = True
            if isinstance(rise, Background):  # the bounds the child proved and sent before it
                try:
                    rise.step(budget.child(0))
                except (KeyboardInterrupt, Exception):  # a message cut by the Ctrl-C: keep what was read
                    pass
        finally:
            if rise is not None:
                rise.close()
        return self._end(stopped, seek)

    def _round(self, rise, seek, ahead, scaffold, background: bool) -> None:
        """One round of :meth:`run`: the bound search's part; then, without a schedule, the
        search for one; with one, a window of the neighbourhood search, and when that has stalled,
        a horizon decided ahead or a scaffold scenario."""
        bracket, budget = self.bracket, self.budget
        part = budget.child(0 if background else self.slice)
        rise.step(part)
        self.stats["bound_s"] += part.elapsed()
        if bracket.best is None and not bracket.closed:
            began = budget.now()
            found = seek.step()
            self.stats["seek_s"] = round(self.stats.get("seek_s", 0.0) + budget.now() - began, 3)
            if found is not None:
                self.start_from(found)
            return
        if bracket.closed:
            return
        part, makespan = budget.child(self.slice), bracket.best.makespan
        self.windows[0].step(part)
        if bracket.best.makespan == makespan:  # the search that shortened it last goes on
            self.windows.reverse()
        self.stats["search_s"] += part.elapsed()
        if not self._stalled() or bracket.closed:
            return
        began = budget.now()
        if ahead is not None and (pick := ahead.pick()) is not None:
            ahead.run(*pick)
        elif scaffold is not None and scaffold.pending:  # no horizon worth deciding ahead
            scaffold.run()
            rise.catch_up()
        self.stats["bound_s"] += budget.now() - began

    def _end(self, stopped: bool, seek) -> Result:
        """The result once the loop of :meth:`run` has ended: how it ended, as a status."""
        if stopped:
            return self.result("interrupted")
        if seek.infeasible:
            self.stats["reason"] = EXHAUSTED
            return self.result("infeasible")
        if self.bracket.best is None:
            return self.result("timeout")
        return self.result("optimal" if self.bracket.closed else "feasible")

    def _stalled(self) -> bool:
        """Whether the best schedule has not shortened for a tenth of the time limit (at least 5 s):
        then this process may help the bound search (:class:`.rise.Ahead`)."""
        since = self.bracket.elapsed() - self.bracket.improvements[-1][0]
        return since >= max(5.0, 0.1 * self.total)

    def _in_turns(self) -> str | None:
        """Why the bound search takes turns with the rest instead of running in a child process
        (None: it runs there). A daemonic process (a worker of a pool, of a sweep) may not start
        children, so there the two searches take turns."""
        if not self.parallel:
            return "parallel is off"
        if FORK is None:
            return "this platform cannot fork"
        if multiprocessing.current_process().daemon:
            return "a daemonic process cannot start a child"
        return None

    def _given(self, given: Schedule | None) -> Incumbent | None:
        """The schedule given to start from, checked by the validator (None if none was given)."""
        if given is None:
            return None
        found = from_schedule(self.instance, given, "given")
        if found is None:
            raise OptionError(f"anytime: the incumbent schedule is not valid for instance "
                              f"'{self.instance.name}' (bille check says why)")
        return found

    def _first(self, given: Incumbent | None) -> None:
        seconds = max(0.01, min(10.0, 0.2 * self.budget.left()))
        found = given or first_schedule(self.instance, self.budget.child(seconds), cut=self.cut)
        if found is not None:
            self.start_from(found)
        elif self.report is not None:
            self.report()

    def _keep_class(self) -> None:
        """The exact joint search among the schedules that keep the structure (:mod:`bille.solvers.bfs`,
        ``cells=keep``) for up to :data:`CLASS_SHARE` of the time limit: on the load-transfer maps it
        decides that class in seconds, its optimum is offered as a schedule, and the class's
        optimum (or the bound it reached) goes to ``stats.class_optima`` (``stats.class_search``
        says how it ended); then, up to :data:`LADDER_SHARE` of the time limit counted from its
        start, it climbs the ladder (:mod:`.ladder`), whose top (the schedules without scaffold)
        gives that class's optimum or bound too. A class's optimum is no bound on every schedule:
        the bracket's lower bound is left as it is."""
        inst = self.instance
        if not self.keep_class or not inst.is_reconfiguration or self.budget.expired():
            return
        from ..bfs import Options as BfsOptions
        from ..bfs import plan as bfs

        began = self.budget.now()
        share = self.budget.child(max(1.0, CLASS_SHARE * self.total))
        got = bfs(inst, BfsOptions(cells="keep", max_states=CLASS_STATES), Run(share.child()))
        lower = got.stats["class"]["lower_bound"]
        self.stats["class_search"] = {"cells": "keep", "status": got.status, "lower_bound": lower,
                                      "states": got.stats.get("states"), "s": round(self.budget.now() - began, 3)}
        if lower is not None:
            self.stats["class_optima" if got.status == "optimal" else "class_lower_bounds"] = {"keep-structure": lower}
        if got.status == "optimal" and got.schedule is not None:
            found = from_schedule(inst, got.schedule, "bfs (cells=keep)")
            if found is not None and self.bracket.best is None:
                self.start_from(found)
            elif found is not None:
                self.bracket.offer(found)
        if self.ladder and got.status == "optimal" and self.bracket.best is not None:
            from .ladder import climb, top_class

            def offer(schedule: Schedule) -> None:
                found = from_schedule(inst, schedule, "bfs (ladder)")
                if found is not None:
                    self.bracket.offer(found)

            rest = max(0.0, LADDER_SHARE * self.total - (self.budget.now() - began))
            self.stats["ladder"] = climb(inst, lambda: self.bracket.best, self.budget.child(rest), offer, CLASS_STATES,
                                         self._closed)
            for key, value in top_class(self.stats["ladder"]).items():  # the schedules without scaffold
                self.stats.setdefault(key, {})["no-scaffold"] = value

    def _closed(self) -> bool:
        """Whether the bracket is closed, with the bounds the background bound search has sent."""
        if isinstance(self.rise, Background):
            self.rise.step(self.budget.child(0))
        return self.bracket.closed

    def start_from(self, found: Incumbent) -> None:
        """``found`` is the first schedule: ``stats.first`` names it."""
        self.stats["first"] = {"method": found.method, "makespan": found.makespan,
                               "s": round(self.bracket.elapsed(), 3)}
        self.bracket.offer(found)

    def result(self, status: str) -> Result:
        for key in ("bound_s", "search_s"):
            self.stats[key] = round(self.stats[key], 3)
        best = self.bracket.best
        schedule = None if best is None else Schedule.from_ids(self.instance, best.ids, meta={"method": "anytime"})
        lower = None if status == "infeasible" else self.bracket.lower
        return Result("anytime", status, schedule, lower_bound=lower, stats=self.stats,
                      time_s=self.bracket.elapsed())


class _Seek:
    """No schedule yet: the reconfiguration loop with fewer robots taking jobs
    (:func:`bille.solvers.incumbent.fewer_robots`) for a fifth of the time limit (at least 4 s); the runs of the
    first schedule that their share cut short, again with twice the time in turn
    (:func:`bille.solvers.incumbent.retry`: a run that ends before its time drops out), for up to three tenths
    (at least 6 s); then the complete planner (:func:`bille.solvers.incumbent.complete_search`) for a tenth (at
    least 2 s), so that what the bound search found beside it is read soon on small instances,
    and then once more, from the start, with all the time left: its search is deterministic and
    heavy-tailed (a few restarts would each stop short of where one long run gets), so it is not
    cut into restarts."""

    def __init__(self, instance: Instance, cut: list, budget: Budget, total: float) -> None:
        self.instance, self.cut, self.budget, self.infeasible = instance, cut, budget, False
        tenth = max(2.0, 0.1 * total)
        self.stages = [("fewer robots", 2 * tenth)]  # (stage, seconds), in turn
        self.stages += [("retry", 3 * tenth)] if cut else []
        self.stages += [("complete", tenth)]

    def step(self) -> Incumbent | None:
        """The next stage; the schedule it found, or None."""
        stage, seconds = self.stages.pop(0) if self.stages else ("complete", float("inf"))
        budget = self.budget.child(max(0.01, seconds))  # never past the run's end
        if stage == "retry":
            return retry(self.instance, self.cut, budget)
        if stage == "fewer robots":
            return fewer_robots(self.instance, budget)
        found, self.infeasible = complete_search(self.instance, budget)
        return found
