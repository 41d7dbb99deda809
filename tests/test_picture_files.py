"""Pictures are written in the format their file name asks for, and schedules compared in one
picture get one row each."""
from __future__ import annotations

import pytest

from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.solvers import load_schedule
from bille.tools.pictures import MAX_ROW_PX, save_png
from bille.tools.trace import trace

MAGIC = {"png": b"\x89PNG", "jpg": b"\xff\xd8\xff", "jpeg": b"\xff\xd8\xff", "pdf": b"%PDF", "svg": b"<?xml",
         "tif": b"II*\x00"}


@pytest.mark.parametrize("suffix", list(MAGIC))
def test_the_suffix_names_the_format(tmp_path, cli, suffix):
    out = tmp_path / f"out.{suffix}"
    assert cli(["view", "corridor-2", "corridor-2.schedule", "--png", out, "--frames", "end", "--cell", "8"]) == 0
    assert out.read_bytes().startswith(MAGIC[suffix])


@pytest.mark.parametrize("argv, message", [
    (["--png", "out.xyz"], "--png: out.xyz: cannot write a '.xyz' picture (expected one of: .png, .jpg"),
    (["--gif", "out.png"], "out.png: an animation is written as .gif"),
])
def test_a_suffix_that_cannot_be_written_is_refused(tmp_path, rejects, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    rejects(["view", "corridor-2", "corridor-2.schedule", *argv], message)
    assert list(tmp_path.iterdir()) == []


def test_two_schedules_side_by_side_get_one_row_each(tmp_path):
    inst = load_instance(bundled_path("corridor-2"))
    sched = load_schedule(bundled_path("corridor-2.schedule"))
    traces = [trace(inst, sched, "a"), trace(inst, sched, "b")]
    cell = 48  # five frames of this map are wider than one row may be
    assert 5 * inst.width * cell > MAX_ROW_PX
    layout = save_png(traces, tmp_path / "two.png", cell=cell)
    assert (layout.rows, layout.cols) == (2, 5)
    alone = save_png(traces[:1], tmp_path / "one.png", cell=cell)
    assert alone.rows > 1 and alone.size_px[0] <= MAX_ROW_PX
