"""Benchmark of the execution layer: steps per second and message round trips on loopback.

``bille bench execute`` runs a schedule on 1 (the baseline), 10 and 50 simulated robot processes
(by default) over the embedded broker or the broker given, and prints per fleet size: steps per
second, the round trip from a step's release to each robot's report (mean, p95, max), and the
ratio of each to the one-robot baseline measured in the same run. The robots pace back and forth
on rows of a tile rectangle (one row each, no robot in another's way), so every step moves every
robot; starting the robot processes is not counted. A fleet that does not come up or finish in
time (a loaded machine) is a row that says so, not an error: the other sizes are still measured.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from bille.instances import Grid, Instance, Robot, load_moveset, save_instance
from bille.solvers import Schedule, save_schedule

from ..execute import session
from ..execute.outcome import Outcome
from ..execute.protocol import ExecutionError

STEP_TIMEOUT = 10.0  # seconds a step may take by default


def connect_timeout(robots: int) -> float:
    """The default wait for a fleet to come up: 30 s, and 1.5 s per robot beyond 20."""
    return max(30.0, 1.5 * robots)


def pacing(robots: int, steps: int) -> tuple[Instance, Schedule]:
    """``robots`` S5 robots on rows of a 4-wide tile rectangle, stepping forward and back."""
    w, h = 4, robots
    grid = Grid.from_masks(w, h, np.zeros(w * h, bool), np.ones(w * h, bool))
    inst = Instance(f"pacing-{robots}", load_moveset("S5"), grid, tuple(Robot((1, y), (0, y)) for y in range(h)))
    row = tuple(("fwd", "back")[t % 2] for t in range(steps))
    return inst, Schedule(tuple(row for _ in range(robots)))


def measure(robots: int, steps: int, broker: str | None, folder: Path, step_timeout: float = STEP_TIMEOUT,
            connect: float | None = None) -> Outcome:
    inst, sched = pacing(robots, steps)
    ip, sp = folder / f"{inst.name}.yaml", folder / f"{inst.name}.schedule.yaml"
    save_instance(inst, ip)
    save_schedule(sched, sp)
    journal = folder / f"{inst.name}-{time.time_ns()}.journal.jsonl"
    settings = dict(step_timeout=step_timeout, connect_timeout=connect or connect_timeout(robots))
    return session.start(inst, str(ip), sched, str(sp), broker=broker, robots="sim", secrets_path=None,
                         journal_path=str(journal), settings=settings)


def report(sizes: list[int], steps: int, broker: str | None, step_timeout: float = STEP_TIMEOUT,
           connect: float | None = None, failed: list | None = None):
    """Yield the table's lines as each fleet size is measured (baseline first); the sizes whose
    run did not complete go to ``failed``."""
    failed = [] if failed is None else failed
    yield f"execution over {'the embedded broker' if not broker else broker}, {steps} steps per run"
    yield f"{'robots':>6} {'steps/s':>8} {'ratio':>6} {'rt mean ms':>10} {'rt p95 ms':>9} {'rt max ms':>9} {'ratio':>6}"
    base = None
    with tempfile.TemporaryDirectory() as tmp:
        for n in [1] + [s for s in sizes if s != 1]:
            try:
                out = measure(n, steps, broker, Path(tmp), step_timeout, connect)
            except ExecutionError as exc:  # the fleet did not come up in time: a result of this machine
                failed.append(n)
                yield f"{n:>6} not measured: {exc}"
                continue
            j = out.to_json()
            if out.status != "completed" or not out.worlds_match:
                failed.append(n)
                yield f"{n:>6} run {out.status}: {'; '.join(j['faults']) or 'worlds differ'}"
                continue
            sps, rt = j["steps_per_second"], j["round_trip_ms"]
            if base is None:
                base = (sps, rt["mean"])
            yield (f"{n:>6} {sps:>8.1f} {sps / base[0]:>6.2f} {rt['mean']:>10.1f} {rt['p95']:>9.1f} {rt['max']:>9.1f} "
                   f"{rt['mean'] / base[1]:>6.2f}")
