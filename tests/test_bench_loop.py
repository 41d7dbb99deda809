"""bille bench loop-schedules: the loop's fingerprints saved, then compared (a change shows)."""
import json

from bille.tools.cli import main


def _run(argv, capsys):
    try:
        main(argv)
    except SystemExit as done:
        captured = capsys.readouterr()
        return done.code, captured.out + captured.err
    raise AssertionError("main() returns through sys.exit")


def test_fingerprints_saved_then_compared(tmp_path, capsys):
    saved = tmp_path / "before.json"
    code, _ = _run(["bench", "loop-schedules", "--only", "corridor-2", "--save", str(saved)], capsys)
    runs = json.loads(saved.read_text())
    assert code == 0 and len(runs) == 8 and all(r["status"] == "feasible" for r in runs.values())
    code, out = _run(["bench", "loop-schedules", "--only", "corridor-2", "--compare", str(saved)], capsys)
    assert code == 0 and "8 of 8 runs identical" in out
    key = sorted(runs)[0]
    runs[key]["schedule"] = "0" * 16  # as if the code had changed that run's schedule
    changed = tmp_path / "changed.json"
    changed.write_text(json.dumps(runs))
    code, out = _run(["bench", "loop-schedules", "--only", "corridor-2", "--compare", str(changed)], capsys)
    assert code == 1 and f"DIFFERS {key}" in out and "7 of 8 runs identical" in out


def test_a_file_that_is_not_fingerprints_is_one_line_and_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]")
    code, out = _run(["bench", "loop-schedules", "--compare", str(bad)], capsys)
    assert code == 2 and "not a fingerprint file" in out and "Traceback" not in out
