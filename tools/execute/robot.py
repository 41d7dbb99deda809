"""The simulated robot: the reference implementation of the robot side of the protocol.

One process per robot. It subscribes to its ``order`` and ``instantActions`` topics, keeps its own
copy of the world (tiles, its pose, its load), executes each released step at most once (a step
whose ``sequenceId`` is not above the last one executed is never executed again, so no pick or
place can happen twice), checks its own action against the canonical rules restricted to itself
before moving, and reports its state after every step. Faults can be injected for tests: a
failed action, a delayed or dropped report, a process that dies.
"""
from __future__ import annotations

import logging
import os
import queue
import random
import signal
import time
from dataclasses import dataclass, field

import numpy as np

from bille.instances import BilleError, instance_from_text
from bille.instances.grid import is_connected
from bille.instances.rules import State, Violation, World, apply

from .broker import BrokerURL, close, connect
from .protocol import (Gate, Sealer, new_nonce, parse_topic, pose_from_json, pose_json, tied_to, tiles_digest,
                       tiles_summary, topic)

log = logging.getLogger("bille.robot")


@dataclass
class Faults:
    """Injected faults. ``*_at`` are step numbers (each fires once); ``rate`` is the chance per
    step of a random failed action or dropped report (drawn from ``seed``); ``delay_ms`` delays
    every report."""

    fail_at: set[int] = field(default_factory=set)
    drop_at: set[int] = field(default_factory=set)
    die_at: set[int] = field(default_factory=set)
    rate: float = 0.0
    delay_ms: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)

    def draw(self, step: int) -> str | None:
        """The fault for a step: ``die``, ``fail``, ``drop`` or None."""
        for kind, steps in (("die", self.die_at), ("fail", self.fail_at), ("drop", self.drop_at)):
            if step in steps:
                steps.discard(step)
                return kind
        if self.rate > 0 and self.rng.random() < self.rate:
            return self.rng.choice(("fail", "drop"))
        return None


class SimRobot:
    """A simulated robot ``robot_id`` of ``fleet`` on the broker at ``url``."""

    def __init__(self, robot_id: str, url: BrokerURL, secret: bytes, *, fleet: str = "default",
                 faults: Faults | None = None):
        self.id, self.url, self.fleet = robot_id, url, fleet
        self.faults = faults or Faults()
        self.sealer = Sealer(robot_id, secret)
        self.gate = Gate({robot_id: secret})
        self.nonce = new_nonce()  # this process's: messages of earlier runs do not carry it
        self.inbox: queue.Queue = queue.Queue()
        self.world: World | None = None
        self.graph = None
        self.tiles: np.ndarray | None = None
        self.pose, self.carrying, self.last_step = -1, False, 0
        self.order_id, self.order_update = None, 0
        self.action_states: list[dict] = []
        self.errors: list[dict] = []
        self.counters = {"picks": 0, "places": 0, "executed": 0, "duplicates": 0, "rejected": 0}
        self.client = None
        self.running = True

    # ---- connection ---------------------------------------------------------------------------

    def _topic(self, kind: str) -> str:
        return topic(self.fleet, self.id, kind)

    def start(self) -> None:
        self._announce()
        self.client = connect(self.url, f"bille-robot-{self.fleet}-{self.id}", will=(self._topic("connection"), self.will),
                              on_message=lambda c, u, m: self.inbox.put((m.topic, m.payload)),
                              on_connected=self._connected, on_disconnected=self._disconnected)

    def _announce(self) -> None:
        # ONLINE, then the last will with the next headerId: a broken connection is news
        self.online = self.sealer.seal("connection", {"nonce": self.nonce, "connectionState": "ONLINE"})
        self.will = self.sealer.seal("connection", {"nonce": self.nonce, "connectionState": "CONNECTIONBROKEN"})

    def _connected(self, client) -> None:
        client.subscribe([(self._topic("order"), 1), (self._topic("instantActions"), 1)])
        client.publish(self._topic("connection"), self.online, qos=1, retain=True)
        self.inbox.put(("report", b""))  # tell whoever listens where this robot is

    def _disconnected(self, client) -> None:
        if self.running:  # the broker may have sent our will: announce anew on reconnection
            self._announce()
            client.will_set(self._topic("connection"), self.will, qos=1, retain=True)

    def stop(self) -> None:
        if self.client is not None:
            off = self.sealer.seal("connection", {"nonce": self.nonce, "connectionState": "OFFLINE"})
            self.client.publish(self._topic("connection"), off, qos=1, retain=True).wait_for_publish(2)
            close(self.client)
            self.client = None

    def serve(self) -> None:
        """Handle messages until stopped (SIGTERM or SIGINT)."""
        self.start()
        try:
            while self.running:
                try:
                    name, payload = self.inbox.get(timeout=0.2)
                except queue.Empty:
                    continue
                self.handle(name, payload)
        finally:
            self.stop()

    # ---- messages -----------------------------------------------------------------------------

    def handle(self, name: str, payload: bytes) -> None:
        if name == "report":
            self.report()
            return
        parsed = parse_topic(name)
        if parsed != (self.fleet, self.id, "order") and parsed != (self.fleet, self.id, "instantActions"):
            return  # not addressed to this robot (a broker may deliver retained messages of other topics)
        if not payload:
            return  # a cleared retained message
        msg = self.gate.admit(self.id, parsed[2], payload)
        if not isinstance(msg, dict):
            self.counters["duplicates" if msg.duplicate else "rejected"] += 1
            log.log(logging.DEBUG if msg.duplicate else logging.WARNING, "%s", msg)  # repeats are expected
            return
        if not tied_to(msg, self.nonce):  # signed, but for a robot process that is gone
            self.counters["rejected"] += 1
            log.warning("dropped %s message for %s: nonce %s is not this process's (a replay of an earlier run)",
                        parsed[2], self.id, msg["nonce"])
            self.report()  # whoever runs the robots learns the current nonce
            return
        if parsed[2] == "instantActions":
            reply = None
            for act in msg["actions"]:
                if act["actionType"] == "initialize":
                    self.initialize(act["parameters"])
                elif act["actionType"] == "cancelOrder":
                    self.order_id = None
                reply = act["actionId"]
            self.report(reply_to=reply)
        elif parsed[2] == "order":
            self.order(msg)

    def initialize(self, params: dict) -> None:
        """Take the world from an ``initialize`` action: instance text, own index, pose, load,
        tile set and the last executed step."""
        try:
            inst = instance_from_text(params["instance"], name="initialize")
            graph = inst.world.graphs[int(params["index"])]
            pose = pose_from_json(graph, params["pose"])
            if pose < 0:
                raise BilleError(f"pose {params['pose']} is not a valid pose")
            tiles = np.zeros(inst.width * inst.height, dtype=bool)
            for x, y in params["tiles"]:
                if not (0 <= x < inst.width and 0 <= y < inst.height):
                    raise ValueError(f"tile [{x}, {y}] is outside the {inst.width}x{inst.height} grid")
                tiles[y * inst.width + x] = True
        except (BilleError, KeyError, IndexError, TypeError, ValueError) as exc:
            self.errors = [{"errorType": "initializeFailed", "errorDescription": str(exc)}]
            log.warning("initialize failed: %s", exc)
            return
        self.world = World(inst.width, inst.height, inst.start.obstacles, (graph,))
        self.graph, self.tiles, self.pose = graph, tiles, pose
        self.carrying, self.last_step = bool(params["carrying"]), int(params["lastStep"])
        self.action_states, self.errors = [], []

    def order(self, msg: dict) -> None:
        if self.world is None:
            self.errors = [{"errorType": "notInitialized", "errorDescription": "order before initialize"}]
            self.report()
            return
        self.order_id, self.order_update = msg["orderId"], msg["orderUpdateId"]
        self.errors = []
        for step in sorted(msg["steps"], key=lambda s: s["sequenceId"]):
            k = step["sequenceId"]
            if not step["released"]:
                continue
            if k <= self.last_step:  # executed before: never again
                self.counters["duplicates"] += 1
                continue
            if k != self.last_step + 1:
                self._fail(step, "outOfOrder", f"step {k} released after step {self.last_step}")
                break
            fault = self.faults.draw(k)
            if fault == "die":
                log.warning("injected fault: dying before step %d", k)
                os._exit(17)
            ok = self._fail(step, "injectedFault", f"injected failure of step {k}") if fault == "fail" else self.execute(step)
            if not ok:
                break
            if fault == "drop":
                log.warning("injected fault: dropping the report of step %d", k)
                return
        self.report()

    def execute(self, step: dict) -> bool:
        """Execute one released step if the rules allow it; False (and FAILED) otherwise."""
        k, name = step["sequenceId"], step["action"]
        index = self.graph.moveset.index
        if name not in index:
            return self._fail(step, "unknownAction", f"{name!r} is not in moveset {self.graph.moveset.name}")
        a = index[name]
        w, h = self.world.width, self.world.height
        for x, y in step["structure"]["picked"] + step["structure"]["placed"]:
            if not (0 <= x < w and 0 <= y < h):
                return self._fail(step, "structureMismatch", f"the step's structure names [{x}, {y}], outside the "
                                                             f"{w}x{h} grid")
        picked = {y * w + x for x, y in step["structure"]["picked"]}
        placed = {y * w + x for x, y in step["structure"]["placed"]}
        target = int(self.graph.target[self.pose, a])
        kind = self.graph.moveset.actions[a].kind.name.lower()
        if kind in ("pick", "place") and target not in (picked if kind == "pick" else placed):
            return self._fail(step, "structureMismatch", f"the step's structure changes do not list this {kind}")
        # the other robots' picks and places of the same step, then this robot's action
        before = self.tiles.copy()
        before[list(picked - {target})] = False
        before[list(placed - {target})] = True
        out = apply(self.world, State(before, (self.pose,), (self.carrying,)), [a], step=k)
        if isinstance(out, Violation):
            return self._fail(step, "ruleViolation", str(out).replace("robot 0", f"robot {self.id}"))
        if (picked or placed) and not is_connected(out.tiles, w, self.world.height):
            return self._fail(step, "ruleViolation", f"step {k}: connectivity: the structure would fall apart")
        self.tiles = out.tiles.copy()
        self.pose, self.carrying, self.last_step = out.poses[0], out.carrying[0], k
        self.counters["executed"] += 1
        self.counters["picks"] += kind == "pick"
        self.counters["places"] += kind == "place"
        self._status(k, name, "FINISHED")
        return True

    def _fail(self, step: dict, kind: str, text: str) -> bool:
        self._status(step["sequenceId"], step["action"], "FAILED")
        self.errors = [{"errorType": kind, "errorDescription": text, "sequenceId": step["sequenceId"]}]
        log.warning("step %d failed: %s", step["sequenceId"], text)
        return False

    def _status(self, k: int, name: str, status: str) -> None:
        self.action_states = [s for s in self.action_states if s["sequenceId"] != k][-7:]
        self.action_states.append({"sequenceId": k, "action": name, "actionStatus": status})

    def state(self, reply_to: str | None = None) -> dict:
        return {
            "nonce": self.nonce,
            "initialized": self.world is not None,
            "orderId": self.order_id,
            "orderUpdateId": self.order_update,
            "lastStep": self.last_step,
            "pose": pose_json(self.graph, self.pose) if self.world is not None else None,
            "carrying": self.carrying,
            "tiles": tiles_summary(self.tiles, self.world.width) if self.world is not None
            else {"count": 0, "digest": tiles_digest([])},
            "actionStates": list(self.action_states),
            "errors": list(self.errors),
            "counters": dict(self.counters),
            "replyTo": reply_to,
        }

    def report(self, reply_to: str | None = None) -> None:
        if self.faults.delay_ms > 0:
            time.sleep(self.faults.delay_ms / 1000)
        self.client.publish(self._topic("state"), self.sealer.seal("state", self.state(reply_to)), qos=1)


def serve(robot_id: str, url: BrokerURL, secret: bytes, *, fleet: str, faults: Faults) -> None:
    """Run one simulated robot until SIGTERM or SIGINT."""
    robot = SimRobot(robot_id, url, secret, fleet=fleet, faults=faults)

    def stop(*_):
        robot.running = False

    before = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        robot.serve()
    finally:  # served in-process (tests, an embedding program): its handlers are given back
        for sig, handler in before.items():
            signal.signal(sig, handler)
