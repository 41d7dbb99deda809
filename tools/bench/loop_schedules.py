"""The reconfiguration loop's schedules as fingerprints, to show that a change of its code keeps
its behaviour (``bille bench loop-schedules``): ``--save before.json``, change the code, then
``--compare before.json`` (exit 1 on any difference).

Every bundled instance that moves tiles, and a few random ones of fixed seeds, runs with every
motion layer (Temporal A* with ``H`` 5 and 10, M*, LaCAM*), with and without load transfer, and
no time limit: the loop's step, expansion and node budgets end every run, so the runs do not
depend on the machine's speed. A fingerprint is the run's status, its failure, the hash of its
action-id matrix and of its statistics (less the timings).
"""
from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path
from typing import Callable

import click

from bille.instances import load_instance
from bille.instances.bundled import bundled_names, bundled_path
from bille.instances.errors import BilleError
from bille.instances.files import write_atomic
from bille.instances.schedule import bind

from ..common import EXIT_NO, EXIT_OK, writable

MOTIONS = {"tastar-H5": ("temporal-astar", 5), "tastar-H10": ("temporal-astar", 10), "mstar": ("mstar", 5),
           "lacam": ("lacam", 5)}
RANDOM = {"random-15x15-s2": (15, 15, 60, 2, 10, 2), "random-10x8-r3-s1": (10, 8, 30, 3, 10, 1),
          "random-10x8-r4-s6": (10, 8, 30, 4, 10, 6)}  # width, height, tiles, robots, moved, seed
TIMINGS = ("plan_ms_mean", "plan_ms_max")


def instances() -> dict:
    from bille.instances.generators.random import random_reconfiguration

    out = {}
    for name in bundled_names():
        inst = load_instance(bundled_path(name))
        if inst.is_reconfiguration:
            out[name] = inst
    for name, (w, h, tiles, robots, moved, seed) in RANDOM.items():
        out[name] = random_reconfiguration(w, h, tiles, robots, moved, seed=seed)
    return out


def digest(value) -> str:
    return hashlib.sha256(value).hexdigest()[:16]


def fingerprint(inst, motion: str, horizon: int, transfer: bool) -> dict:
    import numpy as np

    from bille.heuristics import temporal_astar
    from bille.heuristics.loop import reconfigure

    result = reconfigure.plan(inst, temporal_astar.Options(horizon=horizon, load_transfer=transfer), motion=motion)
    stats = {k: v for k, v in result.stats.items() if k not in TIMINGS}
    ids = None if result.schedule is None else bind(inst, result.schedule)
    return {"status": result.status, "failure": None if result.failure is None else result.failure.text,
            "steps": None if ids is None else int(ids.shape[1]),
            "schedule": None if ids is None else digest(np.ascontiguousarray(ids, dtype=np.int64).tobytes()),
            "stats": digest(json.dumps(stats, sort_keys=True, default=str).encode())}


def run(only: str | None = None, echo: Callable[[str], None] = print) -> dict:
    """Every run's fingerprint (of the instances whose name contains ``only``), each told to
    ``echo`` as it ends."""
    out = {}
    for name, inst in instances().items():
        if only and only not in name:
            continue
        for label, (motion, horizon) in MOTIONS.items():
            for transfer in (False, True):
                key = f"{name} {label} {'lt' if transfer else 'no-lt'}"
                t0 = time.perf_counter()
                out[key] = fingerprint(inst, motion, horizon, transfer)
                f = out[key]
                echo(f"{key:40s} {f['status']:9s} {str(f['steps']):>5s} {f['schedule']} {f['stats']} "
                     f"{time.perf_counter() - t0:6.1f}s {f['failure'] or ''}")
    return out


def differences(got: dict, want: dict) -> list[str]:
    """The lines that say which runs differ from ``want``."""
    return [f"DIFFERS {k}: {want.get(k)} -> {got[k]}" for k in got if want.get(k) != got[k]]


@click.command("loop-schedules")
@click.option("--save", type=click.Path(dir_okay=False), help="Write the fingerprints to this JSON file.")
@click.option("--compare", type=click.Path(exists=True, dir_okay=False),
              help="Compare the fingerprints with this JSON file (exit 1 on any difference).")
@click.option("--only", help="Only the instances whose name contains this.")
def bench_loop_schedules(save: str | None, compare: str | None, only: str | None) -> int:
    """The reconfiguration loop's schedules as fingerprints: every instance that moves tiles and
    three random ones, every motion layer, with and without load transfer, no time limit (the
    loop's own bounds end every run), to show that a change keeps the loop's behaviour."""
    writable(save)
    want = None
    if compare:
        try:
            want = json.loads(Path(compare).read_text())
        except (OSError, ValueError) as exc:
            raise BilleError(f"{compare}: not a fingerprint file ({exc})") from None
        if not isinstance(want, dict):
            raise BilleError(f"{compare}: not a fingerprint file (expected a JSON object of runs)")
    got = run(only, echo=lambda line: click.echo(line, err=True))
    if save:
        write_atomic(Path(save), json.dumps(got, indent=1, sort_keys=True), BilleError)
    if want is None:
        return EXIT_OK
    lines = differences(got, want)
    for line in lines:
        click.echo(line)
    click.echo(f"{len(got) - len(lines)} of {len(got)} runs identical")
    return EXIT_NO if lines else EXIT_OK
