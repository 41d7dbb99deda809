"""Start-up time of the light commands and of two tiny solves, against importing the libraries
every command needs.

Each command runs in a fresh interpreter ``runs`` times, interleaved with the baseline
(``python -c "import numpy, click, yaml, rich"``) so that a change of load on the machine touches
both; the median of each is reported with its ratio to the baseline's.
"""
from __future__ import annotations

import statistics
import subprocess
import sys
import time

BASELINE = "import numpy, click, yaml, rich"
COMMANDS = (["--help"], ["list"], ["show", "point-4"], ["check", "point-4", "point-4.schedule"],
            ["solve", "--help"], ["solve", "crowded-2", "-m", "cbs"], ["solve", "compare-4", "-m", "temporal-astar"])
_MAIN = "import sys; from bille.tools.cli import main; sys.argv[0] = 'bille'; main()"


def _seconds(argv: list[str]) -> float:
    began = time.perf_counter()
    subprocess.run([sys.executable, *argv], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.perf_counter() - began


def measure(commands=COMMANDS, runs: int = 5) -> list[dict]:
    """Per command: its median seconds, the baseline's median over the same rounds, the ratio."""
    base: list[float] = []
    times: dict[int, list[float]] = {i: [] for i in range(len(commands))}
    for _ in range(runs):
        base.append(_seconds(["-c", BASELINE]))
        for i, argv in enumerate(commands):
            times[i].append(_seconds(["-c", _MAIN, *argv]))
    b = statistics.median(base)
    return [{"command": "bille " + " ".join(argv), "s": statistics.median(times[i]), "baseline_s": b,
             "ratio": statistics.median(times[i]) / b} for i, argv in enumerate(commands)]


def report(runs: int = 5) -> list[str]:
    rows = measure(runs=runs)
    lines = [f"median of {runs} runs each, interleaved; baseline `python -c \"{BASELINE}\"` "
             f"{rows[0]['baseline_s']:.3f} s"]
    lines += [f"  {r['command']:<44} {r['s']:.3f} s  {r['ratio']:.1f}x" for r in rows]
    if sys.dont_write_bytecode:  # PYTHONDONTWRITEBYTECODE: bille's modules compiled at every start
        lines.append("Python writes no bytecode here (PYTHONDONTWRITEBYTECODE), so every start compiles "
                     "bille's modules that have none cached yet")
    return lines
