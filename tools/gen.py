"""``bille gen``: generators on the command line; each writes one instance file (or prints it)."""
from __future__ import annotations

import json

import click

from bille.instances import InstanceError, dump_instance, save_instance

from .common import writable

EXIT_OK = 0


def _output(inst, output: str | None, as_json: bool) -> int:
    if output:
        save_instance(inst, output)
    if as_json:
        click.echo(json.dumps(summary(inst, output)))
    elif output:
        click.echo(f"{inst.name}: written to {output}")
    else:
        click.echo(dump_instance(inst), nl=False)
    return EXIT_OK


def summary(inst, path: str | None = None) -> dict:
    """The instance's sizes, as ``--json`` prints them; ``written_to``: the file written (None
    when the instance was printed)."""
    moved = int((inst.start.tiles != inst.goal_tiles).sum()) // 2
    return {"name": inst.name, "written_to": path, "width": inst.width, "height": inst.height,
            "moveset": inst.moveset.name, "robots": inst.num_robots, "tiles": int(inst.start.tiles.sum()),
            "moved": moved, "tasks": None if inst.tasks is None else len(inst.tasks),
            "kind": "reconfiguration" if inst.is_reconfiguration else "path planning", "meta": inst.meta}


def common(f):
    f = click.option("--json", "as_json", is_flag=True, help="Print the instance's summary as one JSON object.")(f)
    f = click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the instance here (default: print it).")(f)
    f = click.option("--seed", type=int, default=0, show_default=True)(f)
    return f


@click.group("gen")
def gen() -> None:
    """Generate instances: random and paper-style maps, MovingAI imports, grid graphs."""


@gen.command("random")
@click.option("--width", type=click.IntRange(min=1), default=10, show_default=True)
@click.option("--height", type=click.IntRange(min=1), default=8, show_default=True)
@click.option("--tiles", type=click.IntRange(min=1), default=30, show_default=True)
@click.option("--robots", type=click.IntRange(min=0), default=2, show_default=True)
@click.option("--moved", type=click.IntRange(min=0), default=3, show_default=True, help="Tiles the goal moves.")
@click.option("--moveset", default="S7", show_default=True)
@click.option("--tasks", is_flag=True, help="Add the task list: a sequence that keeps the tiles connected.")
@common
def gen_random(width, height, tiles, robots, moved, moveset, tasks, seed, output, as_json) -> int:
    """A random connected structure, robots on it, a goal that moves some tiles."""
    from bille.instances.generators.random import random_reconfiguration

    return _output(random_reconfiguration(width, height, tiles, robots, moved, seed=seed, moveset=moveset,
                                          tasks=tasks), output, as_json)


@gen.command("crowded")
@click.option("--width", type=click.IntRange(min=1), default=6, show_default=True)
@click.option("--height", type=click.IntRange(min=1), default=4, show_default=True)
@click.option("--robots", type=click.IntRange(min=2), default=3, show_default=True)
@click.option("--holes", type=float, default=0.1, show_default=True, help="Fraction of the block left without tiles.")
@click.option("--moveset", default="S7", show_default=True)
@common
def gen_crowded(width, height, robots, holes, moveset, seed, output, as_json) -> int:
    """Robots packed on a small structure, each with another robot's start as its goal."""
    from bille.instances.generators.random import crowded

    return _output(crowded(width, height, robots, holes=holes, seed=seed, moveset=moveset), output, as_json)


@gen.command("corridor")
@click.option("--length", type=click.IntRange(min=1), default=6, show_default=True, help="Corridor tiles.")
@click.option("--robots", type=click.IntRange(min=1), default=2, show_default=True)
@click.option("--room", type=click.IntRange(min=2), default=3, show_default=True, help="Side of each room.")
@click.option("--moved", type=click.IntRange(min=0), default=0, show_default=True,
              help="Tiles to carry from the left room to the right (0: robots swap rooms instead).")
@click.option("--moveset", default="S7", show_default=True)
@common
def gen_corridor(length, robots, room, moved, moveset, seed, output, as_json) -> int:
    """Two rooms joined by a one-tile-wide corridor where robots meet head on."""
    from bille.instances.generators.random import corridor

    return _output(corridor(length, robots, room=room, moved=moved, seed=seed, moveset=moveset), output, as_json)


def _counts(text: str, option: str) -> tuple[int, ...]:
    """A comma-separated list of integers (an empty text: none)."""
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise click.BadParameter(f"expected integers separated by commas, got {text!r}", param_hint=option) from None


@gen.command("bridges")
@click.option("--platforms", type=click.IntRange(min=2, max=100), default=2, show_default=True)
@click.option("--size", default="4x4", show_default=True, help="Each platform's tiles, WIDTHxHEIGHT.")
@click.option("--gap", type=click.IntRange(min=1), default=6, show_default=True,
              help="Columns between two platforms (each bridge's length).")
@click.option("--bays", default="3", show_default=True,
              help="Bays on each bridge: offsets from its first column, comma-separated ('' for none).")
@click.option("--moved", type=click.IntRange(min=1), default=4, show_default=True,
              help="Tiles of the west platform's first column, from the top, built beside the east platform.")
@click.option("--robots", default=None, help="Robots per platform, west first, comma-separated (default: 1 each).")
@click.option("--moveset", default="S7", show_default=True)
@click.option("--tasks", is_flag=True, help="Add the paper's building sequence: each tile straight across.")
@click.option("--json", "as_json", is_flag=True, help="Print the instance's summary as one JSON object.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the instance here (default: print it).")
def gen_bridges(platforms, size, gap, bays, moved, robots, moveset, tasks, as_json, output) -> int:
    """The load-transfer maps' family: platforms joined by bridges one tile wide with bays; the
    west platform's first column is built beside the east one. The defaults make lt-1."""
    from bille.instances.generators.bridges import bridges

    try:
        width, height = (int(v) for v in size.lower().split("x"))
    except ValueError:
        raise click.BadParameter(f"expected WIDTHxHEIGHT, got {size!r}", param_hint="--size") from None
    counts = _counts(robots, "--robots") if robots is not None else None
    inst = bridges(platforms=platforms, width=width, height=height, gap=gap, bays=_counts(bays, "--bays"),
                   moved=moved, robots=counts, moveset=moveset, tasks=tasks)
    return _output(inst, output, as_json)


@gen.command("movingai")
@click.argument("map_file", metavar="MAP")
@click.argument("scen", required=False)
@click.option("--agents", "-k", type=int, required=True, help="Number of robots.")
@click.option("--collisions", type=click.Choice(["classic", "bille"]), default="classic", show_default=True,
              help="Classic MAPF collisions (following allowed) or the Bill-E rule (docs/rules.md).")
@common
def gen_movingai(map_file, scen, agents, collisions, seed, output, as_json) -> int:
    """A MovingAI .map (+ .scen) as point robots on an all-tile structure. MAP may name a map
    shipped with bille (bille list --maps: random-32-32-10, room-32-32-4, ...); its first
    scenario is then used unless SCEN is given."""
    from bille.instances.generators.movingai import from_movingai

    map_file, scen = shipped_map(map_file, scen)
    return _output(from_movingai(map_file, scen, agents=agents, seed=seed, collisions=collisions), output, as_json)


def shipped_map(name: str, scen: str | None) -> tuple[str, str | None]:
    """``name`` as a path: the file if it exists, else the MovingAI map shipped under that name
    (with its first scenario when ``scen`` is None)."""
    from pathlib import Path

    from .bench.maps import scenario_of, shipped_maps

    if Path(name).exists():
        return name, scen
    folder = shipped_maps()
    stem = name[:-4] if name.endswith(".map") else name
    path = folder / f"{stem}.map"
    if "/" in stem or not path.is_file():
        return name, scen
    first = scenario_of(folder, stem)
    return str(path), scen if scen is not None or not first.is_file() else str(first)


def _graph(graph_file, vertices, seed):
    """The grid graph of a GRAPH file or a random one of ``vertices`` vertices; connected."""
    import networkx as nx

    from bille.instances.generators.graphs import load_graph, random_grid_graph

    if (graph_file is None) == (vertices is None):
        raise click.UsageError("give a GRAPH file or --vertices N (not both)")
    g = load_graph(graph_file) if graph_file else random_grid_graph(vertices, seed)
    if not nx.is_connected(g):
        raise InstanceError(f"{graph_file}: the graph is not connected ({nx.number_connected_components(g)} parts)")
    return g


def _vertex(text: str | None, option: str = "--start"):
    if text is None:
        return None
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise click.BadParameter(f"expected X,Y (two integers), got {text!r}", param_hint=option) from None
    return (x, y)


@gen.command("hampath")
@click.argument("graph_file", metavar="[GRAPH]", required=False)
@click.option("--vertices", type=int, help="Use a random connected grid graph of this many vertices instead.")
@click.option("--scale", "-s", type=click.IntRange(min=1), default=1, show_default=True,
              help="Edge tiles between two gadgets (vertex tiles are s + 7 apart).")
@click.option("--start", metavar="X,Y", help="The graph vertex the robot starts at (default: a vertex of degree 1, "
                                             "else the first).")
@click.option("--robots", "-r", type=click.IntRange(min=1), default=1, show_default=True,
              help="Corollary 1: this many copies, one robot each.")
@click.option("--moveset", default="point", show_default=True)
@click.option("--search", is_flag=True, help="Also decide by exhaustive search whether the optimal makespan is the "
                                             "bound (small graphs only; one robot, point); the verdict goes to stderr.")
@click.option("--schedule", "schedule_file", type=click.Path(dir_okay=False),
              help="With --search: write the optimal schedule found here.")
@common
def gen_hampath(graph_file, vertices, scale, start, robots, moveset, search, schedule_file, seed, output,
                as_json) -> int:
    """Theorem 1's reduction from Hamiltonian path: a vertex gadget per vertex of GRAPH, edge
    tiles between adjacent ones; the bound (s + 7)(|V| - 1) + t_g |V| is in the metadata.

    With --search, the metadata also get the answer: 'optimum' (a schedule within the bound
    exists; the shortest is optimal) or 'lower_bound' (none within the bound: bound + 1), which
    'bille gap' shows as the file's claim."""
    from bille.instances.generators.hampath import reduction, search_optimum

    if schedule_file and not search:
        raise click.UsageError("--schedule needs --search (the schedule is the one the search finds)")
    writable(output, schedule_file)
    inst = reduction(_graph(graph_file, vertices, seed), scale, start=_vertex(start), robots=robots,
                     moveset=moveset)
    if search:
        if robots != 1 or inst.meta["bound"] is None:
            raise click.UsageError("--search takes one robot with the point moveset")
        bound = inst.meta["bound"]
        found = search_optimum(inst, bound)
        inst.meta["optimal_is_bound"] = found is not None and found.length == bound
        if found is None:
            inst.meta["lower_bound"] = bound + 1
            click.echo(f"{inst.name}: no schedule within the bound {bound}: the optimal makespan is at least "
                       f"{bound + 1} (no Hamiltonian path from the start vertex)", err=True)
        else:
            inst.meta["optimum"] = found.length
            click.echo(f"{inst.name}: optimal makespan {found.length} (the bound is {bound}; "
                       f"{'equal' if found.length == bound else 'below it'})", err=True)
            if schedule_file:
                from bille.instances.schedule import save_schedule

                save_schedule(found, schedule_file)
                click.echo(f"{inst.name}: optimal schedule written to {schedule_file}", err=True)
        if schedule_file and found is None:
            click.echo(f"{inst.name}: no schedule to write to {schedule_file}", err=True)
    return _output(inst, output, as_json)


@gen.command("coop")
@click.argument("graph_file", metavar="[GRAPH]", required=False)
@click.option("--vertices", type=int, help="Attach to a random connected grid graph of this many vertices.")
@click.option("--scale", "-s", type=click.IntRange(min=1), default=1, show_default=True,
              help="Edge tiles between two vertex gadgets (with a graph).")
@click.option("--start", metavar="X,Y", help="The vertex robot 1 starts at (with a graph).")
@click.option("--end", metavar="X,Y", help="The vertex whose upper arm leads to the gadget; no vertex may be above "
                                           "it (default: such a vertex of degree 1 if there is one).")
@click.option("--gap", type=click.IntRange(min=2), default=2, show_default=True,
              help="Cells from an entry to its side's nearest small task.")
@click.option("--search", is_flag=True, help="With a graph: also find each robot's earliest arrival at the gadget by "
                                             "exhaustive search (small graphs only).")
@click.option("--schedule", "schedule_file", type=click.Path(dir_okay=False),
              help="The gadget alone: also write the schedule that splits the large task here (and the "
                   "instance beside it as NAME.instance.yaml, unless -o names a file).")
@common
def gen_coop(graph_file, vertices, scale, start, end, gap, search, schedule_file, seed, output, as_json) -> int:
    """Theorem 2's cooperative gadget: alone (no GRAPH), or attached to Theorem 1's
    construction for GRAPH; the metadata give the arrival time and the bound."""
    from bille.instances.generators.coop import approaches, attached, demonstration, gadget

    if graph_file is None and vertices is None:
        if start or end or search:
            raise click.UsageError("--start, --end and --search need a GRAPH or --vertices")
        if schedule_file:
            from pathlib import Path

            from bille.instances.schedule import Schedule, identity, save_schedule

            if not output:  # the pair is checked together: the instance goes beside its schedule
                path = Path(schedule_file)
                output = str(path.with_name(path.name.split(".")[0] + ".instance.yaml"))
            writable(output, schedule_file)
            save_schedule(Schedule(demonstration(gap), meta={"method": "demonstration (gen coop)"},
                                   instance=identity(gadget(gap))), schedule_file)
            click.echo(f"schedule written to {schedule_file}; check it with: bille check {output} {schedule_file}",
                       err=True)
        return _output(gadget(gap), output, as_json)
    if schedule_file:
        raise click.UsageError("--schedule is for the gadget alone (no GRAPH)")
    g = _graph(graph_file, vertices, seed)
    kw = {"start": _vertex(start), "end": _vertex(end, "--end"), "gap": gap}
    inst = attached(g, scale, **kw)
    if search:
        from bille.instances.generators.hampath import search_optimum

        arrivals = []
        for way in approaches(g, scale, **kw):
            found = search_optimum(way, inst.meta["arrival"])
            arrivals.append(None if found is None else found.length)
        inst.meta["arrivals_within_bound"] = arrivals
        inst.meta["on_time"] = arrivals == [inst.meta["arrival"]] * 2
    return _output(inst, output, as_json)


@gen.command("graph")
@click.argument("graph_file", metavar="[GRAPH]", required=False)
@click.option("--vertices", type=int, help="Generate a random connected grid graph of this many vertices.")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("-o", "--output", type=click.Path(dir_okay=False), help="Write the graph drawing here.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def gen_graph(graph_file, vertices, seed, output, as_json) -> int:
    """Read GRAPH (a drawing with 'o' or lines 'x y') or make a random grid graph, and decide
    whether it has a Hamiltonian path."""
    from bille.instances.generators.graphs import draw_graph, hamiltonian_path
    from bille.instances.files import write_atomic

    g = _graph(graph_file, vertices, seed)
    path = hamiltonian_path(g)
    drawing = draw_graph(g)
    if output:
        write_atomic(output, drawing, InstanceError)
    if as_json:
        click.echo(json.dumps({"vertices": g.number_of_nodes(), "edges": g.number_of_edges(),
                               "hamiltonian_path": None if path is None else [list(v) for v in path],
                               "written_to": output}))
        return EXIT_OK
    click.echo(drawing, nl=False)
    click.echo(f"{g.number_of_nodes()} vertices, {g.number_of_edges()} edges; Hamiltonian path: "
               + ("none" if path is None else " ".join(f"({x},{y})" for x, y in path)))
    return EXIT_OK
