"""What a run did: its faults, its outcome, and how they are printed."""
from __future__ import annotations

import json
import statistics
from dataclasses import dataclass, field
from pathlib import Path

POLICIES = ("stop", "retry", "replan")  # what the executor does after a fault


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
