"""Ctrl-C as a terminal sends it (``bille bench interrupt``).

Each run starts ``bille solve INSTANCE -m METHOD --time-limit L -o FILE`` in a process group of
its own, with SIGINT at its default (a process started in the background of a shell inherits it
ignored), sends SIGINT to the whole group at a random moment (seeded), and records what a user
sees: the exit code, the seconds from the signal to the exit, whether a traceback was printed,
and whether the schedule written (if any) is valid for the instance. A signal is *lost* when the
run goes on past two seconds after it, or exits as if it had not come (exit 0 or 1).
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bille.instances import BilleError
from bille.solvers import load_schedule, validate

from ..common import instance_arg
from ..tables import text_table

GRACE = 2.0  # seconds from the signal to the exit that count as "at once"


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def one_run(instance: str, method: str, time_limit: float, at: float) -> dict:
    """One solve stopped by SIGINT ``at`` seconds after its start."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.yaml"
        argv = [sys.executable, "-m", "bille", "solve", instance, "-m", method, "--time-limit", str(time_limit),
                "-o", str(out)]
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                                preexec_fn=_default_sigint, text=True)
        try:
            proc.wait(timeout=at)
            sent = None  # it finished first
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGINT)
            sent = time.perf_counter()
        try:
            _, err = proc.communicate(timeout=time_limit + 30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            _, err = proc.communicate()
        took = None if sent is None else time.perf_counter() - sent
        row = dict(instance=instance, method=method, at=round(at, 2), code=proc.returncode,
                   after_s=None if took is None else round(took, 2), traceback="Traceback" in err,
                   last_error=err.strip().splitlines()[-1] if "Traceback" in err else None,
                   written=out.is_file(), valid=None)
        if out.is_file():
            try:
                row["valid"] = validate(instance_arg(instance), load_schedule(out)).valid
            except BilleError:
                row["valid"] = False
        row["lost"] = sent is not None and (took > GRACE or proc.returncode in (0, 1))
        return row


def runs(pairs: list[tuple[str, str]], count: int, time_limit: float, seed: int):
    """``count`` runs spread over ``pairs`` (instance, method), each stopped at a random moment
    within the first two thirds of its time limit."""
    rnd = random.Random(seed)
    for k in range(count):
        instance, method = pairs[k % len(pairs)]
        yield one_run(instance, method, time_limit, rnd.uniform(0.3, 2 * time_limit / 3))


def table(rows: list[dict]) -> list[str]:
    lines = [[r["instance"], r["method"], f"{r['at']:.2f}", r["code"], r["after_s"], "yes" if r["traceback"] else "",
              {None: "-", True: "valid", False: "INVALID"}[r["valid"]], "LOST" if r["lost"] else ""] for r in rows]
    columns = ["instance", "method", "signal at [s]", "exit", "exit after [s]", "traceback", "schedule", "lost"]
    out = text_table(columns, lines, right={"signal at [s]", "exit", "exit after [s]"})
    stopped = [r for r in rows if r["after_s"] is not None]
    out.append(f"{len(rows)} runs, {len(stopped)} stopped by the signal ({len(rows) - len(stopped)} finished first): "
               f"{sum(r['lost'] for r in rows)} lost, {sum(r['traceback'] for r in rows)} tracebacks, "
               f"{sum(r['code'] == 130 for r in stopped)} exit 130, "
               f"{sum(r['valid'] is False for r in rows)} invalid schedules; slowest exit "
               f"{max((r['after_s'] for r in stopped), default=0):.2f} s after the signal")
    out += [f"traceback of {r['instance']} {r['method']} (signal at {r['at']:.2f} s): {r['last_error']}"
            for r in rows if r.get("last_error")]
    return out
