"""A sweep's results folder: one JSON line per finished run (``runs.jsonl``, appended as runs
finish, so a sweep stopped or crashed midway loses no finished run), the schedules beside it
(``schedules/HASH-METHOD-N.yaml``), and the table as Parquet and CSV (``results.parquet``,
``results.csv``, rows sorted by run key) written when the sweep ends.

``lower_bound`` is the bound a run proved itself; ``best_lower_bound`` the best bound proved on
the same instance by any run of the sweep (a proved optimum is a bound), and ``certified_gap`` =
(makespan - best_lower_bound) / best_lower_bound: every run is measured against the same bound.
The runs' own file (``runs.jsonl``) holds what each run found; the two cross-run columns are
computed when the table is written or read.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

from bille.instances import BilleError
from bille.instances.claim import base_status

COLUMNS = ["key", "instance", "instance_hash", "width", "height", "robots", "tiles", "moved", "method", "options",
           "label", "status", "makespan", "tiles_traveled", "lower_bound", "best_lower_bound", "certified_gap",
           "time_s", "expansions", "stats", "error", "schedule", "bille_version", "python_version"]
TIMING = ("time_s", "stats")  # the columns that differ from one run of a sweep to the next
TRUSTED = ("optimal", "feasible", "infeasible", "timeout", "unsolved")  # statuses whose bound is a proof


class Store:
    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        try:
            (self.folder / "schedules").mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise BilleError(f"{self.folder}: cannot create the results folder ({exc.strerror})") from None
        self.path = self.folder / "runs.jsonl"
        self.rows = read_rows(self.path)
        self.keys = {r["key"] for r in self.rows}

    def add(self, row: dict) -> None:
        text = row.get("schedule")
        if text:
            name = f"{hashlib.sha256(row['key'].encode()).hexdigest()[:16]}.yaml"
            (self.folder / "schedules" / name).write_text(text, encoding="utf-8")
            row = dict(row, schedule=f"schedules/{name}")
        line = json.dumps({c: row.get(c) for c in COLUMNS if c not in ("best_lower_bound", "certified_gap")}) + "\n"
        with open(self.path, "a", encoding="utf-8") as f:  # one write per line: a killed sweep keeps it
            f.write(line)
        self.rows.append(json.loads(line))
        self.keys.add(row["key"])

    def finish(self) -> tuple[Path, Path]:
        return write_tables(self.rows, self.folder)


def read_rows(path: Path) -> list[dict]:
    """The rows of a ``runs.jsonl``; a last line cut short by a crash is dropped (and so is run
    again), a repeated key keeps its first row."""
    if not path.exists():
        return []
    rows, seen = [], set()
    lines = path.read_text(encoding="utf-8").splitlines()
    for k, line in enumerate(lines):
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            if k == len(lines) - 1:
                break  # cut by a crash while being written
            raise BilleError(f"{path}:{k + 1}: not a JSON row") from None
        if row.get("key") not in seen:
            seen.add(row["key"])
            rows.append(row)
    if lines and not path.read_text(encoding="utf-8").endswith("\n"):
        path.write_text("".join(json.dumps(r) + "\n" for r in rows), encoding="utf-8")  # drop the cut line
    return rows


def write_tables(rows: list[dict], folder: Path) -> tuple[Path, Path]:
    import pyarrow as pa
    import pyarrow.csv as pacsv
    import pyarrow.parquet as pq

    ordered = sorted(certify(rows), key=lambda r: r["key"])
    table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMNS} for r in ordered], schema=_schema())
    parquet, csv = folder / "results.parquet", folder / "results.csv"
    pq.write_table(table, parquet)
    pacsv.write_csv(table, csv)
    return parquet, csv


def best_bounds(rows: list[dict]) -> dict[str, int]:
    """Per instance (by hash): the best lower bound on the makespan that a run of the sweep
    proved (its own ``lower_bound``; runs that failed or contradicted themselves prove nothing)."""
    best: dict[str, int] = {}
    for r in rows:
        if base_status(r.get("status") or "") in TRUSTED and r.get("lower_bound") is not None:
            best[r["instance_hash"]] = max(best.get(r["instance_hash"], 0), r["lower_bound"])
    return best


def certify(rows: list[dict]) -> list[dict]:
    """The rows with ``best_lower_bound`` and ``certified_gap`` (module docstring); no gap where
    the best bound is above the run's makespan (a contradiction between two runs, which
    :func:`contradictions` names)."""
    best = best_bounds(rows)
    out = []
    for r in rows:
        lower = best.get(r["instance_hash"])
        gap = None
        if r.get("makespan") is not None and lower and lower <= r["makespan"]:
            gap = round((r["makespan"] - lower) / lower, 6)
        out.append(dict(r, best_lower_bound=lower, certified_gap=gap))
    return out


def contradictions(rows: list[dict]) -> list[str]:
    """A bound proved by one run above a valid schedule of another, on the same instance: a bug
    in one of them, never hidden."""
    best = best_bounds(rows)
    said = []
    for r in rows:
        lower = best.get(r["instance_hash"])
        if r.get("makespan") is not None and lower is not None and lower > r["makespan"]:
            by = next(o["label"] for o in rows if o["instance_hash"] == r["instance_hash"]
                      and base_status(o.get("status") or "") in TRUSTED and o.get("lower_bound") == lower)
            said.append(f"{r['instance']}: {by} proved a lower bound of {lower}, above the valid schedule of "
                        f"{r['makespan']} steps of {r['label']}")
    return said


def _schema():
    import pyarrow as pa

    ints = {"width", "height", "robots", "tiles", "moved", "makespan", "tiles_traveled", "lower_bound",
            "best_lower_bound", "expansions"}
    floats = {"certified_gap", "time_s"}
    return pa.schema([(c, pa.int64() if c in ints else pa.float64() if c in floats else pa.string()) for c in COLUMNS])


def load_table(folder: str | Path) -> list[dict]:
    """The rows of a results folder (its Parquet table, else its runs so far), each measured
    against the best bound of its instance (:func:`certify`)."""
    folder = Path(folder)
    if (folder / "results.parquet").exists():
        import pyarrow.parquet as pq

        return certify(pq.read_table(folder / "results.parquet").to_pylist())
    if (folder / "runs.jsonl").exists():
        return certify(read_rows(folder / "runs.jsonl"))
    raise BilleError(f"{folder}: no sweep results here (expected results.parquet or runs.jsonl)")
