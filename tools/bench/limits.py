"""Every method within its time limit (``bille bench limits``).

Generated instances of each family (classic and Bill-E collisions, mixed point movesets,
unreachable goals, one to a thousand robots) are written to a temporary folder; each method runs
on each as a user runs it, ``bille solve FILE -m METHOD --time-limit L --json``, in a process of
its own. A row records the exit code, whether one JSON object came out, the status, the time the
result reports and the process's wall time, start-up included. A run *overruns* when its
reported time passes the limit by more than a second or its process by more than three.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bille.instances import save_instance

from ..tables import text_table

REPORTED, PROCESS = 1.0, 3.0  # seconds past the limit allowed: the result's time, the process's


def families(folder: Path) -> dict[str, Path]:
    """The instances, written to ``folder``: name -> file."""
    from bille.instances import instance_from_text

    shipped = (Path(__file__).parents[2] / "instances" / "movesets" / "point.yaml").read_text()
    diagonal = folder / "diagonal.yaml"
    diagonal.write_text(shipped.replace("name: point", "name: diagonal").replace(
        "  west:        {at: [-1, 0]}\n", "  west:        {at: [-1, 0]}\n  north-east:  {at: [1, -1]}\n"))

    def text(grid, robots, goals=None, collisions="classic", goal=None, moveset="point"):
        lines = ["name: made", f"moveset: {moveset}", f"collisions: {collisions}", "grid: |"]
        lines += ["  " + row for row in grid]
        if goal:
            lines += ["goal: |"] + ["  " + row for row in goal]
        lines.append("robots: " + json.dumps(robots))
        if goals is not None:
            lines.append("robot_goals: " + json.dumps(goals))
        return instance_from_text("\n".join(lines) + "\n", "made")

    many = [{"at": [x, y]} for y in range(0, 64, 2) for x in range(0, 64, 2)][:1000]
    made = {
        "classic-unreachable": text(["TT.TT", "TT.TT"], [{"at": [0, 0]}, {"at": [4, 1]}], [[4, 0], [3, 1]]),
        "classic-mixed": text(["TTTTTT"] * 6, [{"at": [0, 3], "moveset": str(diagonal)}, {"at": [2, 4]},
                                               {"at": [4, 4]}], [[2, 4], [4, 2], [2, 2]]),
        "classic-1000": text(["T" * 64] * 64, many, [[r["at"][0] + 1, r["at"][1]] for r in many]),
        "bille-1000": text(["T" * 64] * 64, many, [[r["at"][0] + 1, r["at"][1]] for r in many], collisions="bille"),
        "bille-reconfiguration": text(["TTTTT", "TTTTT", "....."], [{"front": [1, 1], "back": [0, 1]}],
                                      collisions="bille", goal=["TTTTT", "TTTT.", "...T."], moveset="S7"),
    }
    out = {}
    for name, inst in made.items():
        out[name] = folder / f"{name}.yaml"
        save_instance(inst, out[name])
    return out


def one_run(path: Path, method: str, time_limit: float) -> dict:
    argv = [sys.executable, "-m", "bille", "solve", str(path), "-m", method, "--time-limit", str(time_limit), "--json"]
    began = time.perf_counter()
    done = subprocess.run(argv, capture_output=True, text=True, timeout=time_limit + 120)
    wall = time.perf_counter() - began
    try:
        told = json.loads(done.stdout)
    except json.JSONDecodeError:
        told = None
    reported = None if told is None else told.get("time_s")
    over = wall > time_limit + PROCESS or (reported is not None and reported > time_limit + REPORTED)
    return {"method": method, "exit": done.returncode, "json": told is not None,
            "status": None if told is None else told["status"], "reported": reported, "wall": round(wall, 2),
            "traceback": "Traceback" in done.stderr, "overrun": over,
            "error": done.stderr.strip().splitlines()[-1] if done.returncode == 2 and done.stderr.strip() else None}


def report(time_limit: float, methods: list[str], echo) -> int:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, path in families(Path(tmp)).items():
            for method in methods:
                rows.append({"instance": name, **one_run(path, method, time_limit)})
                r = rows[-1]
                echo(f"{name:<22} {method:<15} exit {r['exit']:>3}  {r['status'] or r['error'] or '-'}")
    echo("")
    body = [[r["instance"], r["method"], r["exit"], r["status"] or "refused" if r["exit"] == 2 else r["status"],
             r["reported"], r["wall"], "yes" if r["overrun"] else "", "yes" if r["traceback"] else ""] for r in rows]
    for line in text_table(["instance", "method", "exit", "status", "reported s", "wall s", "overrun", "traceback"],
                           body, right={"exit", "reported s", "wall s"}):
        echo(line)
    bad = [r for r in rows if r["overrun"] or r["traceback"] or (r["exit"] != 2 and not r["json"])]
    echo(f"{len(rows)} runs, limit {time_limit:g} s: {sum(r['overrun'] for r in rows)} overran "
         f"(reported > limit + {REPORTED:g} s or process > limit + {PROCESS:g} s), "
         f"{sum(r['traceback'] for r in rows)} tracebacks, {sum(r['exit'] != 2 and not r['json'] for r in rows)} "
         "without one JSON object")
    return len(bad)
