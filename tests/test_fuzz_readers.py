"""Every reader answers any input with a result or one BilleError: never another exception, and
never a search or an allocation that sizes were not checked for first.

One fuzzer per reader (instance YAML, schedule YAML, libMultiRobotPlanning, MovingAI, sweep
files, journals, robot messages) mutates valid files (``fuzzing.mutated``). CI runs a few hundred
examples of each, the ``slow`` test four times as many (about half a minute in all).
``BILLE_FUZZ_REPORT=FILE`` appends each fuzzer's count of inputs read and refused, by the start
of the refusal's message.
"""
from __future__ import annotations

import atexit
import collections
import json
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings

from bille.instances import BilleError, instance_from_text, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.interop import from_mrp, schedule_from_mrp
from bille.instances.yamlsource import load_yaml_text
from bille.solvers import bind, schedule_from_text, validate
from fuzzing import mutated, mutated_json
from test_interop import MRP

SMALL = ["corridor-2", "point-4", "compare-2"]
INSTANCES = [bundled_path(n).read_text() for n in SMALL]
SCHEDULES = [bundled_path(f"{n}.schedule").read_text() for n in SMALL]
LOADED = {n: load_instance(bundled_path(n)) for n in SMALL}
PLAN = """statistics: {cost: 4, makespan: 2}
schedule:
  agent0:
    - {x: 0, y: 0, t: 0}
    - {x: 1, y: 0, t: 1}
    - {x: 2, y: 0, t: 2}
  agent1:
    - {x: 4, y: 2, t: 0}
    - {x: 3, y: 2, t: 1}
"""
MRP_INSTANCE = from_mrp(load_yaml_text(MRP, "i.mrp.yaml", BilleError)[0], "i")
MAP = "type octile\nheight 3\nwidth 5\nmap\n.....\n.@.@.\n.....\n"
SCEN = "version 1\n1\tm.map\t5\t3\t0\t0\t4\t2\t6.00000000\n0\tm.map\t5\t3\t2\t1\t2\t0\t1.00000000\n"
SWEEPS = [
    "name: fuzz\ntime_limit: 5\nmemory_limit: 500\nmax_runs: 20\ninstances:\n  - corridor-2\n  - {instance: point-4, "
    "moveset: point}\nmethods:\n  temporal-astar: {horizon: [2, 5], epsilon: 1}\n  mstar: {}\n",
    "instances: [{gen: 'corridor --length 2 --robots 1 --seed 0..1'}, crowded-2]\nmethods: {lacam: {improve: 0}}\n",
]

OUTCOMES: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)


def answer(reader: str, read) -> None:
    """Run one read; a result or a BilleError of one line is an answer, anything else fails."""
    try:
        read()
    except BilleError as exc:
        message = str(exc)
        assert message and "\n" not in message.strip(), message
        OUTCOMES[reader]["refused: " + " ".join(message.split(": ")[-1].split()[:3])] += 1
        return
    OUTCOMES[reader]["read"] += 1


# ---- one check per reader ---------------------------------------------------------------------


def read_instance(text: str) -> None:
    answer("instance YAML", lambda: instance_from_text(text, "fuzz.yaml"))


def read_schedule(text: str) -> None:
    def go():
        sched = schedule_from_text(text, "fuzz.schedule.yaml")
        for inst in LOADED.values():
            try:
                bind(inst, sched)
            except BilleError:
                continue
            validate(inst, sched)
    answer("schedule YAML", go)


def read_mrp(text: str) -> None:
    def go():
        data, src = load_yaml_text(text, "fuzz.mrp.yaml", BilleError)
        if isinstance(data, dict) and "schedule" in data:
            validate(MRP_INSTANCE, schedule_from_mrp(MRP_INSTANCE, data, src))
        else:
            from_mrp(data, "fuzz", src)
    answer("libMultiRobotPlanning", go)


def read_movingai(pair: tuple[str, str]) -> None:
    from bille.instances.generators.movingai import from_movingai

    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "m.map").write_text(pair[0], encoding="utf-8", errors="surrogatepass")
        (Path(tmp) / "m.scen").write_text(pair[1], encoding="utf-8", errors="surrogatepass")
        answer("MovingAI", lambda: from_movingai(Path(tmp) / "m.map", Path(tmp) / "m.scen", agents=None))


def read_sweep(text: str) -> None:
    from bille.tools.sweep.spec import load_spec

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "fuzz.yaml"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        answer("sweep files", lambda: load_spec(path))


JOURNAL_TMP = tempfile.mkdtemp(prefix="bille-fuzz-")
atexit.register(shutil.rmtree, JOURNAL_TMP, ignore_errors=True)  # made on import: removed at exit


def _journal_seed() -> str:
    from test_journal_checks import write_journal

    path = Path(JOURNAL_TMP) / "seed.jsonl"
    if not path.exists():
        write_journal(path, finished=5)
    return path.read_text()


def _journal_lines():
    """The seed journal with one of its lines changed as JSON."""
    from hypothesis import strategies as st

    lines = _journal_seed().splitlines()

    @st.composite
    def one(draw):
        k = draw(st.integers(0, len(lines) - 1))
        line = json.dumps(draw(mutated_json(json.loads(lines[k]))))
        return "\n".join(lines[:k] + [line] + lines[k + 1:]) + "\n"
    return one()


def read_journal(text: str) -> None:
    from bille.tools.execute.journal import replay

    path = Path(JOURNAL_TMP) / "fuzz.jsonl"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    answer("journals", lambda: replay(path))


SECRET = b"fuzz-secret"
NONCE = "9f2c41d07be35a68c1e0f4b2d6a87e31"


def _messages() -> list[str]:
    """The documentation's example messages, and an order that places a tile at step 13 of
    corridor-2 (the robot is initialized after step 12), so that mutations reach execution."""
    import re

    from bille.tools.execute.protocol import Sealer

    doc = (Path(__file__).parent.parent / "docs" / "execution.md").read_text()
    examples = [text for _, text in re.findall(r"```json (\w+)\n(.*?)```", doc, re.S)]
    steps = [{"sequenceId": 13, "action": "place", "released": True, "structure": {"picked": [], "placed": [[0, 1]]}},
             {"sequenceId": 14, "action": "wait", "released": False, "structure": {"picked": [], "placed": []}}]
    order = Sealer("r1", SECRET, session="0" * 16).seal("order", {"nonce": NONCE, "orderId": "f" * 16,
                                                                   "orderUpdateId": 1, "steps": steps}, header_id=2)
    return examples + [json.dumps(json.loads(order), indent=1)]


def _initialize() -> bytes:
    from bille.instances.rules import run
    from bille.tools.execute.protocol import Sealer, pose_json, tile_cells

    inst = LOADED["corridor-2"]
    plan = bind(inst, schedule_from_text(SCHEDULES[0]))
    state = list(run(inst.world, inst.start_state, plan[:, :12]))[-1]
    params = {"instance": INSTANCES[0], "index": 1, "pose": pose_json(inst.world.graphs[1], state.poses[1]),
              "carrying": bool(state.carrying[1]), "tiles": tile_cells(state.tiles, inst.width), "lastStep": 12}
    return Sealer("r1", SECRET, session="0" * 16).seal("instantActions", {
        "nonce": NONCE, "actions": [{"actionId": "init", "actionType": "initialize", "parameters": params}]},
        header_id=1)


class _Client:
    def publish(self, *args, **kwargs):
        return None


def read_message(text: str, resign: bool) -> None:
    """The message on every topic: the executor's gate, and the simulated robot's handling of
    orders and instant actions (re-signed with its secret now and then, so that it gets past the
    signature to the schema and the robot's own checks)."""
    from bille.tools.execute.broker import BrokerURL
    from bille.tools.execute.protocol import Gate, Rejection, sign
    from bille.tools.execute.robot import SimRobot

    payload = text.encode("utf-8", "surrogatepass")
    try:
        msg = json.loads(text)
    except ValueError:
        msg = None
    if resign and isinstance(msg, dict):
        msg.pop("signature", None)
        msg["signature"] = sign(msg, SECRET)
        payload = json.dumps(msg).encode()
    for kind in ("order", "instantActions", "state", "connection"):
        out = Gate({"r1": SECRET}).admit("r1", kind, payload)
        OUTCOMES["robot messages"]["gate: " + (" ".join(out.reason.split()[:2]) if isinstance(out, Rejection)
                                               else f"admitted {kind}")] += 1
    robot = SimRobot("r1", BrokerURL("127.0.0.1", 1), SECRET)
    robot.client, robot.nonce = _Client(), NONCE
    robot.handle("bille/v1/default/r1/instantActions", INITIALIZE)
    assert robot.last_step == 12 and not robot.errors
    for kind in ("order", "instantActions"):
        robot.handle(f"bille/v1/default/r1/{kind}", payload)
        said = robot.errors[0]["errorType"] if robot.errors else f"executed to step {robot.last_step}"
        OUTCOMES["robot messages"][f"robot ({kind}): {said}"] += 1


INITIALIZE = _initialize()


# ---- the fuzzers ------------------------------------------------------------------------------


def fuzzers():
    from hypothesis import strategies as st

    return {
        "instance YAML": (mutated(INSTANCES), read_instance),
        "schedule YAML": (mutated(SCHEDULES), read_schedule),
        "libMultiRobotPlanning": (mutated([MRP, PLAN]), read_mrp),
        "MovingAI": (st.tuples(mutated([MAP]), mutated([SCEN])), read_movingai),
        "sweep files": (mutated(SWEEPS), read_sweep),
        "journals": (st.one_of(mutated([_journal_seed()]), _journal_lines()), read_journal),
        "robot messages": (st.tuples(st.one_of(
            mutated(_messages()),
            st.sampled_from([json.loads(m) for m in _messages()]).flatmap(mutated_json).map(json.dumps),
            mutated_json(json.loads(_messages()[-1])["steps"]).map(
                lambda steps: json.dumps({**json.loads(_messages()[-1]), "steps": steps}))),
            st.sampled_from([True, True, True, False])),
            lambda m: read_message(*m)),
    }


CI_EXAMPLES = {"instance YAML": 200, "schedule YAML": 200, "libMultiRobotPlanning": 200, "MovingAI": 200,
               "sweep files": 100, "journals": 150, "robot messages": 150}


def run_fuzzer(name: str, examples: int) -> None:
    strategy, check = fuzzers()[name]
    OUTCOMES.pop(name, None)
    settings(max_examples=examples, database=None)(given(strategy)(check))()
    report = os.environ.get("BILLE_FUZZ_REPORT")
    if report:
        with open(report, "a") as f:
            f.write(json.dumps({"reader": name, "examples": examples, "outcomes": dict(OUTCOMES[name])}) + "\n")


@pytest.mark.parametrize("name", list(CI_EXAMPLES))
def test_fuzz(name):
    run_fuzzer(name, CI_EXAMPLES[name])


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CI_EXAMPLES))
def test_fuzz_thoroughly(name):
    run_fuzzer(name, 4 * CI_EXAMPLES[name])
