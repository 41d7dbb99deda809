"""Benchmark of the reduction generator (``bille bench hampath``).

Theorem 1's instance for full ``k x k`` grid graphs, from the 2x2 grid (the baseline of the run)
up to ``size x size``: time to build and check the instance, time to decide the Hamiltonian path
from the robot's vertex, time to write the YAML file, and the sizes.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from bille.instances import save_instance
from bille.instances.generators.graphs import grid_graph, hamiltonian_path
from bille.instances.generators.hampath import default_start, reduction


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def report(size: int = 10, scale: int = 1, robots: int = 1) -> list[str]:
    lines = [f"hampath: full k x k grid graphs, scale {scale}, {robots} robot(s); ratios to the 2x2 grid",
             f"  {'graph':>7} {'grid':>11} {'tiles':>7} {'moved':>6} {'bound':>7} {'build':>9} {'ratio':>6} "
             f"{'decide':>9} {'write':>9} {'file':>9}"]
    base = None
    reduction(grid_graph([(0, 0), (1, 0)]), scale)     # warm-up: imports and compiled tables
    with tempfile.TemporaryDirectory() as folder:
        for k in sorted({2, *range(4, size + 1, 2), size}):
            g = grid_graph((x, y) for x in range(k) for y in range(k))
            t_build, inst = _timed(lambda: reduction(g, scale, robots=robots))
            t_decide, _ = _timed(lambda: hamiltonian_path(g, start=default_start(g)))
            path = Path(folder) / f"h{k}.yaml"
            t_write, _ = _timed(lambda: save_instance(inst, path))
            base = base or t_build
            moved = int((inst.start.tiles & ~inst.goal_tiles).sum())
            lines.append(f"  {f'{k}x{k}':>7} {f'{inst.width}x{inst.height}':>11} {int(inst.start.tiles.sum()):>7} "
                         f"{moved:>6} {inst.meta['bound']:>7} {t_build * 1e3:>6.0f} ms {t_build / base:>5.1f}x "
                         f"{t_decide * 1e3:>6.1f} ms {t_write * 1e3:>6.0f} ms {path.stat().st_size / 1e3:>6.0f} kB")
    lines.append("  build includes the Hamiltonian path decision and the instance check")
    return lines
