"""One ``bille run``: the broker, the robots (simulated processes or given ids), the journal.

``--robots sim`` (or ``sim:N``) starts one ``bille robot-sim`` process per robot of the schedule,
each with a fresh random secret handed over in its environment (never on the command line, never
written down); they exit with the executor. Given ids (``--robots a,b,c``, in schedule order) are
robots already connected to the broker, with their secrets in ``--secrets FILE``.
"""
from __future__ import annotations

import os
import secrets
import subprocess
import sys
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from bille.instances import Instance
from bille.solvers import bind, validate

from .broker import BrokerURL, EmbeddedBroker, parse_url
from .executor import Settings, load_secrets, run_plan
from .outcome import Outcome
from .journal import Journal, Replayed, fleet_secret, replay, sha256_file
from .protocol import ExecutionError

SECRET_ENV = "BILLE_ROBOT_SECRET"


@dataclass
class SimOptions:
    """Faults for the simulated robots: per-robot extra ``robot-sim`` arguments by index."""

    fault_rate: float = 0.0
    delay_ms: float = 0.0
    seed: int = 0
    extra: dict[int, list[str]] = field(default_factory=dict)


def parse_robots(spec: str, count: int) -> tuple[list[str], bool]:
    """``sim``, ``sim:N`` or ``id,id,...`` -> (ids in schedule order, simulated?)."""
    if spec == "sim" or spec.startswith("sim:"):
        n = count
        if spec != "sim":
            try:
                n = int(spec[4:])
            except ValueError:
                raise ExecutionError(f"--robots: {spec!r}: expected sim:N with a number N") from None
        if n != count:
            raise ExecutionError(f"--robots: sim:{n}, but the schedule has {count} robots")
        return [f"r{i}" for i in range(count)], True
    ids = [r.strip() for r in spec.split(",")]
    if any(not r or "/" in r or "+" in r or "#" in r for r in ids):
        raise ExecutionError(f"--robots: {spec!r}: robot ids must be non-empty and free of '/', '+', '#'")
    if len(set(ids)) != len(ids):
        raise ExecutionError(f"--robots: {spec!r}: a robot id is repeated")
    if len(ids) != count:
        raise ExecutionError(f"--robots: {len(ids)} ids, but the schedule has {count} robots")
    return ids, False


def sim_command(robot: str, url: BrokerURL, fleet: str, opts: SimOptions, index: int) -> list[str]:
    cmd = [sys.executable, "-m", "bille.tools.cli", "robot-sim", "--id", robot, "--broker", str(url),
           "--fleet", fleet, "--secret-env", SECRET_ENV, "--exit-with-parent",
           "--seed", str(opts.seed + index)]
    if opts.fault_rate:
        cmd += ["--fault-rate", str(opts.fault_rate)]
    if opts.delay_ms:
        cmd += ["--delay", str(opts.delay_ms)]
    return cmd + opts.extra.get(index, [])


@contextmanager
def simulated(robots: list[str], url: BrokerURL, fleet: str, opts: SimOptions):
    """Start one simulated robot process per id; yields their secrets; stops them on exit."""
    keys = {r: secrets.token_hex(16) for r in robots}
    procs = []
    try:
        for i, r in enumerate(robots):
            env = dict(os.environ, **{SECRET_ENV: keys[r]})
            procs.append(subprocess.Popen(sim_command(r, url, fleet, opts, i), env=env, stdin=subprocess.DEVNULL))
        yield {r: k.encode() for r, k in keys.items()}
    finally:
        for p in procs:
            if p.poll() is None:
                p.terminate()
        for p in procs:
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                p.kill()


@contextmanager
def broker_at(url: str | None, host: str = "127.0.0.1"):
    """The broker to use: the given URL, or an embedded one on a free port of ``host``."""
    if url:
        yield parse_url(url)
    else:
        with EmbeddedBroker(host) as broker:
            yield broker.url


def start(instance: Instance, instance_path: str, schedule, schedule_path: str, *, broker: str | None,
          robots: str, secrets_path: str | None, journal_path: str, settings: dict,
          sims: SimOptions | None = None, host: str = "127.0.0.1", progress=None) -> Outcome:
    """A fresh run of a schedule. Raises :class:`ExecutionError` (or another ``BilleError``) for
    bad input before anything is sent or written."""
    plan = bind(instance, schedule)
    report = validate(instance, schedule)
    if not report.valid:
        raise ExecutionError(f"{schedule_path}: the schedule does not solve {instance.name}: {report.violation}")
    ids, simulate = parse_robots(robots, instance.num_robots)
    keys = None if simulate else _secrets(secrets_path, ids)
    head = {"instance": str(Path(instance_path).resolve()), "instance_sha256": sha256_file(instance_path),
            "schedule": str(Path(schedule_path).resolve()), "schedule_sha256": sha256_file(schedule_path),
            "fleet": settings.get("fleet", "default"), "robots": ids, "simulated": simulate, "broker": broker,
            "secrets": str(Path(secrets_path).resolve()) if secrets_path else None, "steps": int(plan.shape[1])}
    journal = Journal(journal_path, secret=fleet_secret())
    try:
        journal.write("run", **head)
        with ExitStack() as stack:
            url = stack.enter_context(broker_at(broker, host))
            if simulate:
                keys = stack.enter_context(simulated(ids, url, head["fleet"], sims or SimOptions()))
            return run_plan(instance, plan, Settings(url=url, robots=ids, secrets=keys, **settings), journal,
                            progress=progress)
    except BaseException:
        journal.discard()  # nothing released: leave no journal behind
        raise
    finally:
        journal.close()


def resume(journal_path: str, *, broker: str | None, secrets_path: str | None, settings: dict,
           sims: SimOptions | None = None, replan: bool = False, host: str = "127.0.0.1", progress=None,
           done: Replayed | None = None) -> Outcome:
    """Continue a run from its journal (see :mod:`.journal`); ``replan`` plans the rest again
    from the robots' reported state first. ``done``: the journal already replayed."""
    done = done if done is not None else replay(journal_path)
    head = done.run
    if done.done:
        raise ExecutionError(f"{journal_path}: the run is complete (all {done.finished} steps); nothing to resume")
    ids = head["robots"]
    broker = broker if broker is not None else head["broker"]
    keys = None if head["simulated"] else _secrets(secrets_path or head["secrets"], ids)
    settings = {**settings, "fleet": head["fleet"]}
    with ExitStack() as stack:
        url = stack.enter_context(broker_at(broker, host))
        if head["simulated"]:
            keys = stack.enter_context(simulated(ids, url, head["fleet"], sims or SimOptions()))
        journal = Journal(journal_path, append=True, secret=fleet_secret(), previous=done.signature)
        stack.callback(journal.close)
        journal.write("resume", finished=done.finished, released=done.released)
        return run_plan(done.instance, done.plan, Settings(url=url, robots=ids, secrets=keys, **settings), journal,
                        replayed=done, replan=replan, progress=progress)


def _secrets(path: str | None, ids: list[str]) -> dict[str, bytes]:
    if not path:
        raise ExecutionError("--secrets: robots given by id need their shared secrets (a YAML file: id: secret)")
    return load_secrets(path, ids)
