"""Pictures of schedules with matplotlib (``bille view --png`` and ``--gif``).

The drawing conventions are those of the recording (:mod:`.style`). A picture is a table of
panels, each one frame of one schedule; every panel has ``cell`` pixels per grid cell, a title
band above it and a gap around it, and the legend runs along the bottom, so that the pixel of
every cell is known (:meth:`Layout.cell_center`): tests read colors there.

- PNG: one row per schedule, one column per chosen frame (a strip; one frame is a strip of one).
- GIF: one row with one panel per schedule, side by side, all frames in time.
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
TITLE_PX, GAP_PX, LEGEND_ROW_PX, LEGEND_ITEM_PX = 22, 10, 22, 130


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

    def __init__(self, traces: Sequence[Trace], rows: int, cols: int, cell: int = 32) -> None:
        if cell < 4:
            raise OptionError(f"--cell: at least 4 pixels per cell, got {cell}")
        inst = traces[0].instance
        self.traces = traces
        self.legend = self._legend_items(traces)
        probe = Layout(rows, cols, inst.width, inst.height, cell, 1)
        per_row = max(1, probe.size_px[0] // LEGEND_ITEM_PX)
        self.layout = Layout(rows, cols, inst.width, inst.height, cell, math.ceil(len(self.legend) / per_row))
        w, h = self.layout.size_px
        if w * h > 60_000_000:
            raise OptionError(f"the picture would be {w}x{h} pixels: choose fewer frames or a smaller --cell")
        self.fig = plt.figure(figsize=(w / DPI, h / DPI), dpi=DPI, facecolor="white")
        self.axes = [[self._axes(r, c) for c in range(cols)] for r in range(rows)]
        self.fig.legend(handles=self.legend, loc="lower center", ncol=per_row, frameon=False, fontsize=8,
                        bbox_to_anchor=(0.5, 0.0), handlelength=1.5, columnspacing=1.0)

    def _axes(self, r: int, c: int):
        w, h = self.layout.size_px
        pw, ph = self.layout.panel_px
        ox, oy = self.layout.panel_origin(r, c)
        ax = self.fig.add_axes((ox / w, 1 - (oy + ph) / h, pw / w, ph / h))
        ax.set_axis_off()
        return ax

    @staticmethod
    def _legend_items(traces: Sequence[Trace]) -> list:
        items = [Patch(facecolor=_rgb(style.TILE), label="tile"), Patch(facecolor=_rgb(style.OBSTACLE), label="obstacle")]
        inst = traces[0].instance
        if (inst.goal_tiles & ~inst.start.tiles).any():
            items.append(Patch(facecolor="none", edgecolor=_rgb(style.GOAL_FILL), linewidth=2, label="goal: add a tile"))
        if (inst.start.tiles & ~inst.goal_tiles).any():
            items.append(Patch(facecolor="none", edgecolor=_rgb(style.GOAL_CLEAR), linewidth=2, label="goal: remove"))
        items.append(Patch(facecolor=_rgb(style.ROBOTS[0], 0.3), label="cells swept"))
        for i in range(inst.num_robots):
            items.append(Line2D([], [], color=_rgb(style.robot_color(i)), marker="o", linewidth=3,
                                label=f"robot {style.robot_name(i)}"))
        if any(t.violation is not None for t in traces):
            items.append(Patch(facecolor="none", edgecolor=_rgb(style.VIOLATION), linewidth=2, label="violation"))
        return items

    def draw(self, panels: Sequence[tuple[int, int, Trace, int]]) -> None:
        """Draw frame ``t`` of ``trace`` in panel ``(row, col)`` for each ``(row, col, trace, t)``."""
        for r, c, tr, t in panels:
            ax = self.axes[r][c]
            ax.clear()
            ax.set_axis_off()
            _draw_frame(ax, tr, t)

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
        _draw_robot(ax, tr, t, i, lw)
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

def save_png(traces: Sequence[Trace], path: str | Path, frames: str | None = None, cell: int = 32) -> Layout:
    """A strip: one row per schedule, the chosen frames as columns. Written atomically."""
    steps = max(t.steps for t in traces)
    chosen = choose_frames(frames, steps)
    painter = Painter(traces, len(traces), len(chosen), cell)
    try:
        painter.draw([(r, c, tr, min(f, tr.steps)) for r, tr in enumerate(traces) for c, f in enumerate(chosen)])
        write_with(path, lambda tmp: painter.fig.savefig(tmp, dpi=DPI, format="png"), BilleError)
        return painter.layout
    finally:
        painter.close()


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
