"""Optimal classic MAPF: conflict-based search against basic CBS and joint A* (``bille bench mapf
--optimal``), and against libMultiRobotPlanning's CBS (``bille bench cbs``).

``--optimal``: each shipped MovingAI map with its ``random-1`` scenario, the first ``k`` agents,
solved to the optimal sum of costs by ``cbs`` (every improvement on), by ``cbs`` with every
improvement off (basic CBS, the baseline of the same run) and by joint A* (``astar``); the table
gives each one's status, sum of costs and time, and the ratio of basic CBS's time to ``cbs``'s.

``bille bench cbs``: libMultiRobotPlanning's instances (YAML, as its ``cbs`` example reads them),
each solved by its ``cbs`` program (a binary built from its own repository; never part of bille)
and by bille's ``cbs``, one right after the other. Every sum of costs is compared, and the
geometric mean of the time ratios is taken over the instances both prove. Its time is the one the
program prints (the search, without reading files); bille's is ``cbs``'s own, without loading.
"""
from __future__ import annotations

import statistics
import os
import subprocess
import tempfile
import time
from pathlib import Path

import yaml

from bille.instances import InstanceError
from bille.instances.generators.movingai import from_movingai
from bille.instances.interop import from_mrp
from bille.solvers import solve, validate

from ..common import solved
from ..tables import text_table
from .mapf import SCENARIO

BASIC = {"heuristic": "none", "prioritize": False, "bypass": False, "target": False, "rectangle": False, "corridor": False}
RUNS = (("cbs", "cbs", {}), ("basic CBS", "cbs", BASIC), ("joint A*", "astar", {}))


def optimal_rows(folder: Path, maps, agents, time_limit: float):
    """One row per map and agent count: each of :data:`RUNS` on the same agents."""
    for name in maps:
        for k in agents:
            try:
                inst = from_movingai(folder / f"{name}.map", folder / f"{name}{SCENARIO}", agents=k)
            except InstanceError as exc:
                yield dict(map=name, agents=k, runs={}, reason=str(exc))
                continue
            row = dict(map=name, agents=k, runs={})
            for label, method, options in RUNS:
                result = solved(solve(inst, method, time_limit=time_limit, **options))
                row["runs"][label] = dict(status=result.status, time_s=result.time_s,
                                          soc=result.counters.sum_of_costs if result.status == "optimal" else None)
            yield row


def optimal_table(rows: list[dict]) -> list[str]:
    lines = []
    for r in rows:
        runs = r["runs"]
        cells = [r["map"], str(r["agents"])]
        for label, _, _ in RUNS:
            run = runs.get(label)
            cells += [None, None] if run is None else [run["soc"] if run["soc"] is not None else run["status"],
                                                       f"{run['time_s']:.2f}"]
        mine, base = runs.get("cbs"), runs.get("basic CBS")
        cells.append(f"{base['time_s'] / mine['time_s']:.1f}" if mine and base and mine["soc"] is not None
                     and base["soc"] is not None else None)
        lines.append(cells)
    columns = ["map", "agents"] + [f"{label} {what}" for label, _, _ in RUNS for what in ("SOC", "[s]")] + \
        ["basic/cbs time"]
    return text_table(columns, lines, right=set(columns[1:]))


def write_optimal_csv(rows: list[dict], path: Path) -> None:
    """The rows of :func:`optimal_rows` as CSV, one line per map, agent count and method."""
    import csv
    import io

    from bille.instances import BilleError
    from bille.instances.files import write_atomic

    buffer = io.StringIO()
    out = csv.writer(buffer)
    out.writerow(["map", "agents", "method", "status", "sum_of_costs", "time_s"])
    for r in rows:
        for label, run in r["runs"].items():
            out.writerow([r["map"], r["agents"], label, run["status"], run["soc"], round(run["time_s"], 4)])
    write_atomic(path, buffer.getvalue(), BilleError)


def peer_rows(binary: Path, files: list[Path], time_limit: float):
    """One row per libMultiRobotPlanning instance: its CBS and bille's, one after the other."""
    for path in files:
        row = dict(instance=path.stem)
        try:
            inst = from_mrp(yaml.safe_load(path.read_text()), path.stem, str(path))
        except (InstanceError, yaml.YAMLError) as exc:
            row["reason"] = str(exc).splitlines()[0].split(": ", 1)[-1]
            yield row
            continue
        result = solved(solve(inst, "cbs", time_limit=time_limit))
        row["bille"] = dict(status=result.status, time_s=result.time_s, nodes=result.counters.expanded,
                            soc=result.counters.sum_of_costs if result.status == "optimal" else None,
                            valid=result.schedule is not None and validate(inst, result.schedule).valid)
        row["peer"] = run_peer(binary, path, time_limit)
        yield row


def run_peer(binary: Path, path: Path, time_limit: float) -> dict:
    """libMultiRobotPlanning's ``cbs -i FILE -o OUT`` under ``timeout``: its sum of costs and the
    runtime it prints, or None for both when it finds nothing in time."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.yaml"
        began = time.perf_counter()
        subprocess.run(["timeout", str(time_limit), str(binary), "-i", str(path), "-o", str(out)],
                       capture_output=True, check=False)
        wall = time.perf_counter() - began
        if not out.is_file():
            return dict(soc=None, time_s=wall, nodes=None)
        stats = yaml.safe_load(out.read_text()).get("statistics", {})
        return dict(soc=stats.get("cost"), time_s=float(stats.get("runtime", wall)), nodes=stats.get("highLevelExpanded"))


def peer_table(rows: list[dict]) -> list[str]:
    lines, ratios, counts = [], [], dict(both=0, bille_only=0, peer_only=0, neither=0, differ=0)
    for r in rows:
        if "reason" in r:
            lines.append([r["instance"], None, None, None, None, None, None, r["reason"][:60]])
            continue
        mine, theirs = r["bille"], r["peer"]
        note = ""
        if mine["soc"] is not None and theirs["soc"] is not None:
            counts["both"] += 1
            ratio = mine["time_s"] / max(theirs["time_s"], 1e-6)
            ratios.append(ratio)
            if mine["soc"] != theirs["soc"]:
                counts["differ"] += 1
                note = "DIFFERENT COST"
        else:
            ratio = None
            key = "bille_only" if mine["soc"] is not None else "peer_only" if theirs["soc"] is not None else "neither"
            counts[key] += 1
        if mine["soc"] is not None and not mine["valid"]:
            note = "INVALID"
        lines.append([r["instance"], mine["soc"] if mine["soc"] is not None else mine["status"],
                      f"{mine['time_s']:.3f}", mine["nodes"], theirs["soc"], f"{theirs['time_s']:.3f}",
                      None if ratio is None else f"{ratio:.2f}", note])
    columns = ["instance", "bille SOC", "bille [s]", "bille nodes", "peer SOC", "peer [s]", "time ratio", "note"]
    out = text_table(columns, lines, right=set(columns[1:7]))
    mean = statistics.geometric_mean(ratios) if ratios else None
    out.append(f"both proved {counts['both']}, only bille {counts['bille_only']}, only the peer {counts['peer_only']}, "
               f"neither {counts['neither']}; different costs {counts['differ']}")
    out.append("geometric mean of bille's time over the peer's, where both proved: "
               + ("-" if mean is None else f"{mean:.2f}"))
    return out


def peer_files(paths: list[str]) -> list[Path]:
    """The YAML files named, those of the folders named (sorted), in order."""
    found = []
    for p in map(Path, paths):
        found += sorted(p.glob("*.yaml")) if p.is_dir() else [p]
    return found


def executable(path: str) -> bool:
    return os.path.isfile(path) and os.access(path, os.X_OK)
