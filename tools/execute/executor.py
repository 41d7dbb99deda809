"""The executor: releases a schedule to the robots one step at a time over MQTT.

The synchronous scheme of the paper's Temporal A* section: step ``k`` is released only when every
robot has reported step ``k - 1`` finished. Before a release the executor checks that every
robot's reported world (pose, load, tile digest) is the one the schedule predicts, and applies the
canonical rules to the joint action on the reported state: a step the rules reject is never sent.
Each release and each finished step is journaled before the run goes on (see :mod:`.journal`).

A FAILED action, a robot whose connection breaks, or a robot silent for ``step_timeout`` seconds
after a state request stops further releases (every robot holds where it is) and is handled by
the fault policy: ``stop`` (report and exit; ``bille run --resume`` continues later), ``retry``
(wait for the robot, initialize it again if it restarted, release the step again) or ``replan``
(plan the rest from the reported state with a chosen method and continue).
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from bille.instances import Instance, dump_instance
from bille.instances.rules import State, Violation, apply

from .broker import BrokerURL
from .journal import Journal, Replayed, plan_states
from .outcome import Fault, Outcome
from .protocol import ExecutionError, pose_from_json, pose_json, tile_cells, tiles_summary
from .recovery import Recovery
from .transport import Transport

log = logging.getLogger("bille.execute")


@dataclass
class Settings:
    """How to run: ``robots`` are the ids in schedule order, ``secrets`` their shared secrets."""

    url: BrokerURL
    robots: list[str]
    secrets: dict[str, bytes]
    fleet: str = "default"
    step_timeout: float = 5.0
    window: int = 5  # steps per order: the released one and the horizon after it
    on_fault: str = "stop"
    retries: int = 2
    replan_method: str = "temporal-astar"
    replan_time_limit: float = 60.0
    reconnect_timeout: float = 30.0  # how long ``retry`` waits for a lost robot to answer again
    connect_timeout: float = 30.0  # how long the robots may take to answer at the start




class Executor(Transport, Recovery):
    """Runs ``plan`` (action ids ``int[m, L]``) of ``instance`` on the robots of ``settings``."""

    def __init__(self, instance: Instance, plan: np.ndarray, settings: Settings, journal: Journal,
                 progress: Callable[[int, int, list[str]], None] | None = None, states: list[State] | None = None):
        if len(settings.robots) != instance.num_robots:
            raise ExecutionError(f"--robots: {len(settings.robots)} robots given, but the schedule has "
                                 f"{instance.num_robots}")
        self.instance, self.world, self.s, self.journal = instance, instance.world, settings, journal
        self.set_plan(plan, states if states is not None else plan_states(instance, plan, "the schedule"))
        self.progress = progress or (lambda k, done, waiting: None)
        Transport.__init__(self, settings)
        self.released_at = 0.0
        self.round_trips: list[float] = []
        self.faults: list[Fault] = []

    def set_plan(self, plan: np.ndarray, states: list[State]) -> None:
        self.plan, self.states = plan, states
        self._digests: dict[bytes, dict] = {}  # tile digest of the last tile set asked for
        self.names = [[ms.actions[a].name for a in row] for ms, row in zip(self.instance.movesets, plan.tolist())]

    @property
    def length(self) -> int:
        return self.plan.shape[1]

    def expected(self, i: int, k: int) -> dict:
        st = self.states[k]
        key = st.tiles.tobytes()
        if key not in self._digests:
            self._digests = {key: tiles_summary(st.tiles, self.world.width)}
        return {"pose": pose_json(self.world.graphs[i], st.poses[i]), "carrying": bool(st.carrying[i]),
                "tiles": self._digests[key]}

    def matches(self, i: int, report: dict, k: int) -> bool:
        exp = self.expected(i, k)
        return all(report[key] == exp[key] for key in exp)

    def initialize_params(self, k: int):
        text = dump_instance(self.instance)

        def params(robot: str) -> dict:
            i = self.s.robots.index(robot)
            st = self.states[k]
            return {"instance": text, "index": i, "lastStep": k, "pose": pose_json(self.world.graphs[i], st.poses[i]),
                    "carrying": bool(st.carrying[i]), "tiles": tile_cells(st.tiles, self.world.width)}
        return params

    def structure(self, k: int) -> dict:
        before, after = self.states[k - 1].tiles, self.states[k].tiles
        w = self.world.width
        return {"picked": [[int(c) % w, int(c) // w] for c in np.flatnonzero(before & ~after)],
                "placed": [[int(c) % w, int(c) // w] for c in np.flatnonzero(~before & after)]}

    # ---- the run ------------------------------------------------------------------------------

    def bring_up(self, finished: int, released: int, timeout: float | None = None) -> None:
        """Make every robot's world the journal's: initialize fresh robots, check the others.

        Raises :class:`ExecutionError` for a robot that does not answer or reports a step the
        journal cannot explain.
        """
        robots = self.s.robots
        timeout = timeout or self.s.connect_timeout
        self.request_state(robots)
        silent = self.wait_for(robots, lambda rep: True, timeout, self.request_state)
        if silent:
            raise ExecutionError(f"robot{'s' if len(silent) > 1 else ''} {', '.join(silent)} did not answer within "
                                 f"{timeout:g} s on {self.s.url} (fleet {self.s.fleet}): not running, an "
                                 "unknown id, or a different secret")
        new_run = finished == 0 and released == 0
        fresh = [r for r in robots if new_run or not self.reports[r]["initialized"]]
        if fresh:
            for r in fresh:
                self.reports.pop(r, None)
            params = self.initialize_params(finished)
            self.request_state(fresh, params, kind="initialize")
            silent = self.wait_for(fresh, lambda rep: rep["initialized"] and rep["lastStep"] == finished,
                                   self.s.connect_timeout, lambda missing: self.request_state(missing, params, "initialize"))
            if silent:
                errors = "; ".join(e["errorDescription"] for r in silent for e in self.reports.get(r, {}).get("errors", []))
                raise ExecutionError(f"robot {silent[0]} was not initialized within {self.s.connect_timeout:g} s"
                                     + (f": {errors}" if errors else ""))
        for i, r in enumerate(robots):
            last = self.reports[r]["lastStep"]
            if last not in (finished, released) or not self.matches(i, self.reports[r], last):
                raise ExecutionError(f"robot {r} reports step {last} and a world that the journal does not explain "
                                     f"(finished step {finished}, released {released})")

    def check_release(self, k: int) -> Fault | None:
        """The reported state must be the predicted one, and the rules must accept step ``k`` on it."""
        poses, carrying = list(self.states[k - 1].poses), list(self.states[k - 1].carrying)
        for i, r in enumerate(self.s.robots):
            rep = self.reports[r]
            last = rep["lastStep"]
            if last not in (k - 1, k) or not self.matches(i, rep, last):
                return Fault(k, r, "mismatch", f"reports step {last} with a world that differs from the schedule's")
            if last == k - 1:
                poses[i] = pose_from_json(self.world.graphs[i], rep["pose"])
                carrying[i] = rep["carrying"]
        state = State(self.states[k - 1].tiles, tuple(poses), tuple(carrying))
        out = apply(self.world, state, self.plan[:, k - 1], step=k)
        if isinstance(out, Violation):
            return Fault(k, self.s.robots[out.robot] if out.robot is not None else "-", "rejected",
                         f"the rules reject the step: {out.message}")
        return None

    def release(self, k: int) -> None:
        self.journal.write("released", step=k)
        self.updates += 1
        end = min(self.length, k + self.s.window - 1)
        structures = {j: self.structure(j) for j in range(k, end + 1)}
        self.released_at = time.perf_counter()
        for i, r in enumerate(self.s.robots):
            steps = [{"sequenceId": j, "action": self.names[i][j - 1], "released": j == k, "structure": structures[j]}
                     for j in range(k, end + 1)]
            self.send(r, "order", {"orderId": self.run_id, "orderUpdateId": self.updates, "steps": steps})

    def await_step(self, k: int) -> Fault | None:
        """Wait for every robot to finish step ``k``; the first fault otherwise."""
        robots = self.s.robots
        asked = False
        end = time.perf_counter() + self.s.step_timeout
        timed: set[str] = set()
        while True:
            self.pump(0.02)
            for r in robots:
                rep = self.reports.get(r)
                if rep is not None and rep["lastStep"] >= k and r not in timed:
                    timed.add(r)
                    self.round_trips.append(self.arrivals[r] - self.released_at)
            for r in robots:
                rep = self.reports[r]
                if self.arrivals[r] >= self.released_at and rep["lastStep"] < k:
                    failed = [e for e in rep["errors"] if e.get("sequenceId") == k]
                    if failed:
                        return Fault(k, r, "failed", failed[0]["errorDescription"])
                if self.connection.get(r, "ONLINE") != "ONLINE":
                    return Fault(k, r, "lost", f"connection {self.connection[r]} (last reported step "
                                               f"{rep['lastStep']})")
            waiting = [r for r in robots if self.reports[r]["lastStep"] < k]
            self.progress(k, len(robots) - len(waiting), waiting)
            if not waiting:
                return None
            if time.perf_counter() >= end:
                if asked:
                    return Fault(k, waiting[0], "silent", f"no report of step {k} within "
                                                          f"{2 * self.s.step_timeout:g} s (and no answer to a state request)")
                self.request_state(waiting)  # a report may have been lost
                asked, end = True, time.perf_counter() + self.s.step_timeout

    def execute(self, first: int) -> Outcome:
        """Release steps ``first`` .. L; the robots must have finished step ``first - 1``."""
        start = time.perf_counter()
        k = first
        attempts = 0
        status = "completed"
        while k <= self.length:
            fault = self.check_release(k)
            if fault is None:
                self.release(k)
                fault = self.await_step(k)
            if fault is None:
                self.journal.write("finished", step=k)
                k, attempts = k + 1, 0
                continue
            self.faults.append(fault)
            self.journal.write("fault", step=k, robot=fault.robot, kind=fault.kind, detail=fault.detail)
            log.warning("%s", fault)
            attempts += 1
            if fault.kind in ("mismatch", "rejected") or self.s.on_fault == "stop" or attempts > self.s.retries:
                status = "stopped"
                break
            nxt = self.recover(k, fault)
            if nxt is None:
                status = "stopped"
                break
            k = nxt
        if status == "completed":
            self.journal.write("done", step=self.length)
        return self.outcome(status, k - 1, time.perf_counter() - start, k - first)

    def outcome(self, status: str, finished: int, seconds: float, executed: int = 0) -> Outcome:
        self.request_state(self.s.robots)
        self.wait_for(self.s.robots, lambda rep: rep["lastStep"] >= finished, self.s.step_timeout)
        worlds = status == "completed" and all(
            r in self.reports and self.matches(i, self.reports[r], self.length) for i, r in enumerate(self.s.robots))
        goal = self.states[self.length]
        worlds = worlds and bool(np.array_equal(goal.tiles, self.instance.goal_tiles))
        counters = {r: self.reports[r]["counters"] for r in self.s.robots if r in self.reports}
        return Outcome(status, self.length, finished, seconds, executed, self.round_trips, self.faults,
                       self.gate.duplicates, self.gate.rejected, worlds, counters)


def run_plan(instance: Instance, plan: np.ndarray, settings: Settings, journal: Journal, *,
             replayed: Replayed | None = None, replan: bool = False, progress=None) -> Outcome:
    """Connect, bring the robots up (fresh or from a journal), execute, and disconnect.

    ``replan``: plan the rest again (``settings.replan_method``) from the state the robots report
    before releasing anything.
    """
    if replayed is not None:  # the journal's plan and the world after each of its steps
        ex = Executor(instance, replayed.plan, settings, journal, progress, states=replayed.states)
    else:
        ex = Executor(instance, plan, settings, journal, progress)
    ex.connect()
    try:
        finished = replayed.finished if replayed else 0
        # a step in flight when the executor stopped is released again: robots that did it skip it
        ex.bring_up(finished, replayed.released if replayed else 0)
        first = ex.replan_at(finished + 1) if replan else finished + 1
        if first is None:
            ex.faults.append(Fault(finished + 1, "-", "replan", f"{settings.replan_method} found no schedule"))
            return ex.outcome("stopped", finished, 0.0)
        return ex.execute(first)
    finally:
        ex.close()


def load_secrets(path: str | Path, robots: list[str]) -> dict[str, bytes]:
    """A secrets file: a JSON or YAML mapping of robot id to its shared secret."""
    from bille.instances.yamlsource import load_yaml_file

    path = Path(path)
    data, _ = load_yaml_file(path, ExecutionError)
    if not isinstance(data, dict):
        raise ExecutionError(f"--secrets: {path}: expected a mapping of robot id to secret")
    missing = [r for r in robots if not isinstance(data.get(r), str) or not data[r]]
    if missing:
        raise ExecutionError(f"--secrets: {path}: no secret for robot {missing[0]}")
    return {r: data[r].encode() for r in robots}
