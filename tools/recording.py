"""Schedules as rerun recordings (``bille view --rerun``, ``bille solve/gap/check --rerun``).

One recording holds one or more schedules (:class:`~.trace.Trace`), each under its own entity
path ``/<label>``, on one timeline ``step`` (frame ``t`` is the state after step ``t``). The
default blueprint shows the schedules side by side, with the plots and the current actions below
(one tab per instance when the schedules come from several instances).

Entities of a schedule ``/<label>`` (cell ``(x, y)`` is the unit square from ``(x, y)``: its
centre is ``(x + 0.5, y + 0.5)``; ``y`` grows downward as in the files):

==================================  ===========  =====================================================
``structure``                       Segmentation obstacles and tiles, one pixel per cell (class 0 empty,
                                    Image        1 tile, 2 obstacle); logged at frame 0 and whenever
                                                 a pick or place changes the tiles (latest-at)
``goal/fill``, ``goal/clear``       Boxes2D      cells that must still gain / lose a tile (with the
                                                 structure)
``robots/<i>/goal``                 LineStrips2D static: a ring on robot ``i``'s goal cell
``robots/<i>/feet``                 Points2D     front foot (large) and back foot, every frame
``robots/<i>/body``                 LineStrips2D back foot to front foot (bipeds), labelled
``robots/<i>/load``                 Boxes2D      the carried tile (empty when none)
``robots/<i>/swept``                Boxes2D      the collision set of the step just made
``robots/<i>/path/done``, ``/recent`` LineStrips2D the front foot's path so far: up to the last
                                                 multiple of ``PATH_BLOCK`` frames, and from there
``actions``                         TextDocument the step's actions, one line per robot
``events``                          TextLog      picks, places, and the violation if any
``violation/cells``, ``/robots``    Boxes2D,     at the failing step: the offending cells, rings
                                    LineStrips2D around the offending robots
``/plots/tiles_traveled/<label>``   Scalars      tiles traveled so far
``/plots/waiting/<label>``          Scalars      robots waiting at this step
==================================  ===========  =====================================================

Static geometry is logged once; everything per frame goes in one columnar send per entity.
"""
from __future__ import annotations

import math
import os
import re
import sys
from collections import defaultdict
from pathlib import Path
from typing import Sequence

import numpy as np
import pyarrow as pa
import rerun as rr
import rerun.blueprint as rrb
from rerun.components import LineStrip2DBatch
from rerun.encodings import Vec2DBatch

from bille.instances import BilleError, Kind

from . import style
from .trace import Trace

TIMELINE = "step"
PATH_BLOCK = 32
_ORDER = {"structure": 0.0, "goal": 1.0, "swept": 2.0, "path": 3.0, "load": 4.0, "body": 5.0, "feet": 6.0,
          "violation": 7.0}


def entity_label(text: str) -> str:
    """A label usable as entity path: ``/``-separated parts of letters, digits, ``-``, ``_``, ``.``."""
    parts = [re.sub(r"[^A-Za-z0-9_.-]", "_", p) for p in text.split("/") if p]
    return "/".join(parts) or "schedule"


def record(traces: Sequence[Trace], path: str | Path | None = None, *, spawn: bool = False,
           application: str = "bille") -> dict:
    """Log ``traces`` to a recording: written to ``path`` (atomically: a failure leaves no file)
    and/or streamed to a viewer (``spawn``, only where a display exists).

    Returns ``{"path", "bytes", "frames", "viewer"}`` where ``viewer`` is None or why no viewer
    was opened. Raises :class:`~bille.instances.BilleError` when the file cannot be written.
    """
    import dataclasses

    # entity paths take letters, digits, '-', '_' and '.': labels are made so here, and only here
    traces = [dataclasses.replace(t, label=entity_label(t.label)) for t in traces]
    labels = [t.label for t in traces]
    if len(set(labels)) != len(labels):
        raise BilleError(f"two schedules with the same label in one recording: {labels}")
    rec = rr.RecordingStream(application, send_properties=False)
    blueprint = _blueprint(traces)
    viewer = None
    if spawn:
        viewer = viewer_unavailable()
        if viewer is None:
            try:
                rec.spawn(connect=False, default_blueprint=blueprint)
            except Exception as exc:  # the viewer binary may be missing or fail to start
                viewer = f"the viewer could not be started ({exc})"
    tmp = None
    if path is not None:
        path = Path(path)
        tmp = path.with_name(f".{path.name}.tmp")
        try:
            tmp.touch()
        except OSError as exc:
            raise BilleError(f"{path}: cannot write ({exc.strerror})") from None
    elif not spawn or viewer is not None:
        return {"path": None, "bytes": 0, "frames": max((t.steps for t in traces), default=0) + 1, "viewer": viewer}
    try:
        sinks = [rr.FileSink(str(tmp))] if tmp is not None else []
        if spawn and viewer is None:
            sinks.append(rr.GrpcSink())
        rec.set_sinks(*sinks, default_blueprint=blueprint)
        for t in traces:
            _log_trace(rec, t)
        rec.flush()
        rec.disconnect()
        if tmp is not None:
            tmp.replace(path)
    except BaseException:
        if tmp is not None:
            tmp.unlink(missing_ok=True)
        raise
    size = path.stat().st_size if path is not None else 0
    return {"path": None if path is None else str(path), "bytes": size,
            "frames": max(t.steps for t in traces) + 1, "viewer": viewer}


def viewer_unavailable() -> str | None:
    """Why a viewer window cannot be opened here, or None if it can."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "no display (neither DISPLAY nor WAYLAND_DISPLAY is set)"
    return None


# ---- one schedule ---------------------------------------------------------------------------

def _centers(xys) -> np.ndarray:
    return np.asarray(xys, dtype=np.float32).reshape(-1, 2) + 0.5


def _ring(xy, radius: float, n: int = 24) -> np.ndarray:
    a = np.linspace(0.0, 2 * math.pi, n + 1)
    return np.stack([xy[0] + 0.5 + radius * np.cos(a), xy[1] + 0.5 + radius * np.sin(a)], axis=1)


def _log_trace(rec: rr.RecordingStream, tr: Trace) -> None:
    inst, p = tr.instance, tr.label
    frames = np.arange(tr.steps + 1)
    index = [rr.TimeColumn(TIMELINE, sequence=frames)]
    obstacles = inst.start.obstacles

    w = inst.width
    for i, g in enumerate(inst.robot_goals or ()):
        if g is not None:
            rec.log(f"{p}/robots/{i}/goal", rr.LineStrips2D([_ring(g, style.GOAL_RADIUS)], colors=[style.robot_color(i)],
                                                            radii=0.04, labels=[f"{style.robot_name(i)} goal"],
                                                            draw_order=_ORDER["goal"]), static=True)

    # the structure and what still differs from the goal, when the tiles change
    rec.log(f"{p}/structure", rr.AnnotationContext(style.CELL_CLASSES), static=True)
    marks = (("fill", style.GOAL_FILL, lambda now: inst.goal_tiles & ~now), ("clear", style.GOAL_CLEAR, lambda now: now & ~inst.goal_tiles))
    for name, color, _ in marks:
        rec.log(f"{p}/goal/{name}", rr.Boxes2D.from_fields(half_sizes=[[0.4, 0.4]], colors=[color], radii=[0.04],
                                                          draw_order=_ORDER["goal"]), static=True)
    for t in tr.changes():
        rec.set_time(TIMELINE, sequence=t)
        rec.log(f"{p}/structure", rr.SegmentationImage(style.cell_classes(tr.tiles[t], obstacles, w, inst.height),
                                                       opacity=1.0, draw_order=_ORDER["structure"]))
        for name, _, diff in marks:
            cells = np.flatnonzero(diff(tr.tiles[t]))
            rec.log(f"{p}/goal/{name}", rr.Boxes2D.from_fields(centers=_centers(np.stack([cells % w, cells // w], 1))))

    for i in range(inst.num_robots):
        _log_robot(rec, tr, i, index)

    # text and plots
    lines = [f"step {t}" + "".join(f"\n{style.robot_name(i)}: {a}" for i, a in enumerate(tr.actions[t]) if a)
             for t in frames]
    rec.send_columns(f"{p}/actions", index, rr.TextDocument.columns(text=lines))
    _log_events(rec, tr)
    for plot, values in (("tiles_traveled", tr.traveled), ("waiting", tr.waiting)):
        rec.log(f"plots/{plot}/{p}", rr.SeriesLines(names=[p]), static=True)
        rec.send_columns(f"plots/{plot}/{p}", index, rr.Scalars.columns(scalars=values.astype(np.float64)))
    if tr.violation is not None:
        _log_violation(rec, tr)


def _log_robot(rec, tr: Trace, i: int, index) -> None:
    p, color = f"{tr.label}/robots/{i}", style.robot_color(i)
    point = tr.instance.movesets[i].footprint == "point"
    front, back = _centers(tr.front[:, i]), _centers(tr.back[:, i])
    n = len(front)
    name = style.robot_name(i)

    if point:
        rec.log(f"{p}/feet", rr.Points2D.from_fields(radii=[style.FRONT_RADIUS], colors=[color], labels=[name],
                                                     draw_order=_ORDER["feet"]), static=True)
        rec.send_columns(f"{p}/feet", index, rr.Points2D.columns(positions=front))
    else:
        rec.log(f"{p}/feet", rr.Points2D.from_fields(radii=[style.FRONT_RADIUS, style.BACK_RADIUS], colors=[color],
                                                     draw_order=_ORDER["feet"]), static=True)
        rec.send_columns(f"{p}/feet", index,
                         rr.Points2D.columns(positions=np.stack([front, back], 1).reshape(-1, 2)).partition(np.full(n, 2)))
        rec.log(f"{p}/body", rr.LineStrips2D.from_fields(colors=[color], radii=[0.12], labels=[name],
                                                         draw_order=_ORDER["body"]), static=True)
        rec.send_columns(f"{p}/body", index, rr.LineStrips2D.columns(strips=np.stack([back, front], 1)))

    loads = [tr.load_cell(t, i) for t in range(n)]
    rec.log(f"{p}/load", rr.Boxes2D.from_fields(half_sizes=[[0.25, 0.25]], colors=[color], radii=[0.06],
                                                draw_order=_ORDER["load"]), static=True)
    rec.send_columns(f"{p}/load", index, rr.Boxes2D.columns(centers=_centers([c for c in loads if c is not None]))
                     .partition([int(c is not None) for c in loads]))

    swept = [tr.swept[t][i] for t in range(n)]
    rec.log(f"{p}/swept", rr.Boxes2D.from_fields(half_sizes=[[0.46, 0.46]], colors=[(*color, 110)], radii=[0.03],
                                                 draw_order=_ORDER["swept"]), static=True)
    rec.send_columns(f"{p}/swept", index, rr.Boxes2D.columns(centers=_centers([c for s in swept for c in s]))
                     .partition([len(s) for s in swept]))

    # the path so far, in two strips so that the data grows as n * sqrt(n), not n^2: ``path/done``
    # up to the last multiple of B (logged every B frames), ``path/recent`` from there to t
    for part in ("done", "recent"):
        rec.log(f"{p}/path/{part}", rr.LineStrips2D.from_fields(colors=[color], radii=[0.05], draw_order=_ORDER["path"]),
                static=True)
    marks = np.arange(0, n, PATH_BLOCK)
    rec.send_columns(f"{p}/path/done", [rr.TimeColumn(TIMELINE, sequence=marks)], [_strips([front[: t + 1] for t in marks])])
    rec.send_columns(f"{p}/path/recent", index, [_strips([front[t - t % PATH_BLOCK : t + 1] for t in range(n)])])


def _strips(strips: list[np.ndarray]):
    """One line strip per frame as a column, built as one arrow array (rerun's own conversion
    goes strip by strip in Python and dominates long recordings)."""
    offsets = np.concatenate([[0], np.cumsum([len(s) for s in strips])]).astype(np.int32)
    points = Vec2DBatch(np.concatenate(strips).astype(np.float32)).as_arrow_array()
    batch = LineStrip2DBatch(pa.ListArray.from_arrays(pa.array(offsets), points, type=LineStrip2DBatch._ARROW_DATATYPE))
    return batch.described(rr.LineStrips2D.descriptor_strips()).partition(np.ones(len(strips), dtype=np.int32))


def _log_events(rec, tr: Trace) -> None:
    inst = tr.instance
    movesets = inst.movesets
    for t in range(1, len(tr.actions)):
        if tr.violation is not None and t == tr.violation.step and tr.violation.rule != "goal":
            break  # the failing step's actions were not done
        for i, name in enumerate(tr.actions[t]):
            kind = movesets[i].actions[movesets[i].index[name]].kind
            if kind in (Kind.PICK, Kind.PLACE):
                before, after = tr.tiles[t - 1], tr.tiles[t]
                # its own cell: the changed cell in its collision set (the sets of one step are
                # disjoint, so two robots placing at once each get their own)
                mine = {(int(x), int(y)) for x, y in tr.swept[t][i]}
                changed = [(c % inst.width, c // inst.width) for c in np.flatnonzero(before != after).tolist()]
                where = ", ".join(f"({x}, {y})" for x, y in changed if (x, y) in mine)
                verb = "picks" if kind == Kind.PICK else "places"
                rec.set_time(TIMELINE, sequence=t)
                rec.log(f"{tr.label}/events", rr.TextLog(f"step {t}: {style.robot_name(i)} {verb} ({name}) "
                                                         f"at {where}", level="INFO"))


def _log_violation(rec, tr: Trace) -> None:
    v, p = tr.violation, tr.label
    t = min(v.step, tr.steps)
    rec.set_time(TIMELINE, sequence=t)
    rec.log(f"{p}/violation/cells", rr.Boxes2D(centers=_centers(v.cells), half_sizes=[0.5, 0.5],
                                               colors=[style.VIOLATION], radii=0.08, labels=[v.rule],
                                               draw_order=_ORDER["violation"]))
    robots = [r for r in (v.robot, v.other) if r is not None]
    rings = [_ring(tr.front[t, r], 0.48) for r in robots]
    rec.log(f"{p}/violation/robots", rr.LineStrips2D(rings, colors=[style.VIOLATION], radii=0.08,
                                                     labels=[style.robot_name(r) for r in robots],
                                                     draw_order=_ORDER["violation"]))
    rec.log(f"{p}/events", rr.TextLog(f"step {v.step}: rule {v.rule}: {v.message}", level="ERROR"))


# ---- layout ---------------------------------------------------------------------------------

def _blueprint(traces: Sequence[Trace]) -> rrb.Blueprint:
    by_instance: dict[str, list[Trace]] = defaultdict(list)
    for t in traces:
        by_instance[t.instance.name].append(t)
    pages = [_page(name, group) for name, group in by_instance.items()]
    root = pages[0] if len(pages) == 1 else rrb.Tabs(*pages)
    return rrb.Blueprint(root, collapse_panels=False)


def _page(name: str, group: list[Trace]):
    inst = group[0].instance
    bounds = rrb.VisualBounds2D(x_range=[0, inst.width], y_range=[0, inst.height])
    maps = [rrb.Spatial2DView(origin=f"/{t.label}", name=t.label, visual_bounds=bounds) for t in group]
    common = _common_prefix([t.label for t in group])
    plots = [rrb.TimeSeriesView(origin=f"/plots/{plot}/{common}".rstrip("/"), name=title)
             for plot, title in (("tiles_traveled", "tiles traveled"), ("waiting", "robots waiting"))]
    texts = [rrb.TextDocumentView(origin=f"/{t.label}/actions", name=f"{t.label}: actions") for t in group]
    logs = rrb.TextLogView(contents=[f"/{t.label}/events" for t in group], name="events")
    return rrb.Vertical(rrb.Horizontal(*maps), rrb.Horizontal(*plots, *texts, logs), row_shares=[3, 1], name=name)


def _common_prefix(labels: list[str]) -> str:
    parts = [label.split("/") for label in labels]
    out = []
    for column in zip(*parts):
        if len(set(column)) != 1:
            break
        out.append(column[0])
    if len(labels) == 1:
        out = out[:-1]  # one schedule: the plot's origin is its parent, so the series shows
    return "/".join(out)


# ---- reading back -------------------------------------------------------------------------------

def read(path: str | Path) -> dict[str, dict[str, list]]:
    """A recording's content through rerun's reader: ``{entity: {component: [(step, value)]}}``
    with ``step`` None for static data, sorted by step.

    >>> # read("out.rrd")["/corridor-2/robots/0/feet"]["Points2D:positions"][3]
    """
    from rerun.chunk import RrdReader

    out: dict[str, dict[str, list]] = defaultdict(lambda: defaultdict(list))
    for chunk in RrdReader(str(path)).store().stream().to_chunks():
        data = chunk.to_record_batch().to_pydict()
        steps = data.get(TIMELINE, [None] * chunk.num_rows)
        for column, values in data.items():
            if ":" not in column:
                continue
            for s, v in zip(steps, values):
                if v is not None:
                    out[chunk.entity_path][column].append((s, v))
    for comps in out.values():
        for rows in comps.values():
            rows.sort(key=lambda r: -1 if r[0] is None else r[0])
    return {e: dict(c) for e, c in out.items()}
