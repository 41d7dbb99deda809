"""The neighbourhood search of :mod:`.anytime`: time windows of the best schedule re-solved
exactly in fewer steps (that module's docstring, "Shortening the schedule")."""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from bille.encodings import SAT, UNKNOWN, UNSAT
from bille.encodings.backend import Objective, open_backend
from bille.encodings.ends import roles_taken
from bille.encodings.model import Options, OutOfTime, build
from bille.encodings.solution import decode
from bille.instances import Instance, instance_at
from bille.instances.grid import Grid
from bille.instances.rules import run
from bille.instances.schedule import Schedule

from .incumbent import Incumbent, from_schedule


class Windows:
    """Large neighbourhood search over time windows of the best schedule (module docstring)."""

    def __init__(self, run) -> None:
        self.run = run
        self.length = run.window
        self.done: set = set()  # (schedule key, a, b) proved not to shorten
        self.cursor = 0
        self.budget = run.slice  # seconds per window: grows by half after an undecided one

    def windows(self, makespan: int) -> list[tuple[int, int]]:
        w = min(self.length, makespan)
        stride = max(1, w // 2)
        out = [(makespan - w, makespan)]  # the tail first: it ends at the goal, the freest window
        out += [(a, a + w) for a in range(0, makespan - w, stride)]
        return out

    def step(self, until: float) -> None:
        run = self.run
        while time.perf_counter() < until and not run.closed():
            best = run.best
            key = best.ids.tobytes()
            todo = [(a, b) for a, b in self.windows(best.makespan) if (key, a, b) not in self.done]
            if not todo:  # every window of this length proved; the whole schedule's closes the run
                self.length = min(best.makespan, self.length + max(1, self.length // 2))
                continue
            a, b = todo[self.cursor % len(todo)]
            self.cursor += 1
            status = self.shorten(best, a, b, min(run.end, time.perf_counter() + self.budget))
            if status == UNSAT:
                self.done.add((key, a, b))
            elif status == UNKNOWN:
                self.budget *= 1.5

    def _proved(self, bound: int) -> str:
        """The window over the whole schedule is the exact search from the start to the goal: no
        schedule shorter than ``bound`` in it means none at all, a lower bound of its own."""
        self.run.stats["windows"]["proved_bound"] = bound
        self.run.raise_lower(bound)
        return UNSAT

    def shorten(self, best: Incumbent, a: int, b: int, until: float) -> str:
        run, inst = self.run, self.run.instance
        counts = run.stats["windows"]
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
            model = build(sub, L, Options(), min_done=1, deadline=until, end=end, swap=run.swap)
        except OutOfTime:
            counts["undecided"] += 1
            return UNKNOWN
        found = shortest_part(model, sub, L, until, run.solver)
        if isinstance(found, str):
            counts["undecided" if found == UNKNOWN else "not_shorter"] += 1
            return self._proved(best.makespan) if found == UNSAT and whole else found
        k, part, roles, shortest = found
        if shortest and whole:
            self._proved(k)
        # robot i goes on with the rest of the schedule of the robot whose end state it took
        ids = np.concatenate([best.ids[:, :a], part[:, :k], best.ids[roles, b:]], axis=1)
        spliced = from_schedule(inst, Schedule.from_ids(inst, ids), "anytime")
        if spliced is not None and run.improve(spliced):
            counts["shortened"] += 1
            counts["swapped"] += roles != list(range(inst.num_robots))
        return SAT


def shortest_part(model, sub: Instance, L: int, until: float, solver: str):
    """The window's shortest part: ``done[L]`` required, as many steps ``done`` as can be
    (``done[k]``: every robot waits from step ``k`` on). Returns ``(k, part, roles, shortest)``
    for the best part found (its first ``k`` steps; ``shortest``: proved so), else ``unsat`` or
    ``unknown``."""
    done = [model.done[k] for k in range(1, L + 1)]
    with open_backend(solver, model, sub) as backend:
        outcome = backend.solve(deadline=until, objective=Objective(done, maximize=True, chain=True, at_most=L - 1))
    if outcome.values is None:
        return outcome.status
    k = next(k for k in range(1, L + 1) if outcome.value(model.done[k]))
    return k, decode(model, sub, outcome.value), roles_taken(model, outcome.value, sub.num_robots), outcome.status == SAT


def run_states(instance: Instance, ids: np.ndarray):
    """The states after each step of a valid schedule's action ids."""
    return run(instance.world, instance.start_state, ids)
