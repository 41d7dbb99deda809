"""A schedule names the instance it was made for: written with it, checked on use."""
from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.schedule import dump_schedule, load_schedule, schedule_from_text, written_for
from bille.solvers import solve


def test_a_solved_schedule_records_its_instance_and_reads_back():
    inst = load_instance(bundled_path("compare-2"))
    text = dump_schedule(solve(inst, "astar").schedule)
    assert text.startswith("instance: {name: compare-2, sha256: ")
    again = schedule_from_text(text, "s.yaml")
    assert again.instance["name"] == "compare-2" and written_for(inst, again) is None
    other = load_instance(bundled_path("compare-3"))
    assert written_for(other, again) == "s.yaml was written for 'compare-2', not 'compare-3'"


def test_the_same_instance_renamed_or_rewritten_is_the_same(tmp_path):
    inst = load_instance(bundled_path("compare-2"))
    copy = tmp_path / "mine.yaml"
    copy.write_text("# my copy\n" + bundled_path("compare-2").read_text())
    schedule = schedule_from_text(dump_schedule(solve(inst, "astar").schedule))
    assert written_for(load_instance(copy), schedule) is None


def test_check_warns_of_a_schedule_for_another_instance(cli, capsys, tmp_path):
    out = tmp_path / "c2.yaml"
    assert cli(["solve", "compare-2", "-m", "astar", "-o", out]) == 0
    capsys.readouterr()
    assert cli(["check", "compare-2", out]) == 0
    assert "warning" not in capsys.readouterr().err
    cli(["check", "compare-3", out])
    err = capsys.readouterr().err
    assert f"warning: {out} was written for 'compare-2', not 'compare-3'" in err


def test_run_refuses_a_schedule_for_another_instance(cli, capsys, tmp_path):
    out = tmp_path / "c2.yaml"
    assert cli(["solve", "compare-2", "-m", "astar", "-o", out]) == 0
    capsys.readouterr()
    assert cli(["run", "compare-3", out, "--journal", tmp_path / "j.jsonl"]) == 2
    err = capsys.readouterr().err
    assert "written for 'compare-2', not 'compare-3'; --force to run it anyway" in err
    assert not (tmp_path / "j.jsonl").exists()


def test_an_old_output_file_is_left_and_the_command_says_so(cli, capsys, tmp_path):
    out = tmp_path / "x.yaml"
    out.write_text("robots: []\n")
    # one robot walled off from its goal in a closed world: no schedule
    inst = tmp_path / "walled.yaml"
    inst.write_text("name: walled\nmoveset: S5\ngrid: |\n  TTTT\nrobots: [{front: [1, 0], back: [0, 0]}]\n"
                    "robot_goals: [[0, 0]]\n")
    assert cli(["solve", inst, "-m", "cbs", "-o", out]) == 1
    assert f"no schedule: {out} left as it was, not written by this run" in capsys.readouterr().err
    assert out.read_text() == "robots: []\n"
    assert load_schedule(out).instance is None


def test_a_renamed_copy_or_new_notes_are_the_same_instance():
    import dataclasses

    inst = load_instance(bundled_path("compare-2"))
    schedule = schedule_from_text(dump_schedule(solve(inst, "astar").schedule))
    renamed = dataclasses.replace(inst, name="mine", meta={"note": "a copy"})
    assert written_for(renamed, schedule) is None


def test_a_malformed_digest_is_one_clear_error():
    import pytest

    from bille.instances import ScheduleError

    with pytest.raises(ScheduleError, match="sha256: expected hexadecimal digits"):
        schedule_from_text("instance: {name: x, sha256: 'ab}, x: y'}\nrobots: [[wait]]\n", "s.yaml")
