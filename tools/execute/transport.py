"""The executor's side of the wire: connecting, signing and sending, taking in and checking the
robots' reports (see :mod:`.protocol`)."""
from __future__ import annotations

import logging
import queue
import time
from typing import Callable

from .broker import close, connect
from .protocol import Gate, Sealer, new_session, parse_topic, topic

log = logging.getLogger("bille.execute")


class Transport:
    """Messages to and from the robots of ``settings`` (a part of :class:`.executor.Executor`)."""

    def __init__(self, settings) -> None:
        self.s = settings
        self.gate = Gate(settings.secrets)
        self.sealers = {r: Sealer(r, settings.secrets[r]) for r in settings.robots}
        self.run_id = new_session()
        self.inbox: queue.Queue = queue.Queue()
        self.reports: dict[str, dict] = {}
        self.arrivals: dict[str, float] = {}
        self.connection: dict[str, str] = {}
        self.nonces: dict[str, str] = {}  # each robot process's, from its reports
        self.updates = 0
        self.client = None

    def connect(self) -> None:
        subs = [(topic(self.s.fleet, r, kind), 1) for r in self.s.robots for kind in ("state", "connection")]
        self.client = connect(self.s.url, f"bille-executor-{self.s.fleet}-{self.run_id}",
                              on_message=lambda c, u, m: self.inbox.put((m.topic, m.payload, time.perf_counter(),
                                                                         bool(m.retain))),
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

    def take(self, name: str, payload: bytes, at: float, retained: bool = False) -> None:
        parsed = parse_topic(name)
        if parsed is None or parsed[0] != self.s.fleet or parsed[1] not in self.sealers or not payload:
            return  # not ours, or a cleared retained message
        msg = self.gate.admit(parsed[1], parsed[2], payload)
        if not isinstance(msg, dict):
            # expected: repeats (QoS 1 delivers at least once) and what a broker kept from earlier
            # runs (retained, signed with other secrets); anything else is worth a warning
            log.log(logging.DEBUG if msg.duplicate or retained else logging.WARNING, "%s", msg)
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
