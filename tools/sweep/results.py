"""A sweep's results folder: one JSON line per finished run (``runs.jsonl``, appended as runs
finish, so a sweep stopped or crashed midway loses no finished run), the schedules beside it
(``schedules/HASH-METHOD-N.yaml``), and the table as Parquet and CSV (``results.parquet``,
``results.csv``, rows sorted by run key) written when the sweep ends.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

from bille.instances import BilleError

COLUMNS = ["key", "instance", "instance_hash", "width", "height", "robots", "tiles", "moved", "method", "options",
           "label", "status", "makespan", "tiles_traveled", "lower_bound", "certified_gap", "time_s", "expansions",
           "stats", "error", "schedule", "bille_version", "python_version"]
TIMING = ("time_s", "stats")  # the columns that differ from one run of a sweep to the next


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
        line = json.dumps({c: row.get(c) for c in COLUMNS}) + "\n"
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

    ordered = sorted(rows, key=lambda r: r["key"])
    table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMNS} for r in ordered], schema=_schema())
    parquet, csv = folder / "results.parquet", folder / "results.csv"
    pq.write_table(table, parquet)
    pacsv.write_csv(table, csv)
    return parquet, csv


def _schema():
    import pyarrow as pa

    ints = {"width", "height", "robots", "tiles", "moved", "makespan", "tiles_traveled", "lower_bound", "expansions"}
    floats = {"certified_gap", "time_s"}
    return pa.schema([(c, pa.int64() if c in ints else pa.float64() if c in floats else pa.string()) for c in COLUMNS])


def load_table(folder: str | Path) -> list[dict]:
    """The rows of a results folder (its Parquet table, else its runs so far)."""
    folder = Path(folder)
    if (folder / "results.parquet").exists():
        import pyarrow.parquet as pq

        return pq.read_table(folder / "results.parquet").to_pylist()
    if (folder / "runs.jsonl").exists():
        return read_rows(folder / "runs.jsonl")
    raise BilleError(f"{folder}: no sweep results here (expected results.parquet or runs.jsonl)")
