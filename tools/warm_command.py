"""``bille warm``: compile the solvers' compiled parts ahead of the runs that use them."""
from __future__ import annotations

import time

import click

from .common import EXIT_OK


@click.command()
def warm() -> int:
    """Compile the solvers' compiled parts now (Numba): the exact joint search (bfs), LaCAM*'s
    configuration generator and SUO table, conflict-based search's low level (point robots) and
    the distances on large maps. Numba keeps the
    machine code beside the package (or in its user cache), so only the first run after an
    install compiles, a few seconds; this command is that first run, and later ones only load
    the code. It solves small instances (lt-4; room-32-32-4 with 20 agents, by LaCAM* and by
    conflict-based search) and prints the seconds each part took."""
    for name, part in (("the exact joint search (bfs)", _joint), ("LaCAM*'s generator and SUO table", _lacam),
                       ("conflict-based search's low level", _cbs)):
        began = time.perf_counter()
        part()
        click.echo(f"{name}: {time.perf_counter() - began:.1f} s")
    return EXIT_OK


def _joint() -> None:
    from bille.instances.bundled import bundled_path
    from bille.instances.instance import load_instance
    from bille.solvers import solve

    inst = load_instance(bundled_path("lt-4"))
    found = solve(inst, "bfs", cells="keep", engine="compiled")  # guided by the abstraction
    solve(inst, "bfs", cells="keep", engine="compiled", abstraction=False)  # from both ends
    solve(inst, "bfs", cells="keep", engine="compiled", abstraction=False, incumbent=found.schedule)  # forward


def _lacam() -> None:
    from bille.heuristics.lacam.scatter_compiled import warm_up
    from bille.instances.generators.movingai import from_movingai
    from bille.solvers import solve

    from .bench.maps import scenario_of, shipped_maps

    warm_up()
    folder = shipped_maps()
    inst = from_movingai(folder / "room-32-32-4.map", scenario_of(folder, "room-32-32-4"), agents=20)
    solve(inst, "lacam", improve=0.5)  # Numba is loaded: the compiled generator, distances and table


def _cbs() -> None:
    from bille.heuristics.cbs.mdd_compiled import warm_up
    from bille.instances.generators.movingai import from_movingai
    from bille.solvers import solve

    from .bench.maps import scenario_of, shipped_maps

    warm_up()
    folder = shipped_maps()
    inst = from_movingai(folder / "room-32-32-4.map", scenario_of(folder, "room-32-32-4"), agents=20)
    solve(inst, "cbs")  # Numba is loaded: the compiled low level from the first search
