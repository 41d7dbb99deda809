"""Recordings and pictures: read back with rerun's reader and checked against the rules."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from bille.instances import Kind, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.rules import State, apply
from bille.solvers import Schedule, bind, load_schedule
from bille.tools import style
from bille.tools.cli import main
from bille.tools.pictures import GAP_PX, MAX_ROW_PX, choose_frames, save_gif, save_png
from bille.tools.recording import read, record
from bille.tools.trace import trace

DATA = Path(__file__).parent / "data"


def latest(rows, t):
    """The value shown at step ``t`` (rerun's latest-at: the last row at or before ``t``)."""
    before = [v for s, v in rows if s is not None and s <= t]
    return before[-1] if before else None


def states_by_rules(inst, sched):
    """The states of a valid schedule, by the rules alone."""
    ids = bind(inst, sched)
    states = [inst.start_state]
    for t in range(ids.shape[1]):
        nxt = apply(inst.world, states[-1], ids[:, t], t + 1)
        assert isinstance(nxt, State)
        states.append(nxt)
    return ids, states


@pytest.fixture(scope="module")
def reconfig(tmp_path_factory):
    inst = load_instance(bundled_path("reconfig-30"))
    sched = load_schedule(bundled_path("reconfig-30.schedule"))
    path = tmp_path_factory.mktemp("rrd") / "reconfig.rrd"
    info = record([trace(inst, sched, "reconfig-30")], path)
    return inst, sched, path, info, read(path)


def test_recording_has_the_entities_of_a_schedule(reconfig):
    inst, _, _, info, data = reconfig
    p = "/reconfig-30"
    for i in range(inst.num_robots):
        for part in ("feet", "body", "load", "swept", "path/done", "path/recent"):
            assert f"{p}/robots/{i}/{part}" in data, part
    for entity in ("structure", "goal/fill", "goal/clear", "actions", "events"):
        assert f"{p}/{entity}" in data, entity
    assert {"/plots/tiles_traveled/reconfig-30", "/plots/waiting/reconfig-30"} <= set(data)
    assert info["bytes"] == Path(info["path"]).stat().st_size > 0


def test_timeline_has_one_step_per_frame(reconfig):
    _, sched, _, info, data = reconfig
    steps = {s for comps in data.values() for rows in comps.values() for s, _ in rows if s is not None}
    assert steps == set(range(sched.length + 1))
    assert info["frames"] == sched.length + 1
    assert len(data["/reconfig-30/actions"]["TextDocument:text"]) == sched.length + 1


def test_tile_count_drops_after_a_pick_and_comes_back_after_a_place(reconfig):
    inst, sched, _, _, data = reconfig
    ids = bind(inst, sched)
    kinds = np.array([[inst.movesets[i].actions[a].kind for a in row] for i, row in enumerate(ids)])
    first_pick = int(np.flatnonzero((kinds == Kind.PICK).any(axis=0))[0]) + 1
    first_place = int(np.flatnonzero((kinds == Kind.PLACE).any(axis=0))[0]) + 1
    assert first_pick < first_place

    rows = data["/reconfig-30/structure"]

    def tiles_at(t):
        fmt = latest(rows["SegmentationImage:format"], t)[0]
        buf = np.array(latest(rows["SegmentationImage:buffer"], t)[0], dtype=np.uint8)
        return int((buf.reshape(fmt["height"], fmt["width"]) == 1).sum())

    start = int(inst.start.tiles.sum())
    assert tiles_at(0) == tiles_at(first_pick - 1) == start
    assert tiles_at(first_pick) == start - 1
    assert tiles_at(sched.length) == int(inst.goal_tiles.sum())
    # static geometry once: the structure is logged only when the tiles change
    assert len(rows["SegmentationImage:buffer"]) < sched.length + 1


def test_feet_at_every_step_are_those_of_the_rules(reconfig):
    inst, sched, _, _, data = reconfig
    _, states = states_by_rules(inst, sched)
    for i, g in enumerate(inst.world.graphs):
        rows = data[f"/reconfig-30/robots/{i}/feet"]["Points2D:positions"]
        for t, s in enumerate(states):
            front, back = g.feet_xy(s.poses[i])
            assert latest(rows, t) == [[front[0] + 0.5, front[1] + 0.5], [back[0] + 0.5, back[1] + 0.5]]


def test_carried_tile_is_shown_exactly_while_carrying(reconfig):
    inst, sched, _, _, data = reconfig
    _, states = states_by_rules(inst, sched)
    for i in range(inst.num_robots):
        rows = data[f"/reconfig-30/robots/{i}/load"]["Boxes2D:centers"]
        assert [len(latest(rows, t)) for t in range(len(states))] == [int(s.carrying[i]) for s in states]


def test_several_schedules_side_by_side(tmp_path):
    inst = load_instance(DATA / "line.yaml")
    ok = load_schedule(DATA / "line.ok.yaml")
    waits = Schedule((("wait",) * 3, ("wait",) * 3))
    path = tmp_path / "two.rrd"
    record([trace(inst, ok, "a"), trace(inst, waits, "b")], path)
    data = read(path)
    assert {"/a/robots/0/feet", "/b/robots/0/feet", "/plots/waiting/a", "/plots/waiting/b"} <= set(data)
    assert [v for _, v in data["/plots/waiting/b"]["Scalars:scalars"]] == [[0.0], [2.0], [2.0], [2.0]]
    assert [v for _, v in data["/plots/tiles_traveled/a"]["Scalars:scalars"]] == [[0.0], [2.0], [2.0]]


def test_check_marks_a_violation_at_its_step(tmp_path, capsys):
    path = tmp_path / "bad.rrd"
    code = _run(["check", str(DATA / "line.yaml"), str(DATA / "line.collision.yaml"), "--rerun", str(path)])
    assert code == 1
    data = read(path)
    cells = data["/line.collision/violation/cells"]["Boxes2D:centers"]
    assert cells == [(2, [[3.5, 1.5]])]
    assert data["/line.collision/violation/robots"]["LineStrips2D:labels"] == [(2, ["A", "B"])]
    errors = data["/line.collision/events"]["TextLog:text"]
    assert errors[-1][0] == 2 and "collision" in errors[-1][1][0]
    # the failing step's attempted collision sets overlap in the violation's cell
    swept = [latest(data[f"/line.collision/robots/{i}/swept"]["Boxes2D:centers"], 2) for i in (0, 1)]
    assert [3.5, 1.5] in swept[0] and [3.5, 1.5] in swept[1]


# ---- pictures ---------------------------------------------------------------------------------

def _pixel(img, xy):
    return tuple(int(v) for v in img[xy[1], xy[0], :3])


def _close(a, b, tol=6):
    return all(abs(x - y) <= tol for x, y in zip(a, b))


def test_png_size_and_colors_at_cells(tmp_path):
    inst = load_instance(DATA / "line.yaml")
    sched = load_schedule(DATA / "line.ok.yaml")
    tr = trace(inst, sched, "line")
    path = tmp_path / "line.png"
    layout = save_png([tr], path, frames="0,2", cell=30)
    img = np.asarray(Image.open(path).convert("RGB"))
    assert (img.shape[1], img.shape[0]) == layout.size_px
    assert layout.cols == 2 and layout.rows == 1
    for col, t in enumerate((0, 2)):
        assert _close(_pixel(img, layout.cell_center(0, col, 5, 0)), style.OBSTACLE)  # the obstacle
        assert _close(_pixel(img, layout.cell_center(0, col, 0, 2)), style.EMPTY)
        back = tuple(int(v) for v in tr.back[t, 0])
        assert _close(_pixel(img, layout.cell_center(0, col, *back)), style.robot_color(0))
        occupied = {back, tuple(int(v) for v in tr.front[t, 0]), tuple(int(v) for v in tr.front[t, 1])}
        occupied |= set(tr.swept[t][0]) | set(tr.swept[t][1])
        occupied |= {tuple(int(v) for v in tr.front[k, i]) for k in range(t + 1) for i in range(2)}  # path trails
        free_tiles = [(x, 1) for x in range(6) if (x, 1) not in occupied]
        assert free_tiles
        for cell in free_tiles:
            assert _close(_pixel(img, layout.cell_center(0, col, *cell)), style.TILE), (t, cell)
    # the point robot: its disc, beside the letter in its middle
    fx, fy = layout.cell_center(0, 1, *tr.front[2, 1])
    assert _close(_pixel(img, (fx + int(0.22 * 30), fy)), style.robot_color(1))


@pytest.mark.slow
def test_png_rows_are_schedules_and_gif_has_every_frame(tmp_path):
    inst = load_instance(bundled_path("reconfig-30"))
    sched = load_schedule(bundled_path("reconfig-30.schedule"))
    traces = [trace(inst, sched, "a"), trace(inst, None, "b")]
    layout = save_png(traces, tmp_path / "two.png", frames="all", cell=8)
    assert layout.cols == sched.length + 1 and layout.rows == 2  # one row per schedule; b: its start only
    layout = save_png(traces[:1], tmp_path / "one.png", frames="all", cell=8)
    fit = (MAX_ROW_PX - GAP_PX) // (inst.width * 8 + GAP_PX)  # one schedule's frames wrap into rows
    cols = min(fit, sched.length + 1)
    assert layout.cols == cols and layout.rows == math.ceil((sched.length + 1) / cols)
    assert layout.size_px[0] <= MAX_ROW_PX
    gif = tmp_path / "r.gif"
    layout = save_gif(traces, gif, fps=10, cell=8)
    with Image.open(gif) as im:
        assert im.n_frames == sched.length + 1
        assert im.size == layout.size_px


def test_choose_frames():
    assert choose_frames(None, 12) == [0, 3, 6, 9, 12]
    assert choose_frames("auto", 2) == [0, 1, 2]
    assert choose_frames("end", 7) == [7]
    assert choose_frames("0,4", 7) == [0, 4]
    assert choose_frames("auto", 0) == [0]


# ---- the command line -------------------------------------------------------------------------

def _run(argv):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    return exc.value.code


def test_view_writes_all_outputs(tmp_path, capsys):
    out = {k: tmp_path / f"v.{k}" for k in ("rrd", "png", "gif")}
    code = _run(["view", "corridor-2", "corridor-2.schedule", "--rerun", str(out["rrd"]), "--png", str(out["png"]),
                 "--gif", str(out["gif"]), "--cell", "8"])
    assert code == 0
    assert all(p.stat().st_size > 0 for p in out.values())
    assert "/corridor-2.schedule/robots/1/feet" in read(out["rrd"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.gif", "v.png", "v.rrd"]  # no temporary files left


@pytest.mark.parametrize("argv, message", [
    (["view", "corridor-2", "corridor-2.schedule", "--rerun", "{tmp}/missing/v.rrd"], "cannot write (no folder"),
    (["view", "corridor-2", "point-4.schedule", "--rerun", "{tmp}/v.rrd", "--png", "{tmp}/v.png"], "4 robots, but"),
    (["view", "corridor-2", "corridor-2.schedule", "--png", "{tmp}/v.png", "--frames", "0,99"], "--frames"),
    (["view", "corridor-2", "corridor-2.schedule", "--png", "{tmp}/v.png", "--frames", "x"], "--frames"),
    (["view", "corridor-2", "corridor-2.schedule"], "nothing to do"),
    (["solve", "point-4", "--rerun", "{tmp}/missing/s.rrd"], "cannot write"),
    (["check", "corridor-2", "point-4.schedule", "--rerun", "{tmp}/c.rrd"], "4 robots, but"),
])
def test_bad_view_input_is_one_line_and_leaves_no_file(tmp_path, capsys, argv, message):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert _run(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.rglob("*")) == []


def test_spawn_without_a_display_writes_the_file_and_says_why(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr("sys.platform", "linux")
    path = tmp_path / "s.rrd"
    assert _run(["view", "corridor-2", "corridor-2.schedule", "--spawn", "--rerun", str(path)]) == 0
    assert "viewer was not opened: no display" in capsys.readouterr().err
    assert path.stat().st_size > 0


def test_solve_and_gap_record_their_schedules(tmp_path, capsys):
    path = tmp_path / "s.rrd"
    assert _run(["solve", "compare-2", "--method", "temporal-astar", "--rerun", str(path)]) == 0
    assert "/temporal-astar/robots/1/feet" in read(path)
    path = tmp_path / "g.rrd"
    code = _run(["gap", "compare-2", "--methods", "temporal-astar,cpsat", "--time-limit", "60",
                 "--csv", str(tmp_path / "g.csv"), "--rerun", str(path)])
    assert code == 0
    data = read(path)
    assert {"/compare-2/temporal-astar/robots/0/feet", "/compare-2/cpsat/robots/0/feet"} <= set(data)


def test_two_places_at_once_are_each_robots_own(tmp_path):
    from helpers import make

    inst = make("TTTT\n....", [{"at": [0, 0], "carrying": True}, {"at": [3, 0], "carrying": True}],
                goal="TTTT\nT..T", moveset="point")
    sched = Schedule((("place-south",), ("place-south",)))
    path = tmp_path / "two.rrd"
    record([trace(inst, sched, "two")], path)
    events = [text for step, texts in read(path)["/two/events"]["TextLog:text"] for text in texts]
    assert events == ["step 1: A places (place-south) at (0, 1)", "step 1: B places (place-south) at (3, 1)"]


def test_the_legend_lists_only_what_the_picture_shows():
    from bille.tools.pictures import Painter

    def labels(traces):
        painter = Painter(traces, 1, 1, 8)
        try:
            return [h.get_label() for h in painter.legend]
        finally:
            painter.close()

    line = load_instance(DATA / "line.yaml")
    with_obstacle = labels([trace(line, load_schedule(DATA / "line.ok.yaml"), "line")])
    assert "obstacle" in with_obstacle and "cells swept (its robot's colour)" in with_obstacle
    r30 = load_instance(bundled_path("reconfig-30"))
    alone = labels([trace(r30, None, "start")])
    assert "obstacle" not in alone and "cells swept (its robot's colour)" not in alone and "path so far" not in alone
    assert "goal: add a tile" in alone and "robot A" in alone


def test_picks_places_and_the_hand_over_are_marked():
    from bille.instances.generators.coop import demonstration, gadget
    from bille.tools.pictures import Painter, _manipulations

    inst = gadget(2)
    tr = trace(inst, Schedule(demonstration(2)), "split")
    kinds = [kind for _, _, kind, _ in _manipulations(tr)]
    assert kinds.count("place") == 8 and kinds.count("hand-over") == 1 and kinds.count("pick") == 7
    painter = Painter([tr], 1, 1, 8)
    try:
        assert "hand-over: picked where another placed" in [h.get_label() for h in painter.legend]
    finally:
        painter.close()


def test_frames_are_chosen_per_schedule_and_labels_kept(tmp_path):
    from bille.tools.pictures import _frames_of

    assert _frames_of("auto", 8) == [0, 2, 4, 6, 8] and _frames_of("0,20,30", 8) == [0, 8]
    out = tmp_path / "two.png"
    code = _run(["view", "corridor-2", "corridor-2.schedule", "corridor-2.schedule", "--label", "no transfer",
                 "--label", "with transfer", "--png", str(out), "--rerun", str(tmp_path / "two.rrd")])
    assert code == 0 and out.exists()
    assert "/no_transfer/events" in read(tmp_path / "two.rrd")  # entity paths are made valid, labels are not
    assert trace(load_instance(bundled_path("corridor-2")), None, "no transfer").label == "no transfer"


def test_the_legend_marks_picks_only_when_a_drawn_frame_shows_one():
    from bille.instances.generators.coop import demonstration, gadget
    from bille.tools.pictures import Painter, _manipulations

    inst = gadget(2)
    tr = trace(inst, Schedule(demonstration(2)), "split")
    quiet = [t for t in range(tr.steps + 1) if t not in {step for step, _, _, _ in _manipulations(tr)}]
    some_pick = next(step for step, _, kind, _ in _manipulations(tr) if kind == "pick")

    def labels(frames):
        painter = Painter([tr], 1, 1, 8, frames=[frames])
        try:
            return [h.get_label() for h in painter.legend]
        finally:
            painter.close()

    assert "picked this step" not in labels(quiet[:3])
    assert "picked this step" in labels([some_pick])
