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

A run may start processes of its own (``anytime`` forks its bound search, CP-SAT starts
threads): its child is not a daemon, leads a process group of its own, and is killed with that
group when its time is up or the sweep is stopped (Ctrl-C reaches the sweep alone, which kills
the runs under way and keeps the finished ones). A child whose sweep died without killing it
(``kill -9``) sees its parent gone within a second and ends its group itself.
"""
from __future__ import annotations

import functools
import json
import multiprocessing
import os
import platform
import signal
import sys
import tempfile
import threading
import time
import uuid
from concurrent.futures import ThreadPoolExecutor, as_completed
from importlib.metadata import version

from bille.instances.claim import status_key
from bille.instances.run import Budget

from .spec import Limits, Run

GRACE_S = 30.0  # a run that does not answer this long after its time limit is killed
POLL_S = 0.2  # how often a waiting run looks whether the sweep was stopped
_CONTEXT = None


def _context():
    global _CONTEXT
    if _CONTEXT is None:
        try:
            _CONTEXT = multiprocessing.get_context("forkserver")
            _CONTEXT.set_forkserver_preload(["bille.tools.sweep.warm", "bille.tools.sweep.engine"])
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


def execute(run: Run, limits: Limits, target=None, stop=None) -> dict | None:
    """Run ``run`` in a child process under ``limits`` and return its row (see the module
    docstring); None if ``stop()`` turned true first (the run was killed: it did not finish, so
    it has no row)."""
    row = dict(describe(run), status=None, makespan=None, tiles_traveled=None, lower_bound=None, time_s=None,
               expansions=None, stats=None, error=None, schedule=None, **versions())
    ctx = _context()
    inbox, outbox = ctx.Pipe(duplex=False)
    errors = tempfile.NamedTemporaryFile("w+", suffix=".stderr", delete=False)
    errors.close()
    child = ctx.Process(target=_child, args=(target or solve_in_child, errors.name, outbox, run.text, run.method,
                                             dict(run.options), limits), daemon=False)
    budget = Budget(dict(run.options).get("time_limit", limits.seconds) + GRACE_S)
    _start(child)
    outbox.close()
    answer, stopped = None, False
    try:
        while (left := budget.left()) > 0:
            if inbox.poll(min(POLL_S, left)):
                answer = inbox.recv()
                break
            if stop is not None and stop():
                stopped = True
                break
    except EOFError:  # the child died without a word
        answer = None
    finally:
        if answer is None:
            _kill(child)
        child.join(5)
        if child.is_alive():
            _kill(child)
            child.join()
        inbox.close()
    said = _last_line(errors.name)
    os.unlink(errors.name)
    if stopped:
        return None
    if answer is None:
        code = child.exitcode
        if budget.expired():
            row.update(status="failed", error=f"killed: no answer {GRACE_S:g} s after the time limit")
        else:
            how = f"signal {-code}" if code is not None and code < 0 else f"exit code {code}"
            row.update(status="failed", error=f"crashed ({how})" + (f": {said}" if said else ""))
        row["time_s"] = round(budget.elapsed(), 3)
    else:
        row.update(answer)
    return row


def _kill(child) -> None:
    """Kill the run with every process it started (its process group)."""
    try:
        os.killpg(child.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):  # not yet a group of its own, or gone
        pass
    if child.is_alive():
        child.kill()


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
    """The child leads a process group of its own (what it starts is killed with it, and a
    terminal's Ctrl-C reaches the sweep, not the runs), watches its parent, and writes its
    stderr to a file the parent reads if the child crashes."""
    os.setpgid(0, 0)
    parent = os.getppid()
    threading.Thread(target=_orphaned, args=(parent,), daemon=True, name="bille-watch-parent").start()
    fd = os.open(errors_path, os.O_WRONLY)
    os.dup2(fd, 2)
    os.close(fd)
    target(*args)


def _orphaned(parent: int) -> None:
    """End the run's process group once its parent (the fork server, which ends with the sweep)
    is gone: a sweep killed outright leaves no run behind."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os.killpg(0, signal.SIGKILL)


def _start(child) -> None:
    """Start ``child``, also from a daemonic process: Dask's workers are daemons, and
    multiprocessing refuses children there lest a killed daemon leave them behind (set
    ``distributed.worker.daemon: false`` and they are not). Ours is joined or killed with its
    process group by :func:`execute` itself, and ends itself when orphaned, so the flag is
    lifted for the start alone."""
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


def solve_in_child(outbox, text: str, method: str, options: dict, limits: Limits) -> None:
    """The child's side: limits, the solve, one row sent back."""
    import resource

    from bille.instances.limits import mapped
    from bille.solvers import METHODS

    METHODS[method].plan()  # its module and libraries loaded before the limit (the fork server has them already)
    memory_limit = limits.memory_mb
    if memory_limit:  # on top of what the child has mapped already (bille and its libraries)
        size = mapped() + memory_limit * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (size, size))
    try:
        from bille.instances import OptionError, instance_from_text
        from bille.solvers import dump_schedule, solve

        inst = instance_from_text(text)
        options = {"time_limit": limits.seconds, **options}
        try:
            result = solve(inst, method, bound=True, **options)
        except OptionError as exc:  # the method does not apply to this instance: a row, not a failure
            outbox.send(dict(status="n/a", error=str(exc)))
            return
        m = result.metrics
        stats = {k: v for k, v in result.stats.items() if isinstance(v, (int, float, str, bool)) or v is None}
        if result.failure is not None:  # why the run ended without its answer, in the row's stats
            stats.update(failure=result.failure.text, failure_kind=result.failure.kind)
        counts = result.counters  # the search's effort: LaCAM*'s nodes, or the joint states stored
        expansions = counts.nodes if counts.nodes is not None else counts.states
        said = result.stats.get("violation") or result.stats.get("contradiction") if result.status == "error" else None
        outbox.send(dict(status=status_key(result.status, result.claim), error=said, makespan=m.makespan if m else None,
                         tiles_traveled=m.tiles_traveled if m else None, lower_bound=result.lower_bound,
                         time_s=round(result.time_s, 4), expansions=expansions, stats=json.dumps(stats, sort_keys=True),
                         schedule=None if result.schedule is None else dump_schedule(result.schedule)))
    except MemoryError:
        outbox.send(dict(status="failed", error=f"memory limit: more than {memory_limit} MB"))
    except Exception as exc:  # noqa: BLE001 - every failure is a row, never the end of the sweep
        outbox.send(dict(status="failed", error=f"error: {type(exc).__name__}: {exc}"))
    finally:
        outbox.close()


def run_local(runs: list[Run], limits: Limits, jobs: int, on_row) -> None:
    """The runs on ``jobs`` worker threads, each run in its own child process. Interrupted
    (Ctrl-C), the runs under way are killed; every run finished before is handed to ``on_row``."""
    stop = threading.Event()
    pool = ThreadPoolExecutor(max_workers=jobs)
    futures = [pool.submit(execute, r, limits, stop=stop.is_set) for r in runs]
    handed = set()
    try:
        for fut in as_completed(futures):
            handed.add(fut)
            on_row(fut.result())
    finally:
        stop.set()
        pool.shutdown(wait=True, cancel_futures=True)
    for fut in futures:  # finished while the sweep was being stopped
        if fut not in handed and fut.done() and not fut.cancelled() and fut.exception() is None \
                and fut.result() is not None:
            on_row(fut.result())


class _DaskStop:
    """``stop()`` for a run on a Dask worker: whether the sweep set its stop event (looked up
    at most once a second)."""

    def __init__(self, name: str) -> None:
        self.name, self.when, self.stopped = name, 0.0, False

    def __call__(self) -> bool:
        if not self.stopped and time.monotonic() - self.when >= 1.0:
            from distributed import Event

            self.when = time.monotonic()
            try:
                self.stopped = Event(self.name).is_set()
            except Exception:  # noqa: BLE001 - no scheduler to ask: the run goes on to its limit
                self.stopped = False
        return self.stopped


def run_dask(runs: list[Run], limits: Limits, client, on_row) -> None:
    """The runs as tasks of a Dask cluster (``client``), each in a child process on its worker.
    Interrupted, the sweep's stop event tells the runs under way to end, and the rest are
    cancelled."""
    from distributed import Event
    from distributed import as_completed as dask_completed

    event = Event(f"bille-sweep-stop-{uuid.uuid4().hex}", client=client)
    futures = client.map(execute, runs, limits=limits, stop=_DaskStop(event.name),
                         pure=False)
    run_of = {fut.key: run for fut, run in zip(futures, runs)}
    try:
        for fut in dask_completed(futures):
            try:
                row = fut.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker (KilledWorker) is a row too
                row = dict(describe(run_of[fut.key]), status="failed",
                           error=f"worker lost: {type(exc).__name__}: {exc}", **versions())
            if row is not None:
                on_row(row)
    finally:
        event.set()
        client.cancel([f for f in futures if not f.done()])
