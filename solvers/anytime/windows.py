"""The neighbourhood search of anytime solving (:mod:`.method`): time windows of the best schedule re-solved
exactly in fewer steps (that module's docstring, "Shortening the schedule").

Two searches take turns. The *free* one re-solves a window under every rule: a window over the
whole schedule proved not to shorten is a proof of optimality. The *kept* one re-solves a window
among the parts that pick and place only on the cells where the window's first and last states
differ (``Options.keep_structure`` on the window's sub-instance). It is a restriction, so it proves
nothing about the instance, but its models are a fraction of the size (lt-1, a window of 24 steps:
32 k variables against 147 k), so it decides windows two to four times as long in the same time.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.backend import Objective, open_backend
from bille.encodings.ends import roles_taken
from bille.encodings.model import Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance, instance_at
from bille.instances.grid import Grid
from bille.instances.rules import run
from bille.instances.run import Budget
from bille.instances.schedule import Schedule

from ..incumbent import Incumbent, from_schedule
from .bracket import Bracket


class Windows:
    """Large neighbourhood search over time windows of the bracket's best schedule (module
    docstring): windows of ``length`` steps to start with, each given ``seconds`` to start with
    (within the run's ``budget``), re-solved by ``solver`` (a back end's name); ``swap`` lets interchangeable robots
    end in each other's places. Shorter schedules are offered to ``bracket``, and the whole
    schedule's window proves bounds there. ``counts``: windows tried, shortened (swapped),
    proved not to shorten, undecided; ``proved_bound`` once the whole schedule's window proved one."""

    def __init__(self, instance: Instance, bracket: Bracket, solver: str, length: int, seconds: float, swap: bool,
                 budget: Budget, kept: bool = False) -> None:
        self.instance, self.bracket, self.solver, self.swap, self.budget = instance, bracket, solver, swap, budget
        self.kept = kept
        self.length = length
        self.seconds = seconds  # per window: grows by half after an undecided one
        self.done: set = set()  # (schedule key, a, b) proved not to shorten
        self.cursor = 0
        self.counts = {"tried": 0, "shortened": 0, "swapped": 0, "not_shorter": 0, "undecided": 0}

    def windows(self, makespan: int) -> list[tuple[int, int]]:
        w = min(self.length, makespan)
        stride = max(1, w // 2)
        out = [(makespan - w, makespan)]  # the tail first: it ends at the goal, the freest window
        out += [(a, a + w) for a in range(0, makespan - w, stride)]
        return out

    def step(self, part: Budget) -> None:
        """Windows until ``part`` (a child of the run's budget) expires or the bracket closes."""
        bracket = self.bracket
        while not part.expired() and not bracket.closed:
            best = bracket.best
            key = best.ids.tobytes()
            todo = [(a, b) for a, b in self.windows(best.makespan) if (key, a, b) not in self.done]
            if not todo:  # every window of this length proved; the whole schedule's closes the run
                self.length = min(best.makespan, self.length + max(1, self.length // 2))
                continue
            a, b = todo[self.cursor % len(todo)]
            self.cursor += 1
            status = self.shorten(best, a, b, self.budget.child(self.seconds))
            if status == UNSAT:
                self.done.add((key, a, b))
            elif status == UNKNOWN:
                self.seconds *= 1.5

    def _proved(self, bound: int) -> str:
        """The window over the whole schedule is the exact search from the start to the goal: no
        schedule shorter than ``bound`` in it means none at all, a lower bound of its own (not
        under the restriction of the kept search)."""
        if self.kept:
            return UNSAT
        self.counts["proved_bound"] = bound
        self.bracket.prove(bound)
        return UNSAT

    def shorten(self, best: Incumbent, a: int, b: int, budget: Budget) -> str:
        inst, counts = self.instance, self.counts
        counts["tried"] += 1
        states = [inst.start_state] + list(run_states(inst, best.ids))
        sub = instance_at(inst, states[a], f"{inst.name}[{a}:{b}]")
        end = None
        if b < best.makespan:
            end = states[b]
            sub = dataclasses.replace(sub, goal=Grid.from_masks(inst.width, inst.height, inst.start.obstacles,
                                                                end.tiles))
        L = b - a - 1
        whole = a == 0 and b == best.makespan
        if L < 1:
            return self._proved(best.makespan) if whole else UNSAT
        try:
            model = build(sub, L, Options(keep_structure=self.kept), min_done=1, budget=budget, end=end,
                          swap=self.swap)
        except OutOfTime:
            counts["undecided"] += 1
            return UNKNOWN
        found = shortest_part(model, sub, L, budget, self.solver)
        if isinstance(found, str):
            counts["undecided" if found == UNKNOWN else "not_shorter"] += 1
            return self._proved(best.makespan) if found == UNSAT and whole else found
        k, part, roles, shortest = found
        if shortest and whole:
            self._proved(k)
        # robot i goes on with the rest of the schedule of the robot whose end state it took
        ids = np.concatenate([best.ids[:, :a], part[:, :k], best.ids[roles, b:]], axis=1)
        spliced = from_schedule(inst, Schedule.from_ids(inst, ids), "anytime")
        if spliced is not None and self.bracket.offer(spliced):
            counts["shortened"] += 1
            counts["swapped"] += roles != list(range(inst.num_robots))
        return SAT


def shortest_part(model, sub: Instance, L: int, budget: Budget, solver: str):
    """The window's shortest part: ``done[L]`` required, as many steps ``done`` as can be
    (``done[k]``: every robot waits from step ``k`` on). Returns ``(k, part, roles, shortest)``
    for the best part found (its first ``k`` steps; ``shortest``: proved so), else ``unsat`` or
    ``unknown``."""
    done = [model.done[k] for k in range(1, L + 1)]
    try:
        backend = open_backend(solver, model, sub, budget=budget)
    except OutOfTime:
        return UNKNOWN
    with backend:
        outcome = backend.solve(budget=budget, objective=Objective(done, maximize=True, chain=True, at_most=L - 1))
    if outcome.values is None:
        return outcome.status
    k = next(k for k in range(1, L + 1) if outcome.value(model.done[k]))
    return k, decode(model, sub, outcome.value), roles_taken(model, outcome.value, sub.num_robots), outcome.status == SAT


def run_states(instance: Instance, ids: np.ndarray):
    """The states after each step of a valid schedule's action ids."""
    return run(instance.world, instance.start_state, ids)
