"""Why a run ended without what it was asked for (docs/decisions.md, "Claims").

A :class:`Failure` has a ``kind`` that code may test and a ``text`` for people; no code reads
the text to decide anything.
"""
from __future__ import annotations

from dataclasses import dataclass

# time-limit: the run's time limit; interrupted: the user (Ctrl-C); cap: a limit of the method's
# own (expansions, nodes, states, steps, the horizon cap); unreachable: a robot cannot reach its
# goal; no-schedule: the space the method searched holds none (walking schedules, a class of
# schedules), which proves nothing for the instance; stuck: a heuristic gave up (a deadlock, no
# joint plan, no sequence); error: a bug (a planner's step the rules reject)
KINDS = ("time-limit", "interrupted", "cap", "unreachable", "no-schedule", "stuck", "error")


@dataclass(frozen=True)
class Failure:
    """``kind``: one of :data:`KINDS`; ``text``: what happened, in words."""

    kind: str
    text: str

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown failure kind {self.kind!r} (expected one of {KINDS})")

    def to_json(self) -> dict:
        return {"kind": self.kind, "text": self.text}

    def __str__(self) -> str:
        return self.text


def cap(text: str) -> Failure:
    return Failure("cap", text)


def stuck(text: str) -> Failure:
    return Failure("stuck", text)


def no_schedule(text: str) -> Failure:
    return Failure("no-schedule", text)


CANNOT_REACH = Failure("unreachable", "unreachable")  # a robot cannot walk to its goal
