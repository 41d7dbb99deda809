"""Ctrl-C as a terminal sends it (SIGINT to the whole process group) stops a long solve at once:
the back ends end their call, the exact and anytime methods keep their best schedule and bound,
the command line prints ``interrupted``, writes the schedule and exits 130, and the anytime
method's child process ends without a word."""
import os
import pty
import re
import signal
import subprocess
import sys
import time

import pytest

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.schedule import load_schedule
from bille.solvers import validate

# a solve that would run for minutes: bridge-2 at horizon 22, below its optimum 24
LONG_SOLVE = """
import sys
from bille.encodings.backend import open_backend
from bille.encodings.model import Options, build
from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.run import Budget
inst = load_instance(bundled_path("bridge-2"))
backend = open_backend(sys.argv[1], build(inst, 22, Options()), inst)
try:
    print("solving", flush=True)
    backend.solve(budget=Budget(600))
    print("answered")
except KeyboardInterrupt:
    print("interrupted")
    print(backend.solve(budget=Budget(0.5)).status)  # the back end still answers
"""


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["cpsat", "glucose42", "minisat22"])
def test_ctrl_c_ends_a_back_ends_call_at_once(solver):
    proc = subprocess.Popen([sys.executable, "-c", LONG_SOLVE, solver], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    assert proc.stdout.readline().strip() == "solving"
    time.sleep(1.0)  # into the solve, which takes minutes
    os.killpg(proc.pid, signal.SIGINT)
    out, err = proc.communicate(timeout=60)  # the solve alone would take minutes
    assert out.split() == ["interrupted", "unknown"], err


def _interrupted_cli(args: list[str], pattern: str) -> tuple[int, str, str]:
    """``bille solve ARGS`` with stderr on a terminal (so that it shows its progress), sent Ctrl-C
    as a terminal sends it once the progress matches ``pattern``: exit code, stdout, stderr."""
    master, slave = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "bille", "solve", *args], stdout=subprocess.PIPE, stderr=slave,
                            text=True, start_new_session=True)
    os.close(slave)
    seen = b""
    while not re.search(pattern.encode(), seen):
        chunk = os.read(master, 4096)
        assert chunk, seen.decode(errors="replace")
        seen += chunk
    os.killpg(proc.pid, signal.SIGINT)
    out, _ = proc.communicate(timeout=60)  # the time limit is far longer
    try:
        while chunk := os.read(master, 4096):
            seen += chunk
    except OSError:  # the terminal closed with the process
        pass
    os.close(master)
    return proc.returncode, out, seen.decode(errors="replace")


@pytest.mark.slow
@pytest.mark.parametrize("method, pattern", [("anytime", r"best schedule \d+"), ("cpsat", r"horizon \d+"),
                                             ("sat", r"horizon \d+")])
def test_ctrl_c_on_the_command_line_keeps_the_best_schedule(tmp_path, method, pattern):
    out_file = tmp_path / "best.yaml"
    code, out, err = _interrupted_cli(["bridge-2", "-m", method, "--time-limit", "600", "-o", str(out_file)], pattern)
    assert code == 130, (out, err)
    assert out.startswith(f"{method}: interrupted") and "makespan lower bound" in out
    assert "Traceback" not in err
    inst = load_instance(bundled_path("bridge-2"))
    makespan = validate(inst, load_schedule(out_file)).metrics.makespan
    assert f"makespan {makespan}," in out
