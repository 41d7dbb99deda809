"""Pictures of schedules with matplotlib (``bille view --png`` and ``--gif``).

The drawing conventions are those of the recording (:mod:`.style`). A picture is a table of
panels, each one frame of one schedule; every panel has ``cell`` pixels per grid cell, a title
band above it and a gap around it, and the legend runs along the bottom, so that the pixel of
every cell is known (:meth:`Layout.cell_center`): tests read colors there.

- Picture (``--png``, in the format its suffix names): each schedule its frames (chosen per
  schedule: ``auto`` gives a shorter schedule its own start, end and steps between). Several
  schedules: one row each, side by side in time. One schedule: its frames in rows of at most
  :data:`MAX_ROW_PX` pixels.
- GIF: one row with one panel per schedule, side by side, all frames in time.

Every panel has its coordinates along its left and bottom edges, each robot's path so far, and
marks where a robot picked (``-``) or placed (``+``) a tile in the step just taken, ``h`` where it
picked a tile another robot had placed (a hand-over). The legend lists only what the picture
shows.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")  # pictures are files; no display needed

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Circle, Patch, Rectangle  # noqa: E402

from bille.instances import BilleError, OptionError  # noqa: E402
from bille.instances.files import write_with  # noqa: E402

from . import style  # noqa: E402
from .trace import Trace  # noqa: E402

DPI = 100
TITLE_PX, GAP_PX, LEGEND_ROW_PX, LEGEND_ITEM_PX = 22, 16, 22, 170
MAX_ROW_PX = 1600  # a row of panels wraps beyond this width


def _rgb(color, alpha: float | None = None):
    c = tuple(v / 255 for v in color)
    return c if alpha is None else (*c, alpha)


@dataclass(frozen=True)
class Layout:
    """Pixel geometry of a picture of ``rows x cols`` panels of ``width x height`` cells."""

    rows: int
    cols: int
    width: int
    height: int
    cell: int
    legend_rows: int

    @property
    def panel_px(self) -> tuple[int, int]:
        return self.width * self.cell, self.height * self.cell

    @property
    def size_px(self) -> tuple[int, int]:
        pw, ph = self.panel_px
        return (self.cols * pw + (self.cols + 1) * GAP_PX,
                self.rows * (ph + TITLE_PX) + (self.rows + 1) * GAP_PX + self.legend_rows * LEGEND_ROW_PX)

    def panel_origin(self, row: int, col: int) -> tuple[int, int]:
        """Top-left pixel of a panel's grid (below its title), from the picture's top-left."""
        pw, ph = self.panel_px
        return GAP_PX + col * (pw + GAP_PX), GAP_PX + TITLE_PX + row * (ph + TITLE_PX + GAP_PX)

    def cell_center(self, row: int, col: int, x: int, y: int) -> tuple[int, int]:
        """Pixel ``(column, row)`` of the centre of cell ``(x, y)`` in a panel."""
        ox, oy = self.panel_origin(row, col)
        return int(ox + (x + 0.5) * self.cell), int(oy + (y + 0.5) * self.cell)


def choose_frames(spec: str | None, steps: int) -> list[int]:
    """Frames for a strip: ``None``/``auto`` (start, end and up to three between), ``all``,
    ``end``, or a comma-separated list of frame numbers (``0`` is the start)."""
    if spec is None or spec == "auto":
        count = min(steps + 1, 5)
        return sorted({round(k * steps / max(count - 1, 1)) for k in range(count)})
    if spec == "all":
        return list(range(steps + 1))
    if spec == "end":
        return [steps]
    try:
        frames = [int(part) for part in spec.split(",") if part.strip()]
    except ValueError:
        raise OptionError(f"--frames: expected 'auto', 'all', 'end' or frame numbers like 0,5,9, got {spec!r}") from None
    bad = [f for f in frames if not 0 <= f <= steps]
    if not frames or bad:
        raise OptionError(f"--frames: frames must lie in 0..{steps}, got {spec!r}")
    return frames


class Painter:
    """A figure of panels that can be redrawn for any (trace, frame) per panel."""

    def __init__(self, traces: Sequence[Trace], rows: int, cols: int, cell: int = 32,
                 frames: Sequence[Sequence[int]] | None = None) -> None:
        if cell < 4:
            raise OptionError(f"--cell: at least 4 pixels per cell, got {cell}")
        inst = traces[0].instance
        self.traces = traces
        self.legend = self._legend_items(traces, frames)
        probe = Layout(rows, cols, inst.width, inst.height, cell, 1)
        per_row = max(1, probe.size_px[0] // LEGEND_ITEM_PX)
        self.layout = Layout(rows, cols, inst.width, inst.height, cell, math.ceil(len(self.legend) / per_row))
        w, h = self.layout.size_px
        if w * h > 60_000_000 or max(w, h) >= 1 << 16:
            raise OptionError(f"the picture would be {w}x{h} pixels: choose fewer frames or a smaller --cell")
        self.fig = plt.figure(figsize=(w / DPI, h / DPI), dpi=DPI, facecolor="white")
        self.axes = [[self._axes(r, c) for c in range(cols)] for r in range(rows)]
        self._drawn: set[tuple[int, int]] = set()  # panels with their coordinates set
        self.fig.legend(handles=self.legend, loc="lower center", ncol=per_row, frameon=False, fontsize=8,
                        bbox_to_anchor=(0.5, 0.0), handlelength=1.5, columnspacing=1.0)

    def _axes(self, r: int, c: int):
        w, h = self.layout.size_px
        pw, ph = self.layout.panel_px
        ox, oy = self.layout.panel_origin(r, c)
        ax = self.fig.add_axes((ox / w, 1 - (oy + ph) / h, pw / w, ph / h))
        ax.set_axis_off()
        return ax

    def _coordinates(self, ax) -> None:
        """Cell coordinates along the left and bottom edges (every k-th where cells are small)."""
        inst, cell = self.traces[0].instance, self.layout.cell
        ax.set_axis_on()
        for spine in ax.spines.values():
            spine.set_visible(False)
        kx = max(1, math.ceil((4 * len(str(inst.width - 1)) + 4) / cell))
        ky = max(1, math.ceil(10 / cell))
        ax.set_xticks([x + 0.5 for x in range(0, inst.width, kx)], [str(x) for x in range(0, inst.width, kx)])
        ax.set_yticks([y + 0.5 for y in range(0, inst.height, ky)], [str(y) for y in range(0, inst.height, ky)])
        ax.tick_params(length=0, labelsize=6, pad=1, colors=(0.45, 0.45, 0.45))

    @staticmethod
    def _legend_items(traces: Sequence[Trace], frames: Sequence[Sequence[int]] | None = None) -> list:
        """One entry per kind of thing the picture shows, and none for what it does not
        (``frames``: the frames drawn of each trace, where not all are; a pick is marked only in
        the frame of its step)."""
        grey = (0.45, 0.45, 0.45)
        items = [Patch(facecolor=_rgb(style.TILE), label="tile")]
        inst = traces[0].instance
        if inst.start.obstacles.any():
            items.append(Patch(facecolor=_rgb(style.OBSTACLE), label="obstacle"))
        if (inst.goal_tiles & ~inst.start.tiles).any():
            items.append(Patch(facecolor="none", edgecolor=_rgb(style.GOAL_FILL), linewidth=2, label="goal: add a tile"))
        if (inst.start.tiles & ~inst.goal_tiles).any():
            items.append(Patch(facecolor="none", edgecolor=_rgb(style.GOAL_CLEAR), linewidth=2, label="goal: remove"))
        if inst.robot_goals and any(g is not None for g in inst.robot_goals):
            items.append(Line2D([], [], linestyle="", marker="o", markersize=9, markerfacecolor="none",
                                markeredgecolor=grey, label="goal cell (its robot's colour)"))
        if any(cells for tr in traces for step in tr.swept for cells in step):
            items.append(Patch(facecolor=(*grey, 0.3), label="cells swept (its robot's colour)"))
        if any(tr.steps for tr in traces):
            items.append(Line2D([], [], color=grey, alpha=0.6, linewidth=1.5, label="path so far"))
        drawn = [None] * len(traces) if frames is None else [set(f) for f in frames]
        kinds = {kind for tr, shown in zip(traces, drawn) for step, _, kind, _ in _manipulations(tr)
                 if shown is None or step in shown}
        for kind, text in (("place", "placed this step"), ("pick", "picked this step"),
                           ("hand-over", "hand-over: picked where another placed")):
            if kind in kinds:
                items.append(Line2D([], [], linestyle="", marker=f"${_MARK[kind]}$", markersize=8, color=grey,
                                    label=text))
        for i in range(inst.num_robots):
            items.append(Line2D([], [], color=_rgb(style.robot_color(i)), marker="o", linewidth=3,
                                label=f"robot {style.robot_name(i)}"))
        if any(t.violation is not None for t in traces):
            items.append(Patch(facecolor="none", edgecolor=_rgb(style.VIOLATION), linewidth=2, label="violation"))
        return items

    def draw(self, panels: Sequence[tuple[int, int, Trace, int]]) -> None:
        """Draw frame ``t`` of ``trace`` in panel ``(row, col)`` for each ``(row, col, trace, t)``.
        A panel drawn before keeps its axes and coordinates and loses only the frame's artists
        (the coordinates took two fifths of an animation's time when redrawn every frame)."""
        for r, c, tr, t in panels:
            ax = self.axes[r][c]
            fresh = (r, c) not in self._drawn
            if fresh:
                ax.clear()
                ax.set_axis_off()
            else:
                for artist in [*ax.images, *ax.patches, *ax.lines, *ax.texts, *ax.collections]:
                    artist.remove()
            _draw_frame(ax, tr, t)
            if fresh:
                self._coordinates(ax)
                self._drawn.add((r, c))

    def image(self) -> np.ndarray:
        """The figure as ``uint8[H, W, 3]``."""
        self.fig.canvas.draw()
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def close(self) -> None:
        plt.close(self.fig)


def _draw_frame(ax, tr: Trace, t: int) -> None:
    inst = tr.instance
    w, h = inst.width, inst.height
    ax.imshow(style.cell_image(tr.tiles[t], inst.start.obstacles, w, h), extent=(0, w, h, 0),
              interpolation="nearest", zorder=0)
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    lw = max(1.0, 0.08 * _cell_pt(ax, w))
    now = tr.tiles[t]
    for mask, color in ((inst.goal_tiles & ~now, style.GOAL_FILL), (now & ~inst.goal_tiles, style.GOAL_CLEAR)):
        for c in np.flatnonzero(mask):
            ax.add_patch(Rectangle((c % w + 0.1, c // w + 0.1), 0.8, 0.8, fill=False, edgecolor=_rgb(color),
                                   linewidth=lw, zorder=1))
    for i in range(inst.num_robots):
        color = _rgb(style.robot_color(i))
        for x, y in tr.swept[t][i]:
            ax.add_patch(Rectangle((x + 0.04, y + 0.04), 0.92, 0.92, facecolor=(*color, 0.25), edgecolor="none", zorder=2))
        goal = inst.robot_goals[i] if inst.robot_goals else None
        if goal is not None:
            ax.add_patch(Circle((goal[0] + 0.5, goal[1] + 0.5), style.GOAL_RADIUS, fill=False, edgecolor=color,
                                linewidth=lw, zorder=3))
    for i in range(inst.num_robots):
        if t:
            trail = tr.front[: t + 1, i] + 0.5
            ax.plot(trail[:, 0], trail[:, 1], color=_rgb(style.robot_color(i)), alpha=0.45, linewidth=lw, zorder=4)
    for i in range(inst.num_robots):
        _draw_robot(ax, tr, t, i, lw)
    for step, i, kind, (x, y) in _manipulations(tr):
        if step == t:
            ax.text(x + 0.5, y + 0.5, _MARK[kind], color=_rgb(style.robot_color(i)), fontsize=max(6, 0.5 * _cell_pt(ax, w)),
                    fontweight="bold", ha="center", va="center", zorder=7)
    v = tr.violation
    if v is not None and t == min(v.step, tr.steps):
        for x, y in v.cells:
            ax.add_patch(Rectangle((x, y), 1, 1, fill=False, edgecolor=_rgb(style.VIOLATION), linewidth=2 * lw, zorder=8))
        for r in (v.robot, v.other):
            if r is not None:
                fx, fy = tr.front[t, r]
                ax.add_patch(Circle((fx + 0.5, fy + 0.5), 0.48, fill=False, edgecolor=_rgb(style.VIOLATION),
                                    linewidth=2 * lw, zorder=8))
    when = "start" if t == 0 else f"step {t}/{tr.steps}"
    if v is not None and t == min(v.step, tr.steps):
        when += f", {v.rule}!"
    text, size = _fit(f"{tr.label}: ", when, w * _cell_pt(ax, w))
    ax.text(0, -0.15, text, fontsize=size, va="bottom", ha="left", clip_on=False, transform=ax.transData)


_MARK = {"place": "+", "pick": "-", "hand-over": "h"}


def _manipulations(tr: Trace) -> list[tuple[int, int, str, tuple[int, int]]]:
    """``(step, robot, kind, cell)`` of every pick and place: a pick of a cell whose last place
    was another robot's is a ``hand-over``. The cell is the changed one in the robot's collision
    set (the sets of one step are disjoint)."""
    w, out, placed_by = tr.instance.width, [], {}
    for t in range(1, tr.steps + 1):
        changed = np.flatnonzero(tr.tiles[t] != tr.tiles[t - 1]).tolist()
        if not changed:
            continue
        for i in range(tr.instance.num_robots):
            if tr.carrying[t, i] == tr.carrying[t - 1, i]:
                continue
            mine = {(int(x), int(y)) for x, y in tr.swept[t][i]}
            cell = next(((c % w, c // w) for c in changed if (c % w, c // w) in mine), None)
            if cell is None:
                continue
            if tr.carrying[t, i]:
                other = placed_by.get(cell, i) != i
                out.append((t, i, "hand-over" if other else "pick", cell))
            else:
                placed_by[cell] = i
                out.append((t, i, "place", cell))
    return out


def _draw_robot(ax, tr: Trace, t: int, i: int, lw: float) -> None:
    color = _rgb(style.robot_color(i))
    fx, fy = tr.front[t, i] + 0.5
    bx, by = tr.back[t, i] + 0.5
    if (fx, fy) != (bx, by):
        ax.plot([bx, fx], [by, fy], color=color, linewidth=3 * lw, solid_capstyle="round", zorder=5)
        ax.add_patch(Circle((bx, by), style.BACK_RADIUS, color=color, zorder=6))
    ax.add_patch(Circle((fx, fy), style.FRONT_RADIUS, color=color, zorder=6))
    ax.text(fx, fy, style.robot_name(i), color="white", fontsize=max(5, min(10, 0.3 * _cell_pt(ax, tr.instance.width))),
            ha="center", va="center", zorder=7)
    load = tr.load_cell(t, i)
    if load is not None:
        ax.add_patch(Rectangle((load[0] + 0.22, load[1] + 0.22), 0.56, 0.56, facecolor=_rgb(style.TILE),
                               edgecolor=color, linewidth=2 * lw, zorder=6))


def _fit(head: str, tail: str, width_pt: float) -> tuple[str, float]:
    """``head + tail`` and a font size between 7 and 9 points at which it fits ``width_pt``
    (about 0.6 em per character), ``head`` cut short with an ellipsis if 7 points is too wide."""
    size = max(7.0, min(9.0, width_pt / (0.6 * len(head + tail))))
    room = int(width_pt / (0.6 * size)) - len(tail)
    if len(head) > room:
        head = head[: max(1, room - 3)] + "…: "
    return head + tail, size


def _cell_pt(ax, width: int) -> float:
    """The size of a cell in points."""
    bbox = ax.get_position()
    return bbox.width * ax.figure.get_figwidth() * 72 / width


# ---- files ------------------------------------------------------------------------------------

FORMATS = ("png", "jpg", "jpeg", "pdf", "svg", "svgz", "eps", "ps", "tif", "tiff", "webp")


def image_format(path: str | Path) -> str:
    """The format a picture's file name asks for (``png`` without a suffix); raises
    :class:`OptionError` for a suffix matplotlib cannot write."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if not suffix:
        return "png"
    if suffix not in FORMATS:
        raise OptionError(f"--png: {path}: cannot write a '.{suffix}' picture (expected one of: "
                          f"{', '.join('.' + f for f in FORMATS)})")
    return suffix


def save_png(traces: Sequence[Trace], path: str | Path, frames: str | None = None, cell: int = 32) -> Layout:
    """Each schedule's chosen frames (:func:`choose_frames` on its own length; frame numbers
    beyond a shorter schedule's end show its end, once): one row per schedule when there are
    several; a single schedule's wrapped into rows of at most :data:`MAX_ROW_PX` pixels. Written
    atomically, in the format the file name's suffix names (:func:`image_format`)."""
    fmt = image_format(path)
    inst = traces[0].instance
    per_trace = [_frames_of(frames, tr.steps) for tr in traces]
    fit = max(1, (MAX_ROW_PX - GAP_PX) // (inst.width * cell + GAP_PX)) if len(traces) == 1 else math.inf
    cols = min(fit, max(len(f) for f in per_trace))
    panels, row = [], 0
    for tr, chosen in zip(traces, per_trace):
        for k, f in enumerate(chosen):
            panels.append((row + k // cols, k % cols, tr, f))
        row += math.ceil(len(chosen) / cols)
    painter = Painter(traces, row, cols, cell, frames=per_trace)
    try:
        used = {(r, c) for r, c, _, _ in panels}
        for r, line in enumerate(painter.axes):
            for c, ax in enumerate(line):
                ax.set_visible((r, c) in used)
        painter.draw(panels)
        write_with(path, lambda tmp: painter.fig.savefig(tmp, dpi=DPI, format=fmt), BilleError)
        return painter.layout
    finally:
        painter.close()


def _frames_of(spec: str | None, steps: int) -> list[int]:
    """The frames of one schedule: frame numbers past its end show its end, once."""
    if spec in (None, "auto", "all", "end"):
        return choose_frames(spec, steps)
    try:
        numbers = [int(part) for part in spec.split(",") if part.strip()]
    except ValueError:
        return choose_frames(spec, steps)  # says what is wrong
    if not numbers or min(numbers) < 0:
        return choose_frames(spec, steps)
    return list(dict.fromkeys(min(n, steps) for n in numbers))


def save_gif(traces: Sequence[Trace], path: str | Path, fps: float = 4.0, cell: int = 32, progress=None) -> Layout:
    """The whole schedule in time, one panel per schedule side by side. Written atomically."""
    from PIL import Image

    if fps <= 0:
        raise OptionError(f"--fps: must be positive, got {fps}")
    steps = max(t.steps for t in traces)
    painter = Painter(traces, 1, len(traces), cell)
    images = []
    try:
        for f in range(steps + 1):
            painter.draw([(0, c, tr, min(f, tr.steps)) for c, tr in enumerate(traces)])
            images.append(Image.fromarray(painter.image()).quantize(colors=64, dither=Image.Dither.NONE))
            if progress:
                progress(f + 1, steps + 1)
        duration = [int(1000 / fps)] * len(images)
        duration[-1] = max(duration[-1], 1500)  # rest on the final state
        write_with(path, lambda tmp: images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:],
                                                    duration=duration, loop=0), BilleError)
        return painter.layout
    finally:
        painter.close()
