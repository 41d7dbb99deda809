"""The robot protocol: topics, messages, schemas and signatures (see docs/execution.md).

In the style of VDA 5050 (JSON orders and state reports over MQTT), adapted to Bill-E's motions.
Per robot the topics are ``bille/v1/<fleet>/<robot>/{order,instantActions,state,connection}``.
Every message carries ``headerId`` (counting up per sender session and topic), ``timestamp``,
``version``, ``robot``, ``session`` (the sender's random session id) and ``signature``: the
HMAC-SHA256, keyed with the robot's shared secret, of the message's canonical JSON without the
signature. :class:`Gate` is the receiving side: it drops malformed, unsigned, forged, duplicate,
out-of-order and replayed messages and says why.

Live runs: a robot process draws a fresh random ``nonce`` when it starts and sends it in every
``connection`` and ``state`` message; the executor signs the robot's current nonce into every
``order`` and ``instantActions`` message for it. A robot acts only on messages that carry its own
nonce (:func:`tied_to`), so nothing recorded before it started (an earlier run's ``initialize``
or orders, replayed) can move it; a ``stateRequest`` alone changes nothing and is answered
whatever its nonce, which is how an executor learns the nonce of a robot it meets.
"""
from __future__ import annotations

import hashlib
import hmac
import json
import secrets
from dataclasses import dataclass, field
from datetime import datetime, timezone

from jsonschema import Draft202012Validator

from bille.instances import BilleError

VERSION = "1.0.0"
KINDS = ("order", "instantActions", "state", "connection")
STATUSES = ("WAITING", "RUNNING", "FINISHED", "FAILED")
CONNECTION_STATES = ("ONLINE", "OFFLINE", "CONNECTIONBROKEN")


class ExecutionError(BilleError):
    """Bad input to the execution layer: an unreachable broker, a robot that does not answer,
    a schedule that does not fit, a journal that does not match."""


def topic(fleet: str, robot: str, kind: str) -> str:
    """``bille/v1/<fleet>/<robot>/<kind>``."""
    return f"bille/v1/{fleet}/{robot}/{kind}"


def parse_topic(name: str) -> tuple[str, str, str] | None:
    """``(fleet, robot, kind)`` of a protocol topic, or None."""
    parts = name.split("/")
    if len(parts) != 5 or parts[:2] != ["bille", "v1"] or parts[4] not in KINDS:
        return None
    return parts[2], parts[3], parts[4]


def now() -> str:
    """An ISO 8601 UTC timestamp with milliseconds (sortable as text)."""
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


def new_session() -> str:
    return secrets.token_hex(8)


def new_nonce() -> str:
    """A robot process's nonce: 128 random bits as hex."""
    return secrets.token_hex(16)


def tied_to(msg: dict, nonce: str) -> bool:
    """Whether a robot with ``nonce`` may act on an admitted ``order`` or ``instantActions``
    message: it carries that nonce, or it only asks for a state report."""
    if msg["nonce"] == nonce:
        return True
    return "actions" in msg and all(a["actionType"] == "stateRequest" for a in msg["actions"])


def canonical(body: dict) -> bytes:
    return json.dumps(body, sort_keys=True, separators=(",", ":")).encode()


def sign(body: dict, secret: bytes) -> str:
    return hmac.new(secret, canonical(body), hashlib.sha256).hexdigest()


def is_signature(text: str) -> bool:
    """Whether ``text`` has the form of a signature (64 lower-case hex digits): only such text is
    compared with one (``hmac.compare_digest`` refuses text that is not ASCII)."""
    return len(text) == 64 and all(c in "0123456789abcdef" for c in text)


def tiles_digest(cells) -> str:
    """The digest of a tile set: SHA-256 of ``"x,y;x,y;..."`` in row-major order."""
    text = ";".join(f"{x},{y}" for x, y in sorted(cells, key=lambda c: (c[1], c[0])))
    return hashlib.sha256(text.encode()).hexdigest()


# ---- schemas ------------------------------------------------------------------------------------

_XY = {"type": "array", "items": {"type": "integer", "minimum": 0}, "minItems": 2, "maxItems": 2}
_POSE = {
    "oneOf": [
        {"type": "object", "required": ["front", "back"], "additionalProperties": False,
         "properties": {"front": _XY, "back": _XY}},
        {"type": "object", "required": ["at"], "additionalProperties": False, "properties": {"at": _XY}},
    ]
}
_HEADER = {
    "headerId": {"type": "integer", "minimum": 0},
    "timestamp": {"type": "string", "pattern": r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$"},
    "version": {"const": VERSION},
    "robot": {"type": "string", "minLength": 1},
    "session": {"type": "string", "minLength": 1},
    "signature": {"type": "string", "pattern": "^[0-9a-f]{64}$"},
}
_STEP = {
    "type": "object",
    "required": ["sequenceId", "action", "released", "structure"],
    "additionalProperties": False,
    "properties": {
        "sequenceId": {"type": "integer", "minimum": 1},
        "action": {"type": "string", "minLength": 1},
        "released": {"type": "boolean"},
        "structure": {
            "type": "object", "required": ["picked", "placed"], "additionalProperties": False,
            "properties": {"picked": {"type": "array", "items": _XY}, "placed": {"type": "array", "items": _XY}},
        },
    },
}
_NONCE = {"type": "string", "minLength": 1, "maxLength": 64}
_BODIES = {
    "order": {
        "nonce": _NONCE,
        "orderId": {"type": "string", "minLength": 1},
        "orderUpdateId": {"type": "integer", "minimum": 0},
        "steps": {"type": "array", "items": _STEP, "minItems": 1},
    },
    "instantActions": {
        "nonce": _NONCE,
        "actions": {
            "type": "array", "minItems": 1,
            "items": {
                "type": "object", "required": ["actionId", "actionType", "parameters"], "additionalProperties": False,
                "properties": {
                    "actionId": {"type": "string", "minLength": 1},
                    "actionType": {"enum": ["initialize", "stateRequest", "cancelOrder"]},
                    "parameters": {"type": "object"},
                },
            },
        },
    },
    "state": {
        "nonce": _NONCE,
        "initialized": {"type": "boolean"},
        "orderId": {"type": ["string", "null"]},
        "orderUpdateId": {"type": "integer", "minimum": 0},
        "lastStep": {"type": "integer", "minimum": 0},
        "pose": {"oneOf": [_POSE, {"type": "null"}]},
        "carrying": {"type": "boolean"},
        "tiles": {
            "type": "object", "required": ["count", "digest"], "additionalProperties": False,
            "properties": {"count": {"type": "integer", "minimum": 0}, "digest": {"type": "string"}},
        },
        "actionStates": {
            "type": "array",
            "items": {
                "type": "object", "required": ["sequenceId", "action", "actionStatus"], "additionalProperties": False,
                "properties": {"sequenceId": {"type": "integer", "minimum": 1}, "action": {"type": "string"},
                               "actionStatus": {"enum": list(STATUSES)}},
            },
        },
        "errors": {
            "type": "array",
            "items": {
                "type": "object", "required": ["errorType", "errorDescription"], "additionalProperties": False,
                "properties": {"errorType": {"type": "string"}, "errorDescription": {"type": "string"},
                               "sequenceId": {"type": "integer"}},
            },
        },
        "counters": {
            "type": "object", "additionalProperties": {"type": "integer", "minimum": 0},
            "required": ["picks", "places", "executed", "duplicates", "rejected"],
        },
        "replyTo": {"type": ["string", "null"]},
    },
    "connection": {"nonce": _NONCE, "connectionState": {"enum": list(CONNECTION_STATES)}},
}
SCHEMAS = {
    kind: {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": f"bille {kind} message",
        "type": "object",
        "required": sorted(_HEADER) + sorted(body),
        "additionalProperties": False,
        "properties": {**_HEADER, **body},
    }
    for kind, body in _BODIES.items()
}
_VALIDATORS = {kind: Draft202012Validator(schema) for kind, schema in SCHEMAS.items()}


def schema_error(kind: str, message: dict) -> str | None:
    """The first schema violation of a message, as ``field: problem``, or None."""
    err = next(iter(sorted(_VALIDATORS[kind].iter_errors(message), key=lambda e: list(e.path))), None)
    if err is None:
        return None
    where = ".".join(str(p) for p in err.path) or "message"
    return f"{where}: {err.message}"


# ---- sending ------------------------------------------------------------------------------------


@dataclass
class Sealer:
    """Builds signed messages for one sender session: header fields, a headerId per topic kind."""

    robot: str
    secret: bytes
    session: str = field(default_factory=new_session)
    counters: dict[str, int] = field(default_factory=dict)

    def seal(self, kind: str, body: dict, header_id: int | None = None) -> bytes:
        """The signed message of ``kind`` as bytes. Raises ValueError if it breaks its schema
        (a bug on the sending side, never sent)."""
        if header_id is None:
            header_id = self.counters.get(kind, 0) + 1
        self.counters[kind] = max(self.counters.get(kind, 0), header_id)
        msg = {"headerId": header_id, "timestamp": now(), "version": VERSION, "robot": self.robot,
               "session": self.session, **body}
        msg["signature"] = sign(msg, self.secret)
        problem = schema_error(kind, msg)
        if problem:
            raise ValueError(f"refusing to send a {kind} message that breaks its schema: {problem}")
        return canonical(msg)


# ---- receiving ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Rejection:
    """Why a received message was dropped; ``duplicate`` marks repeats and stale messages."""

    robot: str
    kind: str
    reason: str
    duplicate: bool = False

    def __str__(self) -> str:
        return f"dropped {self.kind} message for {self.robot}: {self.reason}"


@dataclass
class Gate:
    """Checks incoming messages: JSON, signature, schema, robot, session and headerId order.

    ``secrets`` maps robot id to its shared secret. Per (robot, kind) the gate remembers the
    sender's session, the last headerId and timestamp: a message with a headerId not above the
    last one of the same session is a duplicate or out of order; a new session is accepted only
    with a timestamp not older than the last message seen (a restarted sender), so an old
    session's messages cannot be replayed.
    """

    secrets: dict[str, bytes]
    last: dict[tuple[str, str], tuple[str, int, str]] = field(default_factory=dict)
    rejected: int = 0
    duplicates: int = 0

    def admit(self, robot: str, kind: str, payload: bytes) -> dict | Rejection:
        out = self._check(robot, kind, payload)
        if isinstance(out, Rejection):
            if out.duplicate:
                self.duplicates += 1
            else:
                self.rejected += 1
        return out

    def _check(self, robot: str, kind: str, payload: bytes) -> dict | Rejection:
        def no(reason: str, duplicate: bool = False) -> Rejection:
            return Rejection(robot, kind, reason, duplicate)

        secret = self.secrets.get(robot)
        if secret is None:
            return no("unknown robot id")
        try:
            msg = json.loads(payload)
        except (ValueError, UnicodeDecodeError):
            return no("not JSON")
        if not isinstance(msg, dict):
            return no("not a JSON object")
        sig = msg.pop("signature", None)
        if not isinstance(sig, str):
            return no("no signature")
        if not is_signature(sig) or not hmac.compare_digest(sig, sign(msg, secret)):
            return no("bad signature")
        msg["signature"] = sig
        problem = schema_error(kind, msg)
        if problem:
            return no(f"schema: {problem}")
        if msg["robot"] != robot:
            return no(f"names robot {msg['robot']!r} on {robot}'s topic")
        key = (robot, kind)
        session, header, stamp = msg["session"], msg["headerId"], msg["timestamp"]
        if key in self.last:
            last_session, last_header, last_stamp = self.last[key]
            if session == last_session and header <= last_header:
                return no(f"headerId {header} is not above {last_header} (duplicate or out of order)", True)
            if session != last_session and stamp < last_stamp:
                return no(f"session {session} is older than the current one (replay)", True)
        self.last[key] = (session, header, stamp)
        return msg


# ---- world fields: poses and tile sets in messages --------------------------------------------


def pose_json(graph, pose: int) -> dict:
    """``{"front": [x, y], "back": [x, y]}`` (point footprint: ``{"at": [x, y]}``)."""
    feet = [list(c) for c in graph.feet_xy(pose)]
    return {"at": feet[0]} if graph.footprint == "point" else {"front": feet[0], "back": feet[1]}


def pose_from_json(graph, obj: dict) -> int:
    """The pose id of a message's pose, or -1 if it is not a valid pose of this footprint."""
    if graph.footprint == "point":
        return graph.pose_of(tuple(obj["at"])) if "at" in obj else -1
    if "front" not in obj:
        return -1
    return graph.pose_of(tuple(obj["front"]), tuple(obj["back"]))


def tiles_summary(tiles, width: int) -> dict:
    """The ``tiles`` field of a state report: the count and :func:`tiles_digest` of a tile mask."""
    cells = tile_cells(tiles, width)
    return {"count": len(cells), "digest": tiles_digest(map(tuple, cells))}


def tile_cells(tiles, width: int) -> list[list[int]]:
    """A tile mask as ``[[x, y], ...]`` in row-major order."""
    return [[int(c) % width, int(c) // width] for c in tiles.nonzero()[0]]
