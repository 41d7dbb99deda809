"""``bille bench peers``: bille's path planners beside the published C++ ones, on the same
MovingAI rows, in one run, with the ratios.

Each peer is a program built from its own repository, never by bille, and named on the command
line: CBSH2-RTC and EECBS (Jiaoyang Li's; ``-m MAP -a SCEN -k N -t SECONDS -o CSV``; EECBS with
``--suboptimality=1``, which makes it optimal), libMultiRobotPlanning's ``cbs`` (``-i YAML -o
YAML``) and lacam3 (``--no-star``, one thread: its first schedule). A row is a map and the first
``N`` agents of its ``random-1`` scenario:

- **optimal** rows: bille's ``cbs`` (sum of costs, with proof) against the optimal peers. A
  peer's time is the runtime it writes plus its preprocessing (CBSH2-RTC and EECBS: the CSV's
  ``runtime`` and ``preprocessing runtime``; libMultiRobotPlanning: ``statistics.runtime``);
  bille's is the solve's ``time_s`` (what ``bille solve --json`` prints), after a warm-up solve,
  as the peers' times leave out their own start. Both proofs must agree on the sum of costs: a
  difference is printed as ``DIFFERENT COST``.
- **first-schedule** rows: bille's ``lacam -O improve=0`` against lacam3; every lacam3 schedule is
  replayed by bille's validator (:func:`.peers.checked`) before its sum of costs counts.

The summary gives, per peer, the geometric mean of the time ratios (bille / peer) over the rows
both solved, the sum-of-costs ratio, and the rows one solved and the other did not.
"""
from __future__ import annotations

import csv
import io
import tempfile
from pathlib import Path
from statistics import geometric_mean

import yaml

from bille.instances.generators.movingai import from_movingai
from bille.instances.interop import to_mrp
from bille.solvers import solve

from ..common import solved
from ..tables import text_table
from .maps import scenario_of
from .mapf import sum_of_costs
from .peers import program_output, run_lacam3

# the rows the peers were first compared on (the maps shipped with bille)
OPTIMAL_ROWS = (("random-32-32-10", (30, 40, 50, 60)), ("room-32-32-4", (20, 30, 40)),
                ("warehouse-10-20-10-2-1", (20, 40, 60)))
FIRST_ROWS = (("random-32-32-10", (400,)), ("room-32-32-4", (200,)), ("warehouse-10-20-10-2-1", (500,)),
              ("random-64-64-20", (500,)), ("den312d", (200,)))
OPTIMAL_PEERS = ("cbsh2-rtc", "eecbs", "mrp-cbs")
FIRST_PEERS = ("lacam3",)


def parse_rows(text: str) -> tuple[tuple[str, tuple[int, ...]], ...]:
    """``"room-32-32-4:20,30;random-32-32-10:50"`` -> rows; ValueError naming what is wrong."""
    rows = []
    for part in (p.strip() for p in text.split(";")):
        name, sep, counts = part.partition(":")
        if not sep or not name.strip():
            raise ValueError(f"expected MAP:N,N,... got {part!r}")
        try:
            numbers = tuple(int(c) for c in counts.split(","))
        except ValueError:
            raise ValueError(f"agent counts of {name.strip()!r} must be whole numbers, got {counts!r}") from None
        if not numbers or min(numbers) < 1:
            raise ValueError(f"agent counts of {name.strip()!r} must be at least 1")
        rows.append((name.strip(), numbers))
    return tuple(rows)


def run_li(binary: Path, map_file: Path, scen: Path, agents: int, seconds: float, extra=()) -> dict:
    """CBSH2-RTC or EECBS on the first ``agents`` agents: ``status`` (optimal, timeout,
    infeasible, failed), its sum of costs and its time (runtime plus preprocessing)."""
    text = program_output(lambda out: [str(binary), "-m", str(map_file), "-a", str(scen), "-k", str(agents), "-t",
                                       str(seconds), "-o", str(out), *extra], "stats.csv", seconds + 60)
    if isinstance(text, dict):
        return text
    rows = list(csv.DictReader(io.StringIO(text)))
    if not rows or "solution cost" not in rows[-1]:
        return {"status": "failed"}
    row = rows[-1]
    cost = int(float(row["solution cost"]))
    took = float(row["runtime"]) + float(row.get("preprocessing runtime") or 0)
    status = "optimal" if cost >= 0 else "infeasible" if cost == -2 else "timeout"
    return {"status": status, "time_s": took, **({"soc": cost} if cost >= 0 else {})}


def run_mrp(binary: Path, instance, seconds: float) -> dict:
    """libMultiRobotPlanning's ``cbs`` on the instance written as its YAML."""
    from .optimal import run_peer

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "in.yaml"
        path.write_text(yaml.safe_dump(to_mrp(instance)))
        got = run_peer(binary, path, seconds)
    if got["soc"] is None:
        return {"status": "timeout", "time_s": got["time_s"]}
    return {"status": "optimal", "time_s": got["time_s"], "soc": int(got["soc"])}


def bille_cbs(instance, seconds: float) -> dict:
    result = solved(solve(instance, "cbs", time_limit=seconds))  # solve() validates the schedule it returns
    row = {"status": result.status, "time_s": result.time_s}
    if result.status == "optimal":
        row["soc"] = result.counters.sum_of_costs
    return row


def bille_lacam(instance, seconds: float) -> dict:
    result = solved(solve(instance, "lacam", time_limit=seconds, improve=0.0))
    row = {"status": result.status, "time_s": result.time_s, "scatter_s": result.counters.scatter_s}
    if result.metrics is not None:  # a valid schedule (solve() validates it)
        row["soc"] = sum_of_costs(instance, result.schedule)
    return row


def side_by_side(folder: Path, rows, peers: dict[str, Path], seconds: float, kind: str, told=None):
    """Yield one row per map and agent count: bille's run and each peer's, one after the other
    (so a loaded machine weighs on both alike). ``kind``: ``optimal`` or ``first``."""

    mine = bille_cbs if kind == "optimal" else bille_lacam
    for name, counts in rows:
        map_file, scen = folder / f"{name}.map", scenario_of(folder, name)
        # the peers' times leave out their start: bille's its imports and compiled code, which a
        # map may load first (the compiled distances from 5,000 cells), so a warm-up on each map
        mine(from_movingai(map_file, scen, agents=2), seconds)
        if kind == "first":  # the SUO step's compiled table, loaded only on larger problems
            from bille.heuristics.lacam.scatter_compiled import warm_up

            warm_up()
        else:  # the compiled low level, which a run loads once its Python searches have taken long
            from bille.heuristics.cbs.mdd_compiled import warm_up

            warm_up()
        for k in counts:
            inst = from_movingai(map_file, scen, agents=k)
            row = {"map": name, "agents": k, "bille": mine(inst, seconds), "peers": {}}
            for peer, binary in peers.items():
                if peer == "lacam3":
                    got = run_lacam3(binary, map_file, scen, k, inst, seconds=max(1, round(seconds)), anytime=False)
                elif peer == "mrp-cbs":
                    got = run_mrp(binary, inst, seconds)
                else:
                    got = run_li(binary, map_file, scen, k, seconds, ("--suboptimality=1",) if peer == "eecbs" else ())
                row["peers"][peer] = got
            if told is not None:
                told(row)
            yield row


def table(rows: list[dict], peers: list[str], kind: str) -> list[str]:
    """The side-by-side table and, per peer, the geometric means of the ratios and what one
    solved that the other did not."""
    body, ratios = [], {p: ([], []) for p in peers}
    only = {p: [0, 0] for p in peers}  # bille only, peer only
    differ = {p: 0 for p in peers}
    for r in rows:
        b = r["bille"]
        line = [r["map"], str(r["agents"]), f"{b['time_s']:.3f}" if "soc" in b else b["status"],
                str(b.get("soc", "-"))]
        if kind == "first":
            share = b.get("scatter_s")
            shown = share is not None and "soc" in b and b["time_s"] > 0
            line.append(f"{100 * share / b['time_s']:.0f} %" if shown else "-")
        for p in peers:
            got = r["peers"].get(p, {})
            mine, theirs = "soc" in b, "soc" in got
            note = ""
            if mine and theirs:
                t, c = b["time_s"] / max(got["time_s"], 1e-4), b["soc"] / max(got["soc"], 1)
                ratios[p][0].append(t)
                ratios[p][1].append(c)
                if kind == "optimal" and b["soc"] != got["soc"]:
                    differ[p] += 1
                    note = " DIFFERENT COST"
                line += [f"{got['time_s']:.3f}", str(got["soc"]), f"{t:.1f}x{note}"]
            else:
                only[p][0] += mine and not theirs
                only[p][1] += theirs and not mine
                line += [got.get("status", "-") if not theirs else f"{got['time_s']:.3f}",
                         str(got["soc"]) if theirs else "-", "-"]
        body.append(line)
    columns = ["map", "agents", "bille [s]", "bille SOC"] + (["scatter share"] if kind == "first" else [])
    for p in peers:
        columns += [f"{p} [s]", f"{p} SOC", "ratio"]
    lines = text_table(columns, body, right=set(columns[1:]))
    for p in peers:
        t, c = ratios[p]
        head = (f"against {p}: geometric mean time ratio {geometric_mean(t):.2f}x, sum of costs ratio "
                f"{geometric_mean(c):.3f} over "
                f"{len(t)} rows both solved") if t else f"against {p}: no row both solved"
        lines.append(f"{head}; bille alone solved {only[p][0]}, {p} alone {only[p][1]}"
                     + (f"; {differ[p]} DIFFERENT COSTS" if differ[p] else ""))
    return lines


__all__ = ["FIRST_PEERS", "FIRST_ROWS", "OPTIMAL_PEERS", "OPTIMAL_ROWS", "parse_rows", "side_by_side", "table"]
