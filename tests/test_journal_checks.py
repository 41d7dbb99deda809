"""A journal is checked before it is trusted: ``bille run --resume`` refuses, with one line naming
the line and what is wrong (exit 2, nothing sent to a robot), any journal an executor cannot have
written; with a fleet secret every line is signed and a changed line is detected."""
from __future__ import annotations

import json

import pytest

from bille.instances.bundled import bundled_path
from bille.tools.execute.journal import SECRET_ENV, Journal, replay, sha256_file

MAP = "lt-4"  # 74 steps


def write_journal(path, *, finished: int, fault: bool = True, done: bool = False, secret: bytes | None = None):
    """A journal as the executor writes it: ``finished`` steps released and finished, then a
    fault of the next step (or ``done``)."""
    inst, sched = bundled_path(MAP), bundled_path(f"{MAP}.schedule")
    j = Journal(path, secret=secret)
    j.write("run", instance=str(inst), instance_sha256=sha256_file(inst), schedule=str(sched),
            schedule_sha256=sha256_file(sched), fleet="default", robots=["r0", "r1"], simulated=True, broker=None,
            secrets=None, steps=74)
    for k in range(1, finished + 1):
        j.write("released", step=k)
        j.write("finished", step=k)
    if fault:
        j.write("released", step=finished + 1)
        j.write("fault", step=finished + 1, robot="r1", kind="failed", detail="injected failure")
    if done:
        j.write("done", step=74)
    j.close()
    return path


def edit(path, fn):
    lines = path.read_text().splitlines()
    fn(lines)
    path.write_text("\n".join(lines) + "\n")


def test_a_sound_journal_replays(tmp_path):
    j = write_journal(tmp_path / "j.jsonl", finished=47)
    done = replay(j)
    assert (done.finished, done.released, done.done) == (47, 48, False)


def set_last(event: dict):
    return lambda lines: lines.__setitem__(-1, json.dumps(event))


@pytest.mark.parametrize("change, message", [
    # the run said completed 74 of 74 though steps 48-70 never ran
    (set_last({"event": "finished", "step": 70}), "step 70 finished, but step 47 was the last finished"),
    (set_last({"event": "finished", "step": 500}), "step 500 is outside the plan (steps 1 to 74)"),
    (set_last({"event": "finished", "step": -3}), "step -3 is outside the plan"),
    (lambda lines: lines.__setitem__(-1, '{"event": "finished", "step": NaN}'), "not a journal line"),
    (set_last({"event": "finished", "step": 47.5}), "field 'step': expected a whole number"),
    (set_last({"event": "finished", "step": True}), "field 'step': expected a whole number"),
    (set_last({"event": "finished", "step": 47}), "step 47 finished, but step 47 was the last finished"),
    (set_last({"event": "released", "step": 60}),
     "step 60 released after step 47 finished"),
    (set_last({"event": "done", "step": 74}), "'done' at step 74, but 47 of the plan's 74 steps finished"),
    (set_last({"event": "teleport", "step": 48}), "not a journal event"),
    (set_last({"event": "run"}), "a second 'run' event"),
    (set_last({"event": "resume", "finished": 60, "released": 61}), "'resume' says finished 60"),
    (set_last({"event": "replan", "step": 30, "schedule": "x", "schedule_sha256": "y"}),
     "'replan' after step 30, but step 47 is the last finished"),
    (lambda lines: lines.__setitem__(0, lines[0].replace('"steps": 74', '"steps": 90')), "the run has 90 steps"),
    (lambda lines: lines.__setitem__(0, lines[0].replace('"simulated": true', '"simulated": 1')),
     "field 'simulated': expected bool"),
])
def test_a_journal_an_executor_cannot_have_written_is_refused(tmp_path, rejects, change, message):
    j = write_journal(tmp_path / "j.jsonl", finished=47)
    edit(j, change)
    rejects(["run", "--resume", j], message)


def test_events_after_done_are_refused(tmp_path, rejects):
    j = write_journal(tmp_path / "j.jsonl", finished=74, fault=False, done=True)
    edit(j, lambda lines: lines.append(json.dumps({"event": "released", "step": 74})))
    rejects(["run", "--resume", j], "'released' after 'done'")


def test_a_finished_run_resumed_says_so_and_exits_0(tmp_path, cli, capsys):
    j = write_journal(tmp_path / "j.jsonl", finished=74, fault=False, done=True)
    before = j.read_text()
    capsys.readouterr()
    assert cli(["run", "--resume", j]) == 0
    out = capsys.readouterr().out
    assert "finished (all 74 steps); nothing to resume" in out
    assert cli(["run", "--resume", j, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["status"] == "completed"
    assert j.read_text() == before  # nothing appended


SECRET = b"fleet-secret"


def test_signed_journal_replays_with_its_secret(tmp_path, monkeypatch):
    j = write_journal(tmp_path / "j.jsonl", finished=47, secret=SECRET)
    assert all("signature" in json.loads(line) for line in j.read_text().splitlines())
    monkeypatch.setenv(SECRET_ENV, SECRET.decode())
    assert replay(j).finished == 47


@pytest.mark.parametrize("change, message", [
    (lambda lines: lines.__setitem__(5, lines[5].replace('"step": 3', '"step": 30')), ":6: bad signature"),
    (lambda lines: lines.pop(5), ":6: bad signature"),  # a line removed: the chain breaks at the next
    (lambda lines: lines.insert(3, lines.pop(4)), ":4: bad signature"),
    (lambda lines: lines.__setitem__(2, json.dumps({k: v for k, v in json.loads(lines[2]).items() if k != "signature"})),
     ":3: the line is not signed"),
])
def test_a_changed_signed_line_is_detected(tmp_path, rejects, monkeypatch, change, message):
    j = write_journal(tmp_path / "j.jsonl", finished=47, secret=SECRET)
    edit(j, change)
    monkeypatch.setenv(SECRET_ENV, SECRET.decode())
    rejects(["run", "--resume", j], message)


def test_signatures_need_the_right_secret(tmp_path, rejects, monkeypatch):
    signed = write_journal(tmp_path / "s.jsonl", finished=5, secret=SECRET)
    plain = write_journal(tmp_path / "p.jsonl", finished=5)
    monkeypatch.delenv(SECRET_ENV, raising=False)
    rejects(["run", "--resume", signed], f"the journal is signed: set {SECRET_ENV}")
    monkeypatch.setenv(SECRET_ENV, "another")
    rejects(["run", "--resume", signed], ":1: bad signature")
    rejects(["run", "--resume", plain], ":1: the line is not signed, but a fleet secret is set")


def test_a_crash_cut_line_is_still_an_event_that_never_happened(tmp_path, monkeypatch):
    j = write_journal(tmp_path / "j.jsonl", finished=47, secret=SECRET)
    with open(j, "a") as f:
        f.write('{"event": "finished", "st')
    monkeypatch.setenv(SECRET_ENV, SECRET.decode())
    assert replay(j).finished == 47


def test_lines_appended_on_resume_continue_the_chain(tmp_path, monkeypatch):
    j = write_journal(tmp_path / "j.jsonl", finished=47, secret=SECRET)
    monkeypatch.setenv(SECRET_ENV, SECRET.decode())
    done = replay(j)
    more = Journal(j, append=True, secret=SECRET, previous=done.signature)
    more.write("resume", finished=47, released=48)
    more.write("released", step=48)
    more.write("finished", step=48)
    more.close()
    assert replay(j).finished == 48
