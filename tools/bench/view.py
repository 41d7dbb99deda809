"""Benchmark of the recording and the pictures (``bille bench view``).

A random valid ``steps``-step schedule of ``robots`` robots on a ``size x size`` structure (the
one of ``bille bench core``) is replayed for drawing, logged to a rerun file, and drawn as a PNG
strip of five frames, against the validator on the same schedule as the baseline of the run.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from bille.solvers import validate

from .core import walk_instance
from ..pictures import save_png
from ..recording import read, record
from ..trace import trace


def report(size: int = 64, robots: int = 20, steps: int = 1000, seed: int = 0) -> list[str]:
    inst, sched = walk_instance(size, robots, steps, seed)

    def timed(fn):
        t0 = time.perf_counter()
        out = fn()
        return time.perf_counter() - t0, out

    t_validate, report_ = timed(lambda: validate(inst, sched))
    if not report_.valid:
        raise RuntimeError(f"the benchmark's random walk is invalid: {report_.violation}")
    with tempfile.TemporaryDirectory() as folder:
        rrd, png = Path(folder) / "bench.rrd", Path(folder) / "bench.png"
        t_trace, tr = timed(lambda: trace(inst, sched, "walk"))
        t_record, info = timed(lambda: record([tr], rrd))
        t_read, data = timed(lambda: read(rrd))
        t_png, layout = timed(lambda: save_png([tr], png, cell=8))
        png_kb = png.stat().st_size / 1e3
    total = t_trace + t_record
    m = report_.metrics
    return [
        f"view: {sched.length} steps x {robots} robots on {size}x{size} ({m.picks} picks, {m.places} places, "
        f"{len(tr.changes())} frames where the tiles change)",
        f"  validate (baseline)      {t_validate * 1e3:8.0f} ms",
        f"  replay for drawing       {t_trace * 1e3:8.0f} ms   = {t_trace / t_validate:.1f}x validate",
        f"  log to rerun file        {t_record * 1e3:8.0f} ms   = {t_record / t_validate:.1f}x validate",
        f"  replay + log             {total * 1e3:8.0f} ms   [target < 5000 ms]; file {info['bytes'] / 1e6:.1f} MB, "
        f"{len(data)} entities",
        f"  read back (rerun reader) {t_read * 1e3:8.0f} ms",
        f"  PNG strip of 5 frames    {t_png * 1e3:8.0f} ms   {layout.size_px[0]}x{layout.size_px[1]} px, {png_kb:.0f} kB",
    ]


def main() -> None:
    for line in report():
        print(line, flush=True)


if __name__ == "__main__":
    main()
