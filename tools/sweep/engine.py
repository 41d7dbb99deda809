"""Running a sweep's runs: each in a child process of its own, with a time and a memory limit, on
local worker threads or on a Dask cluster; the same rows either way.

A run's child process is forked from a fork server that has bille imported (tens of
milliseconds per run instead of a fresh interpreter's second). The child sets its address-space
limit, solves through ``solve()`` (which validates every schedule), and sends one row back. What
goes wrong is a row too, never the end of the sweep: ``memory limit`` (Python ran out of the
run's memory: the limit is on top of what the child has mapped when it starts), ``crashed`` (it
died: a signal or an exit code, with the last words it wrote to stderr, e.g. a C++ library's
``std::bad_alloc`` at the memory limit), ``killed`` (no answer 30 s after its time limit),
``error`` (an exception, with its message).
"""
from __future__ import annotations

import functools
import json
import multiprocessing
import os
import platform
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from importlib.metadata import version

from .spec import Run

GRACE_S = 30.0  # a run that does not answer this long after its time limit is killed
_CONTEXT = None


def _context():
    global _CONTEXT
    if _CONTEXT is None:
        try:
            _CONTEXT = multiprocessing.get_context("forkserver")
            _CONTEXT.set_forkserver_preload(["bille.solvers", "bille.tools.sweep.engine"])
        except ValueError:  # no fork server on this platform
            _CONTEXT = multiprocessing.get_context("spawn")
    return _CONTEXT


@functools.lru_cache(maxsize=1)
def versions() -> dict:
    return {"bille_version": version("bille"), "python_version": platform.python_version()}


@functools.lru_cache(maxsize=256)
def _sizes(text: str) -> dict:
    from bille.instances import instance_from_text

    inst = instance_from_text(text)
    return dict(width=inst.width, height=inst.height, robots=inst.num_robots, tiles=int(inst.start.tiles.sum()),
                moved=int((inst.start.tiles & ~inst.goal_tiles).sum()))


def describe(run: Run) -> dict:
    """The columns that depend on the run alone (not on its outcome)."""
    return dict(key=run.key, instance=run.instance, instance_hash=run.instance_hash, **_sizes(run.text),
                method=run.method, options=run.options_json, label=run.label)


def execute(run: Run, time_limit: float, memory_limit: int | None, target=None) -> dict:
    """Run ``run`` in a child process and return its row (see the module docstring)."""
    row = dict(describe(run), status=None, makespan=None, tiles_traveled=None, lower_bound=None,
               certified_gap=None, time_s=None, expansions=None, stats=None, error=None, schedule=None,
               **versions())
    ctx = _context()
    inbox, outbox = ctx.Pipe(duplex=False)
    errors = tempfile.NamedTemporaryFile("w+", suffix=".stderr", delete=False)
    errors.close()
    child = ctx.Process(target=_child, args=(target or solve_in_child, errors.name, outbox, run.text, run.method,
                                             dict(run.options), time_limit, memory_limit), daemon=True)
    began = time.perf_counter()
    _start(child)
    outbox.close()
    limit = dict(run.options).get("time_limit", time_limit) + GRACE_S
    answer = None
    try:
        if inbox.poll(limit):
            answer = inbox.recv()
    except EOFError:
        answer = None
    finally:
        if child.is_alive() and answer is None:
            child.kill()
        child.join(5)
        inbox.close()
    if answer is None:
        code = child.exitcode
        if time.perf_counter() - began >= limit:
            row.update(status="failed", error=f"killed: no answer {GRACE_S:g} s after the time limit")
        else:
            how = f"signal {-code}" if code is not None and code < 0 else f"exit code {code}"
            said = _last_line(errors.name)
            row.update(status="failed", error=f"crashed ({how})" + (f": {said}" if said else ""))
        row["time_s"] = round(time.perf_counter() - began, 3)
    else:
        row.update(answer)
    os.unlink(errors.name)
    return row


def _last_line(path: str) -> str:
    """The last lines a crashed child wrote to its stderr, in one line (a library's last word,
    such as ``std::bad_alloc`` when it ran out of memory)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = [line.strip() for line in f if line.strip()]
    except OSError:
        return ""
    return " ".join(lines[-2:])[:200]


def _child(target, errors_path, *args) -> None:
    """The child's stderr goes to a file the parent reads if the child crashes."""
    fd = os.open(errors_path, os.O_WRONLY)
    os.dup2(fd, 2)
    os.close(fd)
    target(*args)


def _start(child) -> None:
    """Start ``child``, also from a daemonic process: Dask's workers are daemons, and
    multiprocessing refuses children there lest a killed daemon leave them behind. Ours is
    joined or killed by :func:`execute` itself, and a daemon of its own, so the flag is lifted
    for the start alone."""
    config = multiprocessing.current_process()._config
    daemon = config.get("daemon")
    config["daemon"] = False
    # The child needs bille, not the main module; a main module run as a script (the bille
    # console script) would be run again in every child (170 ms each) unless its path is hidden
    # while the child's start data are taken.
    main = sys.modules["__main__"]
    path = main.__dict__.pop("__file__", None) if getattr(main, "__spec__", None) is None else None
    try:
        child.start()
    finally:
        if daemon is not None:
            config["daemon"] = daemon
        if path is not None:
            main.__file__ = path


def solve_in_child(outbox, text: str, method: str, options: dict, time_limit: float, memory_limit) -> None:
    """The child's side: limits, the solve, one row sent back."""
    import resource

    from bille.instances.limits import mapped

    if memory_limit:  # on top of what the child has mapped already (bille and its libraries)
        size = mapped() + memory_limit * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (size, size))
    try:
        from bille.instances import instance_from_text
        from bille.solvers import dump_schedule, solve

        inst = instance_from_text(text)
        options = {"time_limit": time_limit, **options}
        result = solve(inst, method, bound=True, **options)
        m, lower = result.metrics, result.lower_bound
        gap = None
        if m is not None and lower:
            gap = round((m.makespan - lower) / lower, 6)
        stats = {k: v for k, v in result.stats.items() if isinstance(v, (int, float, str, bool)) or v is None}
        expansions = next((int(result.stats[k]) for k in ("expansions", "nodes", "states")
                           if isinstance(result.stats.get(k), (int, float))), None)
        outbox.send(dict(status=result.status, makespan=m.makespan if m else None,
                         tiles_traveled=m.tiles_traveled if m else None, lower_bound=lower, certified_gap=gap,
                         time_s=round(result.time_s, 4), expansions=expansions, stats=json.dumps(stats, sort_keys=True),
                         schedule=None if result.schedule is None else dump_schedule(result.schedule)))
    except MemoryError:
        outbox.send(dict(status="failed", error=f"memory limit: more than {memory_limit} MB"))
    except Exception as exc:  # noqa: BLE001 - every failure is a row, never the end of the sweep
        outbox.send(dict(status="failed", error=f"error: {type(exc).__name__}: {exc}"))
    finally:
        outbox.close()


def run_local(runs: list[Run], time_limit: float, memory_limit, jobs: int, on_row) -> None:
    """The runs on ``jobs`` worker threads, each run in its own child process."""
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(execute, r, time_limit, memory_limit) for r in runs]
        for fut in as_completed(futures):
            on_row(fut.result())


def run_dask(runs: list[Run], time_limit: float, memory_limit, client, on_row) -> None:
    """The runs as tasks of a Dask cluster (``client``), each in a child process on its worker."""
    from distributed import as_completed as dask_completed

    futures = client.map(execute, runs, time_limit=time_limit, memory_limit=memory_limit, pure=False)
    run_of = {fut.key: run for fut, run in zip(futures, runs)}
    for fut in dask_completed(futures):
        try:
            row = fut.result()
        except Exception as exc:  # noqa: BLE001 - a lost worker (KilledWorker) is a row too
            row = dict(describe(run_of[fut.key]), status="failed", error=f"worker lost: {type(exc).__name__}: {exc}",
                       **versions())
        on_row(row)
