"""Published MAPF solvers beside bille's LaCAM* (``bille bench mapf --peers DIR``): lacam3
(Okumura, AAMAS 2024; C++, its command-line program) and pypibt (Okumura's Python PIBT).

They are never part of bille: each is built from its own repository, as its README says, into
one folder: ``DIR/lacam3/build/main`` and ``DIR/pypibt/pypibt/``. A peer that is not there is
left out. Every schedule a peer returns is checked by bille's validator under classic
collisions (vertex and swap conflicts, moves between neighbouring free cells) before its sum of
costs counts; an invalid one counts as a failure.
"""
from __future__ import annotations

import json
from statistics import geometric_mean
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bille.instances import Instance
from bille.instances.schedule import Schedule
from bille.solvers import validate

STEP = {(0, 0): "wait", (0, -1): "north", (1, 0): "east", (0, 1): "south", (-1, 0): "west"}
PYPIBT_STEPS = 1000  # pypibt's own default horizon

_PYPIBT = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
from pypibt import PIBT, get_grid, get_scenario
grid = get_grid(sys.argv[2])
starts, goals = get_scenario(sys.argv[3], int(sys.argv[4]))
start = time.perf_counter()
plan = PIBT(grid, starts, goals, seed=0).run(max_timestep=int(sys.argv[5]))
took = time.perf_counter() - start
solved = [tuple(map(int, v)) for v in plan[-1]] == [tuple(map(int, v)) for v in goals]
print(json.dumps({"time_s": took, "solved": solved, "plan": [[[int(x), int(y)] for y, x in c] for c in plan]}))
"""


def available(folder: Path) -> dict[str, Path]:
    """The peers built in ``folder``: name -> what runs it."""
    found = {}
    for name in PEERS:
        try:
            found[name] = peer_at(name, folder / PEERS[name][0])
        except ValueError:
            pass
    return found


# name -> (where it lies in a --peers folder, what --against names, a file that must be in it)
PEERS = {"lacam3": ("lacam3/build/main", "program", None),
         "pypibt": ("pypibt", "repository folder", "pypibt/__init__.py")}


def peer_at(name: str, path: Path) -> Path:
    """``path`` as what runs peer ``name`` (:data:`PEERS`), or ValueError saying what it is not."""
    _, what, inside = PEERS[name]
    if not ((path / inside).is_file() if inside else path.is_file()):
        raise ValueError(f"{path}: not {name}'s {what}" + (f" (no {inside} in it)" if inside else ""))
    return path


def program_output(command, name: str, seconds: float) -> str | dict:
    """Run a peer's program, ``command(out)`` its arguments given the path of the file it writes
    its answer to (``name``, in a folder of its own), for at most ``seconds``: the file's text,
    or the row of a run that gave none (``{"status": "timeout"}`` or ``{"status": "failed"}``)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / name
        try:
            subprocess.run(command(out), capture_output=True, timeout=seconds, check=False)
        except subprocess.TimeoutExpired:
            return {"status": "timeout"}
        return out.read_text() if out.is_file() else {"status": "failed"}


def run_lacam3(binary: Path, map_file: Path, scen: Path, agents: int, instance: Instance, *,
               seconds: int, anytime: bool) -> dict:
    """lacam3 on the first ``agents`` rows of ``scen``: its first schedule (``--no-star``, one
    thread, as bille's) or its best after ``seconds`` (``anytime``); ``time_s`` as it reports it
    (planning, its distance tables included)."""
    text = program_output(lambda out: [str(binary), "-m", str(map_file), "-i", str(scen), "-N", str(agents), "-t",
                                       str(seconds), "-o", str(out)]
                          + ([] if anytime else ["--no-star", "--no-multi-thread"]), "result.txt", seconds + 30)
    if isinstance(text, dict):
        return text
    fields = dict(line.split("=", 1) for line in text.splitlines() if "=" in line and ":" not in line.split("=")[0])
    if fields.get("solved") != "1":
        return {"status": "unsolved", "time_s": int(fields.get("comp_time", 0)) / 1000}
    plan = [[(int(x), int(y)) for x, y in re.findall(r"\((\d+),(\d+)\)", line.split(":", 1)[1])]
            for line in text.split("solution=", 1)[1].strip().splitlines() if ":" in line]
    row = {"time_s": int(fields["comp_time"]) / 1000, "first_s": int(fields["comp_time_initial_solution"]) / 1000}
    return {**row, **checked(instance, plan)}


def run_pypibt(folder: Path, map_file: Path, scen: Path, agents: int, instance: Instance) -> dict:
    """pypibt's PIBT (seed 0, at most :data:`PYPIBT_STEPS` steps); ``time_s`` its ``run()``."""
    try:
        done = subprocess.run([sys.executable, "-c", _PYPIBT, str(folder), str(map_file), str(scen), str(agents),
                               str(PYPIBT_STEPS)], capture_output=True, text=True, timeout=600, check=False)
    except subprocess.TimeoutExpired:
        return {"status": "timeout"}
    if done.returncode != 0:
        return {"status": "failed"}
    got = json.loads(done.stdout)
    if not got["solved"]:
        return {"status": "unsolved", "time_s": got["time_s"]}
    return {"time_s": got["time_s"], **checked(instance, [[tuple(v) for v in c] for c in got["plan"]])}


def checked(instance: Instance, plan: list[list[tuple[int, int]]]) -> dict:
    """A peer's configurations (cells per step) as a bille schedule, validated; its sum of costs
    (each agent's last arrival at its goal)."""
    starts = [tuple(r.front) for r in instance.robots]
    if [tuple(v) for v in plan[0]] != starts:
        return {"status": "other agents"}  # the peer read the scenario differently
    actions = []
    for i in range(instance.num_robots):
        moves = []
        for a, b in zip(plan, plan[1:]):
            step = (b[i][0] - a[i][0], b[i][1] - a[i][1])
            if step not in STEP:
                return {"status": "invalid"}
            moves.append(STEP[step])
        actions.append(tuple(moves))
    report = validate(instance, Schedule(tuple(actions)))
    if not report.valid:
        return {"status": "invalid"}
    goals = [tuple(g) for g in instance.robot_goals]
    soc = 0
    for i, goal in enumerate(goals):
        t = len(plan) - 1
        while t > 0 and tuple(plan[t - 1][i]) == tuple(goal):
            t -= 1
        soc += t
    return {"status": "feasible", "soc": soc}


def timed(run) -> dict:
    start = time.perf_counter()
    row = run()
    row.setdefault("wall_s", time.perf_counter() - start)
    return row


LARGEST_S = 30.0  # "solved" for the largest agent count: a first schedule within this time


def peers_table(rows: list[dict], names: list[str]) -> list[str]:
    """Per map and agent count: bille's time, sum of costs and the share of its first schedule's
    time spent on the SUO paths (:mod:`bille.heuristics.lacam.scatter`), and per peer the ratios bille /
    peer of time and of sum of costs (below 1: bille faster, or cheaper); then per map the largest
    agent count each solved within :data:`LARGEST_S`, and the geometric means of the ratios."""
    from ..tables import text_table

    table, ratios = [], {n: ([], []) for n in names}
    largest: dict[str, dict[str, int]] = {}
    for r in rows:
        if r["status"] == "skipped":
            continue
        mine = "soc" in r
        spread = r.get("scatter_s")
        line = [r["map"], str(r["agents"]), f"{r['time_s']:.2f}" if mine else r["status"],
                str(r["soc"]) if mine else "-",
                f"{100 * spread / r['first_s']:.0f} %" if mine and spread is not None and r.get("first_s") else "-"]
        best = largest.setdefault(r["map"], {})
        if mine and r["time_s"] <= LARGEST_S:
            best["bille"] = max(best.get("bille", 0), r["agents"])
        for n in names:
            peer = r["peers"].get(n, {})
            ok = peer.get("status") == "feasible"
            if ok and peer["time_s"] <= LARGEST_S:
                best[n] = max(best.get(n, 0), r["agents"])
            if ok and mine:
                t, c = r["time_s"] / max(peer["time_s"], 1e-3), r["soc"] / peer["soc"]
                ratios[n][0].append(t)
                ratios[n][1].append(c)
                line += [f"{peer['time_s']:.2f}", str(peer["soc"]), f"{t:.2f}x", f"{c:.3f}"]
            else:
                line += [f"{peer['time_s']:.2f}" if ok else peer.get("status", "-"),
                         str(peer["soc"]) if ok else "-", "-", "-"]
        table.append(line)
    columns = ["map", "agents", "bille [s]", "bille SOC", "scatter share"]
    for n in names:
        columns += [f"{n} [s]", f"{n} SOC", "time ratio", "SOC ratio"]
    lines = text_table(columns, table, right=set(columns[1:]))
    lines.append("largest agent count solved within 30 s: " + "; ".join(
        f"{m}: bille {b.get('bille', 0)}, " + ", ".join(f"{n} {b.get(n, 0)}" for n in names)
        for m, b in largest.items()))
    for n in names:
        t, c = ratios[n]
        if t:
            lines.append(f"against {n}: geometric mean time ratio {geometric_mean(t):.2f}x, "
                         f"sum of costs ratio {geometric_mean(c):.3f} ({len(t)} runs both solved)")
    return lines
