"""``bille run`` and ``bille robot-sim``: the command line of the execution layer."""
from __future__ import annotations

import json
import logging
import os
import sys
import threading
import time
from datetime import datetime
from pathlib import Path

import click

from .outcome import POLICIES, dumps, summary_lines

EXIT_OK, EXIT_NO, EXIT_INTERRUPTED = 0, 1, 130


def _interrupted(journal: Path, as_json: bool) -> int:
    """Ctrl-C during a run: the step its journal reached and how to go on from there."""
    from .session import replay

    try:
        done = replay(journal)
    except Exception:  # noqa: BLE001 - no journal, or none yet readable: nothing was finished
        done = None
    finished = 0 if done is None else done.finished
    steps = None if done is None else done.plan.shape[1]
    if as_json:
        click.echo(json.dumps({"status": "interrupted", "finished": finished, "steps": steps,
                               "journal": None if done is None else str(journal)}))
    elif done is None:
        click.echo("interrupted before the first step was journaled: nothing to resume", err=True)
    else:
        click.echo(f"interrupted after step {finished} of {steps}; continue with: bille run --resume {journal}",
                   err=True)
    return EXIT_INTERRUPTED


class _Progress:
    """A live line on a terminal: step, robots done, whom the executor waits for."""

    def __init__(self, enabled: bool, total: int):
        self.enabled, self.total, self.last = enabled, total, 0.0
        self.progress = None
        if enabled:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            self.progress = Progress(TextColumn("step"), MofNCompleteColumn(), BarColumn(), TimeElapsedColumn(),
                                     TextColumn("{task.description}"), transient=True)
            self.task = self.progress.add_task("", total=total)

    def __enter__(self):
        if self.progress is not None:
            self.progress.start()
        return self

    def __exit__(self, *exc):
        if self.progress is not None:
            self.progress.stop()

    def __call__(self, k: int, done: int, waiting: list[str]) -> None:
        if self.progress is None or time.perf_counter() - self.last < 0.1 and waiting:
            return
        self.last = time.perf_counter()
        who = ", ".join(waiting[:6]) + (" ..." if len(waiting) > 6 else "")
        text = f"robots done {done}/{done + len(waiting)}" + (f", waiting for {who}" if waiting else "")
        self.progress.update(self.task, completed=k - 1 if waiting else k, description=text)


@click.command("run")
@click.argument("instance", required=False)
@click.argument("schedule", required=False)
@click.option("--resume", "journal_in", type=click.Path(dir_okay=False), metavar="JOURNAL",
              help="Continue the run of this journal (INSTANCE and SCHEDULE come from it).")
@click.option("--replan", is_flag=True, help="With --resume: plan the rest again (--replan-method) from the "
                                             "robots' reported state instead of retrying the step.")
@click.option("--broker", metavar="URL", help="mqtt://host:port of an external broker (default: an embedded "
                                              "broker on a free loopback port).")
@click.option("--bind", default="127.0.0.1", show_default=True, metavar="HOST",
              help="Address the embedded broker listens on.")
@click.option("--robots", default="sim", show_default=True, metavar="sim|sim:N|ID,ID,...",
              help="Simulated robot processes, or the ids of running robots in schedule order.")
@click.option("--secrets", "secrets_path", type=click.Path(dir_okay=False), metavar="FILE",
              help="YAML mapping of robot id to shared secret (robots given by id).")
@click.option("--fleet", default="default", show_default=True, help="The fleet name in the topics.")
@click.option("--journal", type=click.Path(dir_okay=False), help="Journal file (default: <instance>-<time>.journal.jsonl).")
@click.option("--step-timeout", type=click.FloatRange(min=0.1), default=5.0, show_default=True,
              help="Seconds before a silent robot is asked for its state, and again before it is a fault.")
@click.option("--on-fault", type=click.Choice(POLICIES), default="stop", show_default=True,
              help="stop and report; retry the step; or re-plan from the reported state.")
@click.option("--retries", type=click.IntRange(min=0), default=2, show_default=True, help="Recoveries per step.")
@click.option("--replan-method", default="temporal-astar", show_default=True, help="Planner for --on-fault replan and --replan.")
@click.option("--reconnect-timeout", type=click.FloatRange(min=0.1), default=30.0, show_default=True,
              help="Seconds a retry waits for a lost robot to answer again.")
@click.option("--connect-timeout", type=click.FloatRange(min=0.1), default=30.0, show_default=True,
              help="Seconds the robots may take to answer at the start.")
@click.option("--window", type=click.IntRange(min=1), default=5, show_default=True,
              help="Steps per order: the released step and the horizon after it.")
@click.option("--sim-fault-rate", type=click.FloatRange(0, 1), default=0.0, help="Simulated robots: chance per step of "
                                                                                  "a failed action or dropped report.")
@click.option("--sim-delay", type=click.FloatRange(min=0), default=0.0, metavar="MS", help="Simulated robots: report delay.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the simulated robots' faults.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
@click.option("--force", is_flag=True, help="Run a schedule that names another instance than INSTANCE.")
def run(instance, schedule, journal_in, replan, broker, bind, robots, secrets_path, fleet, journal, step_timeout,
        on_fault, retries, replan_method, reconnect_timeout, connect_timeout, window, sim_fault_rate, sim_delay, seed,
        as_json, force) -> int:
    """Execute SCHEDULE of INSTANCE on robots over MQTT, one synchronized step at a time.

    Exit 0 when the robots reached the goal, 1 when the run stopped safely after a fault (resume
    it with --resume), 2 for bad input.
    """
    from bille.instances import InstanceError, ScheduleError, load_instance
    from bille.instances.bundled import resolve
    from bille.instances.schedule import written_for
    from bille.solvers import METHODS, load_schedule

    from . import session
    from .protocol import ExecutionError

    if replan_method not in METHODS:
        raise ExecutionError(f"--replan-method: unknown method {replan_method!r} (expected one of: {', '.join(METHODS)})")
    settings = dict(step_timeout=step_timeout, on_fault=on_fault, retries=retries, replan_method=replan_method,
                    reconnect_timeout=reconnect_timeout, connect_timeout=connect_timeout, window=window)
    sims = session.SimOptions(fault_rate=sim_fault_rate, delay_ms=sim_delay, seed=seed)
    _quiet_logs(as_json)
    if journal_in:
        if instance or schedule:
            raise click.UsageError("give either INSTANCE SCHEDULE or --resume JOURNAL, not both")
        path = Path(journal_in)
        done = session.replay(path)
        if done.done:  # nothing to send: say so, as the run's own end did
            if replan:
                raise ExecutionError(f"{path}: the run is complete (all {done.finished} steps); nothing to re-plan")
            if as_json:
                click.echo(json.dumps({"status": "completed", "steps": done.finished, "finished": done.finished,
                                       "executed": 0, "journal": str(path)}))
            else:
                click.echo(f"completed: the run of {path} is finished (all {done.finished} steps); nothing to resume")
            return EXIT_OK
        try:
            with _Progress(not as_json and sys.stderr.isatty(), done.plan.shape[1]) as bar:
                out = session.resume(journal_in, broker=broker, secrets_path=secrets_path, settings=settings,
                                     sims=sims, replan=replan, host=bind, progress=bar, done=done)
        except KeyboardInterrupt:
            return _interrupted(path, as_json)
    else:
        if not instance or not schedule:
            raise click.UsageError("missing INSTANCE and SCHEDULE (or --resume JOURNAL)")
        if replan:
            raise click.UsageError("--replan goes with --resume JOURNAL")
        inst_path, sched_path = resolve(instance, InstanceError), resolve(schedule, ScheduleError)
        inst, sched = load_instance(inst_path), load_schedule(sched_path)
        why = written_for(inst, sched)
        if why is not None:
            if not force:
                raise ScheduleError(f"{why}; --force to run it anyway")
            click.echo(f"warning: {why}; run as --force asks", err=True)
        path = Path(journal or f"{inst.name}-{datetime.now():%Y%m%d-%H%M%S}.journal.jsonl")
        settings["fleet"] = fleet
        try:
            with _Progress(not as_json and sys.stderr.isatty(), sched.length) as bar:
                out = session.start(inst, str(inst_path), sched, str(sched_path), broker=broker, robots=robots,
                                    secrets_path=secrets_path, journal_path=str(path), settings=settings, sims=sims,
                                    host=bind, progress=bar)
        except KeyboardInterrupt:
            return _interrupted(path, as_json)
    if as_json:
        click.echo(dumps(out))
    else:
        for line in summary_lines(out, path):
            click.echo(line)
    return EXIT_OK if out.status == "completed" and out.worlds_match else EXIT_NO


def _quiet_logs(quiet: bool) -> None:
    logging.basicConfig(level=logging.ERROR if quiet else logging.WARNING, format="bille: %(message)s",
                        stream=sys.stderr)


@click.command("robot-sim")
@click.option("--id", "robot_id", required=True, help="This robot's id (a topic level).")
@click.option("--broker", required=True, metavar="URL", help="mqtt://host:port")
@click.option("--fleet", default="default", show_default=True)
@click.option("--secret-env", default="BILLE_ROBOT_SECRET", show_default=True, metavar="VAR",
              help="Environment variable holding the shared secret.")
@click.option("--secrets", "secrets_path", type=click.Path(dir_okay=False), metavar="FILE",
              help="Or: a YAML mapping of robot id to secret.")
@click.option("--fault-rate", type=click.FloatRange(0, 1), default=0.0, show_default=True,
              help="Chance per step of a failed action or a dropped report.")
@click.option("--delay", type=click.FloatRange(min=0), default=0.0, show_default=True, metavar="MS",
              help="Delay of every state report.")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--fail-at", type=click.IntRange(min=1), multiple=True, metavar="STEP", help="Fail this step once.")
@click.option("--drop-at", type=click.IntRange(min=1), multiple=True, metavar="STEP", help="Drop this step's report once.")
@click.option("--die-at", type=click.IntRange(min=1), multiple=True, metavar="STEP",
              help="Exit abruptly before executing this step.")
@click.option("--exit-with-parent", is_flag=True, hidden=True)
def robot_sim(robot_id, broker, fleet, secret_env, secrets_path, fault_rate, delay, seed, fail_at, drop_at, die_at,
              exit_with_parent) -> int:
    """A simulated robot: executes its orders against its own copy of the world and reports its
    state (the reference implementation of the robot side, see docs/execution.md)."""
    from .broker import parse_url
    from .executor import load_secrets
    from .protocol import ExecutionError
    from .robot import Faults, serve

    url = parse_url(broker)
    if secrets_path:
        secret = load_secrets(secrets_path, [robot_id])[robot_id]
    elif os.environ.get(secret_env):
        secret = os.environ[secret_env].encode()
    else:
        raise ExecutionError(f"--secret-env: no secret in ${secret_env} (or give --secrets FILE)")
    logging.basicConfig(level=logging.WARNING, format=f"bille robot {robot_id}: %(message)s", stream=sys.stderr)
    if exit_with_parent:
        parent = os.getppid()

        def watch():
            while os.getppid() == parent:
                time.sleep(0.5)
            os._exit(0)
        threading.Thread(target=watch, daemon=True).start()
    else:  # started by hand: say what it serves (processes started by bille run stay quiet)
        click.echo(f"bille robot-sim: robot '{robot_id}' of fleet '{fleet}' serving orders from {broker} "
                   f"(Ctrl-C to stop)", err=True)
    serve(robot_id, url, secret, fleet=fleet,
          faults=Faults(set(fail_at), set(drop_at), set(die_at), fault_rate, delay, seed))
    return EXIT_OK
