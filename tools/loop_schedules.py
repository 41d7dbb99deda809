"""The reconfiguration loop's schedules as fingerprints, to show that a change of its code keeps
its behaviour: ``python -m bille.tools.loop_schedules --save before.json``, change the code, then
``python -m bille.tools.loop_schedules --compare before.json`` (exit 1 on any difference).

Every bundled instance that moves tiles, and a few random ones of fixed seeds, runs with every
motion layer (Temporal A* with ``H`` 5 and 10, M*, LaCAM*), with and without load transfer, and
no time limit: the loop's step, expansion and node budgets end every run, so the runs do not
depend on the machine's speed. A fingerprint is the run's status, its failure, the hash of its
action-id matrix and of its statistics (less the timings).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time

import numpy as np

from bille.heuristics.loop import reconfigure
from bille.instances import load_instance
from bille.instances.bundled import bundled_names, bundled_path
from bille.instances.generators.random import random_reconfiguration
from bille.instances.schedule import bind

MOTIONS = {"tastar-H5": ("temporal-astar", 5), "tastar-H10": ("temporal-astar", 10), "mstar": ("mstar", 5),
           "lacam": ("lacam", 5)}
RANDOM = {"random-15x15-s2": (15, 15, 60, 2, 10, 2), "random-10x8-r3-s1": (10, 8, 30, 3, 10, 1),
          "random-10x8-r4-s6": (10, 8, 30, 4, 10, 6)}  # width, height, tiles, robots, moved, seed
TIMINGS = ("plan_ms_mean", "plan_ms_max")


def instances() -> dict:
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
    result = reconfigure.plan(inst, motion=motion, horizon=horizon, load_transfer=transfer)
    stats = {k: v for k, v in result.stats.items() if k not in TIMINGS}
    ids = None if result.schedule is None else bind(inst, result.schedule)
    return {"status": result.status, "failure": result.stats.get("failure"),
            "steps": None if ids is None else int(ids.shape[1]),
            "schedule": None if ids is None else digest(np.ascontiguousarray(ids, dtype=np.int64).tobytes()),
            "stats": digest(json.dumps(stats, sort_keys=True, default=str).encode())}


def run(only: str | None = None) -> dict:
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
                print(f"{key:40s} {f['status']:9s} {str(f['steps']):>5s} {f['schedule']} {f['stats']} "
                      f"{time.perf_counter() - t0:6.1f}s {f['failure'] or ''}", flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--save", help="write the fingerprints to this JSON file")
    parser.add_argument("--compare", help="compare the fingerprints with this JSON file")
    parser.add_argument("--only", help="only the instances whose name contains this")
    args = parser.parse_args(argv)
    got = run(args.only)
    if args.save:
        with open(args.save, "w") as f:
            json.dump(got, f, indent=1, sort_keys=True)
    if args.compare:
        with open(args.compare) as f:
            want = json.load(f)
        differ = [k for k in got if want.get(k) != got[k]]
        for k in differ:
            print(f"DIFFERS {k}: {want.get(k)} -> {got[k]}")
        print(f"{len(got) - len(differ)} of {len(got)} runs identical")
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
