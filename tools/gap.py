"""The gap report: heuristics against the exact optimum on the same instances.

For every instance, every method runs under the same time limit; the optimum is the makespan an
exact method proved optimal, and each method's gap is how much longer its makespan is, in percent.
Methods that do not apply to an instance (joint A* on a reconfiguration instance; Temporal A* and
M* run the reconfiguration loop there) are listed as ``n/a`` with the reason.
"""
from __future__ import annotations

import csv
from pathlib import Path

from bille.instances import BilleError, Instance, OptionError
from bille.solvers import solve

from .tables import text_table

DEFAULT_METHODS = ("temporal-astar", "mstar", "astar", "cpsat", "sat")
EXACT = ("cpsat", "sat", "bfs")
FIELDS = ["instance", "method", "status", "makespan", "tiles_traveled", "time_s", "gap_percent", "note"]


def run(instances: list[Instance], methods, time_limit: float, threads: int = 1, progress=None,
        schedules: dict | None = None) -> list[dict]:
    """One row per instance and method; ``schedules``, if given, receives every schedule found
    under ``(instance name, method)``."""
    rows = []
    for inst in instances:
        mine = []
        for method in methods:
            if progress:
                progress(inst.name, method)
            options = {"time_limit": time_limit}
            if method == "cpsat":
                options["threads"] = threads
            try:
                result = solve(inst, method, **options)
            except OptionError as exc:
                mine.append(dict(instance=inst.name, method=method, status="n/a", makespan=None,
                                 tiles_traveled=None, time_s=None, gap_percent=None, note=str(exc)))
                continue
            m = result.metrics
            if schedules is not None and result.schedule is not None:
                schedules[inst.name, method] = result.schedule
            note = result.stats.get("failure") or result.stats.get("reason") or ""
            if not note and "objective" in result.stats:
                note = "walking only: optimizes the sum of costs"
            mine.append(dict(instance=inst.name, method=method, status=result.status,
                             makespan=m.makespan if m else None, tiles_traveled=m.tiles_traveled if m else None,
                             time_s=round(result.time_s, 3), gap_percent=None, note=note))
        proved = {r["makespan"] for r in mine if r["method"] in EXACT and r["status"] == "optimal"}
        if len(proved) > 1:  # two exact methods disagree: a bug, never hide it
            raise BilleError(f"{inst.name}: exact methods disagree on the optimal makespan: {sorted(proved)}")
        if proved:
            opt = proved.pop()
            for r in mine:
                if r["makespan"] is not None:
                    r["gap_percent"] = round(100.0 * (r["makespan"] - opt) / opt, 1) if opt else 0.0
        rows += mine
    return rows


def table(rows: list[dict]) -> list[str]:
    def show(v, fmt="{}"):
        return None if v is None else fmt.format(v)

    columns = ["instance", "method", "status", "makespan", "tiles", "time [s]", "gap", "note"]
    return text_table(columns, [[r["instance"], r["method"], r["status"], r["makespan"], r["tiles_traveled"],
                                 show(r["time_s"], "{:.3f}"), show(r["gap_percent"], "{:+.1f}%"), _short(r["note"])]
                                for r in rows], right={"makespan", "tiles", "time [s]", "gap"})


def write_csv(rows: list[dict], path: Path) -> None:
    from bille.instances.files import write_atomic
    import io

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=FIELDS)
    w.writeheader()
    w.writerows(rows)
    write_atomic(path, buf.getvalue(), BilleError)


def _short(note: str) -> str:
    return note if len(note) <= 60 else note[:57] + "..."
