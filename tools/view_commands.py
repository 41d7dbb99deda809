"""The ``view`` command: rerun recordings, pictures and animations of schedules."""
from __future__ import annotations

from pathlib import Path

import click

from .common import (EXIT_NO, EXIT_OK, instance_arg, label_of, record_traces, schedule_for, stderr_console, trace_of,
                     unique, writable)


@click.command()
@click.argument("instance")
@click.argument("schedules", nargs=-1)
@click.option("--rerun", "rrd", type=click.Path(dir_okay=False), metavar="OUT.rrd",
              help="Write a rerun recording (schedules side by side; open it with 'rerun OUT.rrd').")
@click.option("--spawn", is_flag=True, help="Also open the rerun viewer, where a display exists.")
@click.option("--png", type=click.Path(dir_okay=False), metavar="OUT.png",
              help="Write a picture (.png, .jpg, .pdf, .svg, ...: the format the suffix names): one row per "
                   "schedule, the chosen frames side by side (one schedule alone wraps into rows).")
@click.option("--gif", type=click.Path(dir_okay=False), metavar="OUT.gif",
              help="Write an animation of the whole schedule(s).")
@click.option("--frames", default="auto", show_default=True,
              help="Frames of the PNG: auto (start, end, three between), all, end, or numbers like 0,5,9.")
@click.option("--fps", type=click.FloatRange(min=0.1, max=50), default=4.0, show_default=True, help="GIF frames per second.")
@click.option("--cell", type=click.IntRange(4, 256), default=32, show_default=True, help="Pixels per grid cell.")
@click.option("--label", "labels", multiple=True, help="A name per schedule, in order (default: the file names).")
def view(instance: str, schedules, rrd, spawn: bool, png, gif, frames: str, fps: float, cell: int, labels) -> int:
    """Look at SCHEDULES (any number, none for the instance alone) on INSTANCE: a rerun
    recording, a picture or an animation (exit 1 if a schedule breaks a rule)."""
    if not (rrd or spawn or png or gif):
        raise click.UsageError("nothing to do: give --rerun, --spawn, --png or --gif")
    if labels and len(labels) != len(schedules):
        raise click.BadParameter(f"{len(labels)} labels for {len(schedules)} schedules", param_hint="--label")
    writable(rrd, png, gif)
    inst = instance_arg(instance)
    names = list(labels) or unique([label_of(arg) for arg in schedules])
    traces = [trace_of(inst, schedule_for(arg, inst), name) for arg, name in zip(schedules, names)] or [trace_of(inst, None, inst.name)]
    if gif and Path(gif).suffix.lower() not in ("", ".gif"):
        raise click.BadParameter(f"{gif}: an animation is written as .gif", param_hint="--gif")
    if png:
        from .pictures import choose_frames, image_format

        image_format(png)  # a bad suffix or --frames fails before any file is written
        choose_frames(frames, max(t.steps for t in traces))
    if rrd or spawn:
        record_traces(traces, rrd, spawn=spawn)
    if png:
        from .pictures import save_png

        layout = save_png(traces, png, frames, cell)
        click.echo(f"picture written to {png} ({layout.size_px[0]}x{layout.size_px[1]} pixels)")
    if gif:
        from rich.progress import Progress

        from .pictures import save_gif

        with Progress(transient=True, console=stderr_console()) as bar:
            task = bar.add_task("drawing frames", total=max(t.steps for t in traces) + 1)
            layout = save_gif(traces, gif, fps, cell, progress=lambda done, total: bar.update(task, completed=done))
        click.echo(f"animation written to {gif} ({max(t.steps for t in traces) + 1} frames)")
    bad = [t for t in traces if t.violation is not None]
    for t in bad:
        click.echo(f"{t.label}: invalid: {t.violation}")
    return EXIT_NO if bad else EXIT_OK
