"""The execution layer over real brokers: the embedded amqtt broker and mosquitto.

Simulated robots are separate processes (``bille robot-sim``). Every run ends with a check of the
robots' own worlds against the goal, of the journal's replay, and of the pick and place counts
(nothing twice).
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from bille.instances import load_instance
from bille.instances.bundled import resolve
from bille.instances.moveset import Kind
from bille.solvers import bind, load_schedule, validate
from bille.tools.execute import session
from bille.tools.execute.broker import EmbeddedBroker, close, connect, free_port, parse_url
from bille.tools.execute.journal import read_events, replay
from bille.tools.execute.protocol import Gate, Sealer, ExecutionError, parse_topic, tiles_digest, topic

# amqtt's clean-up of a dropped client connection leaves an asyncio transport to the collector
# (its broker thread, not our code); those warnings are not failures of the run under test.
pytestmark = pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")

MAP = "lt-4"  # two robots, four tiles moved, 74 steps
FAST = dict(step_timeout=1.0, reconnect_timeout=5.0, connect_timeout=30.0)


@pytest.fixture(scope="module")
def case():
    ip, sp = str(resolve(MAP)), str(resolve(f"{MAP}.schedule"))
    inst, sched = load_instance(ip), load_schedule(sp)
    assert validate(inst, sched).valid
    ids = bind(inst, sched)
    kinds = [[inst.movesets[i].actions[a].kind for a in row] for i, row in enumerate(ids.tolist())]
    picks = [row.count(Kind.PICK) for row in kinds]
    places = [row.count(Kind.PLACE) for row in kinds]
    return inst, ip, sched, sp, picks, places


@pytest.fixture(scope="module")
def embedded():
    with EmbeddedBroker() as broker:
        yield str(broker.url)


@pytest.fixture(scope="module")
def mosquitto(tmp_path_factory):
    """A mosquitto broker on a free loopback port: the one ``.ci/run`` starts (there its absence
    is a failure, not a skip), or one started here."""
    if os.environ.get("BILLE_TEST_MOSQUITTO"):
        yield os.environ["BILLE_TEST_MOSQUITTO"]
        return
    exe = shutil.which("mosquitto") or next((p for p in ("/usr/sbin/mosquitto",) if os.path.exists(p)), None)
    if exe is None:
        if os.environ.get("BILLE_REQUIRE_MOSQUITTO"):
            pytest.fail("mosquitto is not installed")
        pytest.skip("mosquitto is not installed")
    port = free_port()
    conf = tmp_path_factory.mktemp("mosquitto") / "mosquitto.conf"
    conf.write_text(f"listener {port} 127.0.0.1\nallow_anonymous true\nset_tcp_nodelay true\n")
    proc = subprocess.Popen([exe, "-c", str(conf)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"mqtt://127.0.0.1:{port}"
    for _ in range(100):
        try:
            close(connect(parse_url(url), "probe"))
            break
        except ExecutionError:
            time.sleep(0.05)
    yield url
    proc.terminate()
    proc.wait(5)


@pytest.fixture(params=["embedded", "mosquitto"])
def broker(request):
    return request.getfixturevalue(request.param)


def start(case, tmp_path, broker=None, extra=None, **settings):
    inst, ip, sched, sp, _, _ = case
    journal = tmp_path / "run.journal.jsonl"
    out = session.start(inst, ip, sched, sp, broker=broker, robots="sim", secrets_path=None, journal_path=str(journal),
                        settings={**FAST, **settings}, sims=session.SimOptions(extra=extra or {}))
    return out, journal


def assert_journal_sound(journal: Path, inst) -> None:
    """Steps are released in order (a step again only after a fault), each finished once, and
    the journal replays to the goal."""
    events = read_events(journal)
    released = [e["step"] for e in events if e["event"] == "released"]
    finished = [e["step"] for e in events if e["event"] == "finished"]
    assert finished == sorted(set(finished)) == list(range(1, len(finished) + 1))
    assert all(b in (a, a + 1) for a, b in zip(released, released[1:]))
    done = replay(journal)
    assert done.done and done.finished == done.plan.shape[1]
    assert np.array_equal(done.states[-1].tiles, inst.goal_tiles)


def test_a_schedule_runs_to_the_goal_on_both_brokers(case, tmp_path, broker, caplog):
    inst, _, sched, _, picks, places = case
    caplog.set_level("DEBUG", logger="bille.execute")
    out, journal = start(case, tmp_path, broker)
    # a successful run says nothing alarming: repeats and earlier runs' retained messages are debug
    assert not [r for r in caplog.records if r.name.startswith("bille") and r.levelno >= 30]
    assert out.status == "completed" and out.finished == sched.length
    assert out.worlds_match  # every robot's own world: tiles, pose and load equal the goal's
    assert [out.robot_counters[f"r{i}"]["picks"] for i in range(2)] == picks
    assert [out.robot_counters[f"r{i}"]["places"] for i in range(2)] == places
    assert out.duplicates == out.rejected == 0 and len(out.round_trips) == 2 * sched.length
    assert_journal_sound(journal, inst)


@pytest.mark.slow
def test_a_failed_action_stops_safely_and_the_run_resumes(case, tmp_path, embedded):
    inst = case[0]
    out, journal = start(case, tmp_path, embedded, extra={1: ["--fail-at", "3"]})
    assert out.status == "stopped" and out.finished == 2
    assert [(f.step, f.robot, f.kind) for f in out.faults] == [(3, "r1", "failed")]
    assert replay(journal).finished == 2
    again = session.resume(str(journal), broker=embedded, secrets_path=None, settings=FAST)
    assert again.status == "completed" and again.worlds_match
    assert_journal_sound(journal, inst)


def test_retry_repeats_only_the_failed_robot(case, tmp_path, embedded):
    inst, _, sched, _, picks, _ = case
    out, journal = start(case, tmp_path, embedded, extra={1: ["--fail-at", "3"]}, on_fault="retry")
    assert out.status == "completed" and out.worlds_match and len(out.faults) == 1
    counters = out.robot_counters
    assert counters["r0"]["executed"] == counters["r1"]["executed"] == sched.length
    assert counters["r0"]["duplicates"] == 1  # step 3 released again: r0 had done it, and skips it
    assert [counters[f"r{i}"]["picks"] for i in range(2)] == picks
    assert_journal_sound(journal, inst)


def test_replan_continues_from_the_reported_state(case, tmp_path, embedded):
    inst = case[0]
    out, journal = start(case, tmp_path, embedded, extra={1: ["--fail-at", "3"]}, on_fault="replan")
    assert out.status == "completed" and out.worlds_match
    events = read_events(journal)
    replans = [e for e in events if e["event"] == "replan"]
    assert len(replans) == 1 and replans[0]["step"] == 2
    schedule = load_schedule(replans[0]["schedule"])
    assert schedule.actions[1][0] == "wait"  # the failed robot's step 3 is what happened: nothing
    assert_journal_sound(journal, inst)


@pytest.mark.slow
def test_a_stopped_run_resumes_with_a_new_plan(case, tmp_path, embedded):
    inst = case[0]
    out, journal = start(case, tmp_path, embedded, extra={0: ["--fail-at", "5"], 1: ["--fail-at", "5"]})
    assert out.status == "stopped" and out.finished == 4
    again = session.resume(str(journal), broker=embedded, secrets_path=None, settings=FAST, replan=True)
    assert again.status == "completed" and again.worlds_match
    replans = [e for e in read_events(journal) if e["event"] == "replan"]
    assert [e["step"] for e in replans] == [4]  # nobody did step 5: the new plan starts after step 4
    assert_journal_sound(journal, inst)


@pytest.mark.slow
def test_a_dropped_report_is_recovered_by_a_state_request(case, tmp_path, embedded):
    out, journal = start(case, tmp_path, embedded, extra={0: ["--drop-at", "5"]})
    assert out.status == "completed" and out.worlds_match and not out.faults
    assert out.robot_counters["r0"]["executed"] == case[2].length
    assert_journal_sound(journal, case[0])


@pytest.mark.slow
def test_a_killed_robot_stops_the_run_with_a_report(case, tmp_path, embedded):
    out, journal = start(case, tmp_path, embedded, extra={0: ["--die-at", "4"]})
    assert out.status == "stopped" and out.finished == 3
    fault = out.faults[-1]
    assert (fault.step, fault.robot, fault.kind) == (4, "r0", "lost")
    assert "CONNECTIONBROKEN" in fault.detail
    events = read_events(journal)
    assert max(e["step"] for e in events if e["event"] == "released") == 4  # nothing released after the fault
    again = session.resume(str(journal), broker=embedded, secrets_path=None, settings=FAST)
    assert again.status == "completed" and again.worlds_match


# ---- robots given by id: they outlive the executor -------------------------------------------


def spawn_robots(url: str, secrets: dict[str, str], tmp_path: Path):
    path = tmp_path / "secrets.yaml"
    path.write_text("".join(f"{r}: {s}\n" for r, s in secrets.items()))
    procs = [subprocess.Popen([sys.executable, "-m", "bille.tools.cli", "robot-sim", "--id", r, "--broker", url,
                               "--secrets", str(path)], stdin=subprocess.DEVNULL) for r in secrets]
    return path, procs


def stop_all(procs) -> None:
    for p in procs:
        p.terminate()
    for p in procs:
        p.wait(10)


class Probe:
    """The test as an executor: signed instant actions and orders, state reports read back."""

    def __init__(self, url: str, robot: str, secret: bytes):
        self.robot, self.sealer, self.gate = robot, Sealer(robot, secret), Gate({robot: secret})
        self.reports: list[dict] = []
        self.nonce = "unknown"  # the robot process's, learnt from its first report
        self.client = connect(parse_url(url), f"probe-{robot}", on_message=self._take)
        self.client.subscribe([(topic("default", robot, "state"), 1), (topic("default", robot, "connection"), 1)])

    def _take(self, client, userdata, message):
        _, robot, kind = parse_topic(message.topic)
        msg = self.gate.admit(robot, kind, message.payload)
        if isinstance(msg, dict):
            self.nonce = msg["nonce"]
            if kind == "state":
                self.reports.append(msg)

    def online(self, other_than: str) -> None:
        """Wait for the robot's announcement of a process whose nonce is not ``other_than``."""
        deadline = time.time() + 10
        while self.nonce in ("unknown", other_than):
            assert time.time() < deadline, "the robot did not come online"
            time.sleep(0.05)

    def seal(self, kind: str, body: dict) -> bytes:
        """A message for the robot, tied to its live process."""
        return self.sealer.seal(kind, {"nonce": self.nonce, **body})

    def publish(self, kind: str, payload: bytes) -> None:
        self.client.publish(topic("default", self.robot, kind), payload, qos=1).wait_for_publish(5)

    def state(self) -> dict:
        n = len(self.reports)
        deadline = time.time() + 10
        while time.time() < deadline:
            self.publish("instantActions", self.seal("instantActions", {"actions": [
                {"actionId": f"q{n}", "actionType": "stateRequest", "parameters": {}}]}))
            for _ in range(40):
                replies = [r for r in self.reports[n:] if r["replyTo"] == f"q{n}"]
                if replies:
                    return replies[-1]
                time.sleep(0.05)
        raise AssertionError("the robot did not answer")


@pytest.mark.slow
def test_a_killed_executor_resumes_without_repeating_a_pick_or_place(case, tmp_path, embedded):
    inst, ip, sched, sp, picks, places = case
    secrets = {"left": "k-left-0123", "right": "k-right-4567"}
    path, procs = spawn_robots(embedded, secrets, tmp_path)
    journal = tmp_path / "crash.journal.jsonl"
    try:
        cmd = [sys.executable, "-m", "bille.tools.cli", "run", ip, sp, "--broker", embedded, "--robots", "left,right",
               "--secrets", str(path), "--journal", str(journal), "--sim-delay", "0"]
        executor = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.time() + 60
        while time.time() < deadline:  # kill it mid-run, after a pick
            if journal.exists() and journal.read_text().count('"finished"') >= 30:
                break
            time.sleep(0.02)
        executor.send_signal(signal.SIGKILL)
        executor.wait(10)
        assert not replay(journal).done
        out = session.resume(str(journal), broker=None, secrets_path=None, settings=FAST)
        assert out.status == "completed" and out.worlds_match
        assert_journal_sound(journal, inst)
        for i, r in enumerate(secrets):  # the same robot processes all along: their counts are the run's
            counters = out.robot_counters[r]
            assert (counters["picks"], counters["places"]) == (picks[i], places[i])
            assert counters["executed"] == sched.length
    finally:
        stop_all(procs)


def test_forged_and_replayed_messages_are_rejected(case, tmp_path, embedded):
    inst, ip, sched, sp, _, _ = case
    secret = "robot-secret-99"
    _, procs = spawn_robots(embedded, {"solo": secret}, tmp_path)
    try:
        probe = Probe(embedded, "solo", secret.encode())
        assert not probe.state()["initialized"]  # up, and waiting for its world
        single = load_instance(ip)
        text = Path(ip).read_text()
        tiles = [[int(c) % single.width, int(c) // single.width] for c in np.flatnonzero(single.start.tiles)]
        r = single.robots[0]
        init = {"instance": text, "index": 0, "lastStep": 0, "carrying": False, "tiles": tiles,
                "pose": {"front": list(r.front), "back": list(r.back)}}
        probe.publish("instantActions", probe.seal("instantActions", {"actions": [
            {"actionId": "init", "actionType": "initialize", "parameters": init}]}))
        assert probe.state()["initialized"]
        step = {"sequenceId": 1, "action": sched.actions[0][0], "released": True, "structure": {"picked": [], "placed": []}}
        order = probe.seal("order", {"orderId": "o", "orderUpdateId": 1, "steps": [step]})
        probe.publish("order", order)
        probe.publish("order", order)  # replayed: the same bytes again
        forger = Sealer("solo", b"not-the-secret")
        step2 = dict(step, sequenceId=2, action=sched.actions[0][1])
        probe.publish("order", forger.seal("order", {"nonce": probe.nonce, "orderId": "o", "orderUpdateId": 2,
                                                     "steps": [step2]}))
        tampered = json.loads(probe.seal("order", {"orderId": "o", "orderUpdateId": 3, "steps": [step2]}))
        tampered["steps"][0]["action"] = "wait"
        probe.publish("order", json.dumps(tampered).encode())
        probe.publish("order", b"{not json")
        state = probe.state()
        assert state["lastStep"] == 1 and state["counters"]["executed"] == 1
        assert state["counters"]["duplicates"] == 1 and state["counters"]["rejected"] == 3
        probe.client.disconnect()
    finally:
        stop_all(procs)


@pytest.mark.slow
def test_a_restarted_robot_ignores_the_orders_of_its_earlier_process(case, tmp_path, embedded):
    # the earlier process's signed initialize and step-1 order, replayed to a fresh process of the
    # same robot with no executor running: refused, and the robot does not move
    inst, ip, sched, sp, _, _ = case
    secret = "robot-secret-7"
    single = load_instance(ip)
    tiles = [[int(c) % single.width, int(c) // single.width] for c in np.flatnonzero(single.start.tiles)]
    r = single.robots[0]
    init = {"instance": Path(ip).read_text(), "index": 0, "lastStep": 0, "carrying": False, "tiles": tiles,
            "pose": {"front": list(r.front), "back": list(r.back)}}
    step = {"sequenceId": 1, "action": sched.actions[0][0], "released": True, "structure": {"picked": [], "placed": []}}
    _, procs = spawn_robots(embedded, {"solo": secret}, tmp_path)
    try:
        probe = Probe(embedded, "solo", secret.encode())
        first_nonce = probe.state()["nonce"]
        recorded = [("instantActions", probe.seal("instantActions", {"actions": [
            {"actionId": "init", "actionType": "initialize", "parameters": init}]})),
            ("order", probe.seal("order", {"orderId": "o", "orderUpdateId": 1, "steps": [step]}))]
        for kind, payload in recorded:
            probe.publish(kind, payload)
        assert probe.state()["lastStep"] == 1  # the live process acted on them
        probe.client.disconnect()
    finally:
        stop_all(procs)
    _, procs = spawn_robots(embedded, {"solo": secret}, tmp_path)
    try:
        probe = Probe(embedded, "solo", secret.encode())
        probe.online(other_than=first_nonce)  # up, and nothing sent to it yet
        for kind, payload in recorded:
            probe.publish(kind, payload)
        after = probe.state()
        assert after["nonce"] != first_nonce
        assert not after["initialized"] and after["lastStep"] == 0 and after["pose"] is None
        assert after["counters"]["rejected"] == 2 and after["counters"]["executed"] == 0
        probe.client.disconnect()
    finally:
        stop_all(procs)


# ---- the protocol's gate, message by message --------------------------------------------------


def test_the_gate_admits_each_signed_message_once():
    secret = b"s"
    sealer, gate = Sealer("r", secret), Gate({"r": secret})
    first = sealer.seal("connection", {"nonce": "n", "connectionState": "ONLINE"})
    assert isinstance(gate.admit("r", "connection", first), dict)
    again = gate.admit("r", "connection", first)
    assert again.duplicate and "not above" in again.reason
    later = sealer.seal("connection", {"nonce": "n", "connectionState": "OFFLINE"})
    assert gate.admit("r", "connection", later)["connectionState"] == "OFFLINE"
    # a message of an older session (a replay from an earlier run) is refused
    old = Sealer("r", secret, session="0ld")
    stale = json.loads(old.seal("connection", {"nonce": "n", "connectionState": "ONLINE"}))
    stale["timestamp"] = "2000-01-01T00:00:00.000Z"
    stale.pop("signature")
    from bille.tools.execute.protocol import canonical, sign
    stale["signature"] = sign(stale, secret)
    assert gate.admit("r", "connection", canonical(stale)).duplicate
    assert gate.duplicates == 2 and gate.rejected == 0


@pytest.mark.parametrize("payload, reason", [
    (b"\xff", "not JSON"),
    (b"[1]", "not a JSON object"),
    (b'{"headerId": 1}', "no signature"),
])
def test_the_gate_rejects_malformed_messages(payload, reason):
    gate = Gate({"r": b"s"})
    out = gate.admit("r", "state", payload)
    assert out.reason == reason and gate.rejected == 1


def test_the_gate_rejects_forgery_schema_breaks_and_strangers():
    from bille.tools.execute.protocol import canonical, sign

    gate = Gate({"r": b"s", "q": b"t"})
    good = json.loads(Sealer("r", b"s").seal("connection", {"nonce": "n", "connectionState": "ONLINE"}))
    forged = dict(good, signature=sign({k: v for k, v in good.items() if k != "signature"}, b"x"))
    assert gate.admit("r", "connection", canonical(forged)).reason == "bad signature"
    body = {k: v for k, v in good.items() if k != "signature"}
    body["connectionState"] = "SLEEPY"
    bad = canonical({**body, "signature": sign(body, b"s")})
    assert gate.admit("r", "connection", bad).reason.startswith("schema: connectionState")
    assert gate.admit("x", "connection", canonical(good)).reason == "unknown robot id"
    other = Sealer("r", b"t").seal("connection", {"nonce": "n", "connectionState": "ONLINE"})  # on q's topic
    assert "names robot 'r'" in gate.admit("q", "connection", other).reason
    with pytest.raises(ValueError, match="schema"):
        Sealer("r", b"s").seal("state", {"lastStep": -1})


def test_tile_digest_is_order_free():
    assert tiles_digest([(1, 0), (0, 1)]) == tiles_digest([(0, 1), (1, 0)]) != tiles_digest([(0, 1)])


# ---- bad input: one line, exit 2, nothing written ---------------------------------------------


def bille(*args, cwd):
    return subprocess.run([sys.executable, "-m", "bille.tools.cli", *args], capture_output=True, text=True, cwd=cwd,
                          timeout=120)


@pytest.mark.parametrize("args, message", [
    (["--broker", "mqtt://127.0.0.1:9"], "cannot reach the broker at mqtt://127.0.0.1:9"),
    (["--broker", "http://x"], "is not a broker URL"),
    (["--robots", "sim:3"], "sim:3, but the schedule has 2 robots"),
    (["--robots", "a,b"], "need their shared secrets"),
    (["--robots", "a,a"], "a robot id is repeated"),
    (["--replan-method", "magic"], "unknown method 'magic'"),
])
def test_bad_run_options_exit_2_and_leave_no_journal(tmp_path, args, message):
    out = bille("run", MAP, f"{MAP}.schedule", "--journal", "j.jsonl", *args, cwd=tmp_path)
    assert out.returncode == 2, out.stderr
    assert message in out.stderr and out.stderr.count("\n") == 1 and "Traceback" not in out.stderr
    assert not (tmp_path / "j.jsonl").exists()


def test_a_schedule_of_another_instance_is_refused(tmp_path):
    out = bille("run", MAP, "lt-5.schedule", cwd=tmp_path)
    assert out.returncode == 2 and "3 robots, but instance 'lt-4' has 2" in out.stderr


def test_robots_that_do_not_answer_are_named(tmp_path, embedded):
    (tmp_path / "s.yaml").write_text("ghost: a\nshade: b\n")
    out = bille("run", MAP, f"{MAP}.schedule", "--broker", embedded, "--robots", "ghost,shade", "--secrets", "s.yaml",
                "--connect-timeout", "1", "--journal", "j.jsonl", cwd=tmp_path)
    assert out.returncode == 2 and "robots ghost, shade did not answer within 1 s" in out.stderr
    assert not (tmp_path / "j.jsonl").exists()


@pytest.mark.slow
def test_the_command_line_runs_and_resumes_a_stopped_run(tmp_path):
    out = bille("run", MAP, f"{MAP}.schedule", "--journal", "j.jsonl", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    assert summary["status"] == "completed" and summary["worlds_match_goal"] and summary["steps_per_second"] > 0
    again = bille("run", "--resume", "j.jsonl", cwd=tmp_path)
    assert again.returncode == 0 and "is finished (all 74 steps); nothing to resume" in again.stdout


def test_the_documented_messages_validate_and_their_signatures_verify():
    import re

    doc = (Path(__file__).parent.parent / "docs" / "execution.md").read_text()
    blocks = re.findall(r"```json (\w+)\n(.*?)```", doc, re.S)
    assert sorted(kind for kind, _ in blocks) == sorted(["order", "instantActions", "state", "connection"])
    for kind, text in blocks:
        msg = json.loads(text)
        gate = Gate({msg["robot"]: b"example-secret"})
        assert isinstance(gate.admit(msg["robot"], kind, text.encode()), dict), kind


@pytest.mark.slow
def test_a_journal_line_cut_by_a_crash_is_dropped_before_appending(case, tmp_path, embedded):
    inst = case[0]
    out, journal = start(case, tmp_path, embedded, extra={0: ["--fail-at", "6"]})
    assert out.status == "stopped"
    with open(journal, "a") as f:
        f.write('{"event": "finished", "st')  # the executor died while writing
    assert replay(journal).finished == 5
    again = session.resume(str(journal), broker=embedded, secrets_path=None, settings=FAST)
    assert again.status == "completed"
    assert_journal_sound(journal, inst)


@pytest.mark.slow
def test_point_robots_run_too(tmp_path, embedded):
    ip, sp = str(resolve("point-4")), str(resolve("point-4.schedule"))
    inst, sched = load_instance(ip), load_schedule(sp)
    out = session.start(inst, ip, sched, sp, broker=embedded, robots="sim", secrets_path=None,
                        journal_path=str(tmp_path / "p.jsonl"), settings=FAST)
    assert out.status == "completed" and out.worlds_match and out.finished == sched.length


def test_robot_sim_says_what_it_serves(tmp_path):
    path = tmp_path / "secrets.yaml"
    path.write_text("left: s3cret\n")
    proc = subprocess.Popen([sys.executable, "-m", "bille.tools.cli", "robot-sim", "--id", "left", "--broker",
                             "mqtt://127.0.0.1:1", "--secrets", str(path)], stdin=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    try:
        first = proc.stderr.readline()
    finally:
        proc.kill()
        proc.wait(10)
        proc.stderr.close()
    assert "robot 'left'" in first and "mqtt://127.0.0.1:1" in first


def test_bench_execute_reports_a_fleet_that_is_not_up_in_time_as_a_row(cli, capsys):
    # robots cannot start within 0.1 s: a result of this machine (exit 1), not bad input (exit 2)
    assert cli(["bench", "execute", "--robots", "2", "--steps", "2", "--connect-timeout", "0.1",
                "--step-timeout", "5"]) == 1
    rows = capsys.readouterr().out.splitlines()[2:]
    assert [r.split()[:3] for r in rows] == [["1", "not", "measured:"], ["2", "not", "measured:"]]
    assert "did not answer within 0.1 s" in rows[0]


@pytest.mark.slow
def test_a_run_interrupted_says_the_step_reached_and_how_to_resume(tmp_path):
    # it said only "interrupted"
    journal = tmp_path / "run.journal.jsonl"
    bille = Path(sys.executable).parent / "bille"
    child = subprocess.Popen([str(bille), "run", "reconfig-30", "reconfig-30.schedule", "--sim-delay", "700",
                              "--journal", str(journal)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (journal.exists() and '"finished"' in journal.read_text()):
        time.sleep(0.1)
    os.killpg(child.pid, signal.SIGINT)
    _, err = child.communicate(timeout=60)
    assert child.returncode == 130 and "Traceback" not in err
    assert f"continue with: bille run --resume {journal}" in err and "interrupted after step " in err
