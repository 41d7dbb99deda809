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

import json
import logging
import queue
import statistics
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from bille.instances import Instance, Robot, dump_instance
from bille.instances.grid import Grid
from bille.instances.rules import State, Violation, apply
from bille.solvers import Schedule, bind, save_schedule, solve

from .broker import BrokerURL, close, connect
from .journal import Journal, Replayed, plan_states, sha256_file
from .protocol import (ExecutionError, Gate, Sealer, new_session, parse_topic, pose_from_json, pose_json,
                       tile_cells, tiles_summary, topic)

log = logging.getLogger("bille.execute")
POLICIES = ("stop", "retry", "replan")


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


@dataclass
class Fault:
    step: int
    robot: str
    kind: str  # failed | lost | silent | mismatch
    detail: str

    def __str__(self) -> str:
        return f"step {self.step}: robot {self.robot}: {self.kind}: {self.detail}"


@dataclass
class Outcome:
    """What a run did. ``status``: ``completed`` or ``stopped`` (safely, after ``faults[-1]``)."""

    status: str
    steps: int
    finished: int
    seconds: float
    executed: int = 0  # steps finished by this executor (a resumed run starts after the journal's)
    round_trips: list[float] = field(default_factory=list)
    faults: list[Fault] = field(default_factory=list)
    duplicates: int = 0
    rejected: int = 0
    worlds_match: bool = False
    robot_counters: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        rt = sorted(self.round_trips)
        ms = {}
        if rt:
            ms = {"mean": 1000 * statistics.fmean(rt), "p50": 1000 * rt[len(rt) // 2],
                  "p95": 1000 * rt[min(len(rt) - 1, int(0.95 * len(rt)))], "max": 1000 * rt[-1]}
        return {
            "status": self.status, "steps": self.steps, "finished": self.finished, "executed": self.executed,
            "seconds": round(self.seconds, 3),
            "steps_per_second": round(self.executed / self.seconds, 2) if self.seconds > 0 else None,
            "round_trip_ms": {k: round(v, 2) for k, v in ms.items()},
            "faults": [str(f) for f in self.faults], "duplicates": self.duplicates, "rejected": self.rejected,
            "worlds_match_goal": self.worlds_match, "robot_counters": self.robot_counters,
        }


class Executor:
    """Runs ``plan`` (action ids ``int[m, L]``) of ``instance`` on the robots of ``settings``."""

    def __init__(self, instance: Instance, plan: np.ndarray, settings: Settings, journal: Journal,
                 progress: Callable[[int, int, list[str]], None] | None = None, states: list[State] | None = None):
        if len(settings.robots) != instance.num_robots:
            raise ExecutionError(f"--robots: {len(settings.robots)} robots given, but the schedule has "
                                 f"{instance.num_robots}")
        self.instance, self.world, self.s, self.journal = instance, instance.world, settings, journal
        self.set_plan(plan, states if states is not None else plan_states(instance, plan, "the schedule"))
        self.progress = progress or (lambda k, done, waiting: None)
        self.gate = Gate(settings.secrets)
        self.sealers = {r: Sealer(r, settings.secrets[r]) for r in settings.robots}
        self.run_id = new_session()
        self.inbox: queue.Queue = queue.Queue()
        self.reports: dict[str, dict] = {}
        self.arrivals: dict[str, float] = {}
        self.connection: dict[str, str] = {}
        self.nonces: dict[str, str] = {}  # each robot process's, from its reports
        self.released_at = 0.0
        self.round_trips: list[float] = []
        self.faults: list[Fault] = []
        self.updates = 0
        self.client = None

    def set_plan(self, plan: np.ndarray, states: list[State]) -> None:
        self.plan, self.states = plan, states
        self._digests: dict[bytes, dict] = {}  # tile digest of the last tile set asked for
        self.names = [[ms.actions[a].name for a in row] for ms, row in zip(self.instance.movesets, plan.tolist())]

    @property
    def length(self) -> int:
        return self.plan.shape[1]

    # ---- messages -----------------------------------------------------------------------------

    def connect(self) -> None:
        subs = [(topic(self.s.fleet, r, kind), 1) for r in self.s.robots for kind in ("state", "connection")]
        self.client = connect(self.s.url, f"bille-executor-{self.s.fleet}-{self.run_id}",
                              on_message=lambda c, u, m: self.inbox.put((m.topic, m.payload, time.perf_counter())),
                              on_connected=lambda c: c.subscribe(subs))

    def close(self) -> None:
        if self.client is not None:
            close(self.client)
            self.client = None

    def send(self, robot: str, kind: str, body: dict) -> None:
        """Sign and publish, tied to the robot's live process by its nonce (unknown before its
        first report: then only a state request gets through)."""
        body = {"nonce": self.nonces.get(robot, "unknown"), **body}
        self.client.publish(topic(self.s.fleet, robot, kind), self.sealers[robot].seal(kind, body), qos=1)

    def pump(self, timeout: float) -> None:
        """Take in the messages waiting, or the first to arrive within ``timeout`` seconds."""
        try:
            item = self.inbox.get(timeout=max(0.0, timeout))
        except queue.Empty:
            return
        while True:
            self.take(*item)
            try:
                item = self.inbox.get_nowait()
            except queue.Empty:
                return

    def take(self, name: str, payload: bytes, at: float) -> None:
        parsed = parse_topic(name)
        if parsed is None or parsed[0] != self.s.fleet or parsed[1] not in self.sealers:
            return
        msg = self.gate.admit(parsed[1], parsed[2], payload)
        if not isinstance(msg, dict):
            log.warning("%s", msg)
        elif parsed[2] == "state":
            self.reports[parsed[1]] = msg
            self.arrivals[parsed[1]] = at
            self.nonces[parsed[1]] = msg["nonce"]
        else:
            self.connection[parsed[1]] = msg["connectionState"]
            self.nonces[parsed[1]] = msg["nonce"]

    def request_state(self, robots, params=None, kind="stateRequest") -> None:
        for r in robots:
            self.send(r, "instantActions", {"actions": [
                {"actionId": f"{self.run_id}-{kind}-{self.updates}", "actionType": kind,
                 "parameters": params(r) if params else {}}]})
        self.updates += 1

    def wait_for(self, robots, ok: Callable[[dict], bool], timeout: float, resend=None) -> list[str]:
        """Wait until ``ok(report)`` holds for every robot; the robots for which it does not.

        ``resend(missing)`` repeats a request every second (a robot may not have listened yet).
        """
        end = time.perf_counter() + timeout
        again = time.perf_counter() + 1.0
        while True:
            missing = [r for r in robots if r not in self.reports or not ok(self.reports[r])]
            if not missing or time.perf_counter() >= end:
                return missing
            if resend is not None and time.perf_counter() >= again:
                resend(missing)
                again = time.perf_counter() + 1.0
            self.pump(min(0.05, end - time.perf_counter()))

    # ---- the world in messages ----------------------------------------------------------------

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

    def recover(self, k: int, fault: Fault) -> int | None:
        """Bring the robots back to the state after step ``k - 1`` and (for ``replan``) plan again.

        Returns the step to release next, or None when the run must stop.
        """
        robots = self.s.robots
        self.connection = {r: s for r, s in self.connection.items() if s == "ONLINE"}
        self.reports = {r: rep for r, rep in self.reports.items() if r != fault.robot}
        try:
            self.bring_up(k - 1, k, self.s.reconnect_timeout)
        except ExecutionError as exc:
            log.warning("recovery of step %d failed: %s", k, exc)
            return None
        return self.replan_at(k) if self.s.on_fault == "replan" else k

    def replan_at(self, k: int) -> int | None:
        """Re-plan before releasing step ``k`` (robots at step ``k - 1``, some perhaps at ``k``);
        the step to release next, or None."""
        robots = self.s.robots
        done = [i for i, r in enumerate(robots) if self.reports[r]["lastStep"] == k]
        if not self.replan(k, done):
            return None
        if not done:
            return k
        # the robots' copies of the world took in the whole step: give them the world as it is
        self.request_state(robots, self.initialize_params(k), kind="initialize")
        if self.wait_for(robots, lambda rep: rep["lastStep"] == k and self.matches(robots.index(rep["robot"]), rep, k),
                         self.s.step_timeout):
            return None
        self.journal.write("finished", step=k)
        return k + 1

    def replan(self, k: int, done: list[int]) -> bool:
        """Plan from the state the robots report, with the chosen method.

        If robots ``done`` finished step ``k`` and the others did not, step ``k`` becomes what
        happened (the others wait) and the plan goes on after it; otherwise after step ``k - 1``.
        """
        inst, prefix = self.instance, self.plan[:, : k - 1]
        st = self.states[k - 1]
        if done:
            for r in self.s.robots:
                self.reports.pop(r, None)
            step = np.array([self.plan[i, k - 1] if i in done else inst.movesets[i].wait for i in range(inst.num_robots)])
            st = apply(self.world, st, step, step=k)
            if isinstance(st, Violation):
                log.warning("cannot re-plan: step %d done by only some robots breaks the rules: %s", k, st.message)
                return False
            prefix = np.concatenate([prefix, step[:, None]], axis=1)
        result = solve(_instance_at(inst, st, f"{inst.name}-from-{prefix.shape[1]}"), self.s.replan_method,
                       time_limit=self.s.replan_time_limit)
        if result.schedule is None or result.status not in ("optimal", "feasible"):
            log.warning("re-planning from step %d with %s found no schedule (%s)", prefix.shape[1],
                        self.s.replan_method, result.status)
            return False
        tail = np.concatenate([prefix[:, k - 1:], bind(inst, result.schedule)], axis=1)
        path = self.journal.path.with_name(f"{self.journal.path.name}.replan-{k - 1}.schedule.yaml")
        save_schedule(Schedule.from_ids(inst, tail), path)
        plan = np.concatenate([self.plan[:, : k - 1], tail], axis=1)
        self.set_plan(plan, self.states[:k] + plan_states(inst, tail, "the re-planned schedule", self.states[k - 1])[1:])
        self.journal.write("replan", step=k - 1, schedule=str(path), schedule_sha256=sha256_file(path),
                           method=self.s.replan_method, steps=int(tail.shape[1]))
        return True

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


def _instance_at(inst: Instance, st: State, name: str) -> Instance:
    """The instance of reaching ``inst``'s goal from state ``st`` (tiles, poses, loads)."""
    grid = Grid.from_masks(inst.width, inst.height, inst.start.obstacles, st.tiles)
    robots = []
    for i, r in enumerate(inst.robots):
        feet = inst.world.graphs[i].feet_xy(st.poses[i])
        robots.append(Robot(feet[0], feet[1] if len(feet) > 1 else None, bool(st.carrying[i]), r.moveset))
    return Instance(name, inst.moveset, grid, tuple(robots), inst.goal_grid, inst.robot_goals)


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


def summary_lines(out: Outcome, journal: Path) -> list[str]:
    j = out.to_json()
    resumed = f" ({out.executed} in this run)" if out.executed != out.finished else ""
    lines = [f"{out.status}: {out.finished} of {out.steps} steps{resumed} in {j['seconds']:.2f} s "
             f"({j['steps_per_second'] or 0:.1f} steps/s)"]
    if j["round_trip_ms"]:
        rt = j["round_trip_ms"]
        lines.append(f"round trip: mean {rt['mean']:.1f} ms, p95 {rt['p95']:.1f} ms, max {rt['max']:.1f} ms")
    lines.append(f"messages dropped: {out.duplicates} duplicate or out of order, {out.rejected} rejected")
    if out.status == "completed":
        lines.append("robots' worlds equal the goal" if out.worlds_match else "robots' worlds DIFFER from the goal")
    for f in out.faults:
        lines.append(f"fault: {f}")
    if out.status == "stopped":
        lines.append(f"all robots hold after step {out.finished}. Retry the step with: bille run --resume {journal}; "
                     f"or re-plan from here: bille run --resume {journal} --replan --replan-method METHOD")
    lines.append(f"journal: {journal}")
    return lines


def dumps(out: Outcome) -> str:
    return json.dumps(out.to_json())
