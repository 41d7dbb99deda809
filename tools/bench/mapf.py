"""Classic MAPF on MovingAI benchmarks (``bille bench mapf``), and LaCAM* at scale (``bille bench
lacam``).

MAPF: each map with its ``random-1`` scenario, the first ``k`` agents for growing ``k``, under
classic collisions (docs/rules.md), solved by ``lacam``: success, sum of costs (each agent's last
arrival at its goal), makespan and time. The baseline of the same run is the sum of the agents'
shortest-path lengths, a lower bound on the sum of costs: the ratio says how far above it the
schedule is.

Scale: S7 robots with random goal cells on a fully tiled square: time to the first schedule.
"""
from __future__ import annotations

import random
from pathlib import Path

import numpy as np

from bille.instances import Grid, Instance, InstanceError, check_instance, load_moveset
from bille.instances.generators.movingai import from_movingai
from bille.instances.metrics import sum_of_costs as metrics_soc
from bille.instances.schedule import bind
from bille.instances.walking import walk_for
from bille.solvers import solve

from ..common import solved
from .maps import SCENARIO
from ..tables import text_table
from .core import north_facing

MAPS = ("random-32-32-10", "room-32-32-4", "warehouse-10-20-10-2-1", "random-64-64-20")
AGENTS = (50, 100, 200, 300, 400)
def map_names(folder: Path) -> list[str]:
    """The maps of ``folder`` that have a ``random-1`` scenario, sorted."""
    return sorted(p.name[: -len(SCENARIO)] for p in folder.glob(f"*{SCENARIO}") if (folder / p.name.replace(
        SCENARIO, ".map")).is_file())


def sum_of_costs(instance: Instance, schedule) -> int:
    """Each robot's cost is the step after which it stands on its goal for good (0 if it never
    leaves it); robots without a goal cost nothing (:func:`bille.instances.metrics.sum_of_costs`)."""
    return metrics_soc(instance, bind(instance, schedule)) or 0


def lower_soc(instance: Instance) -> int:
    """The summed shortest-path lengths of the robots alone: a lower bound on the sum of costs."""
    tiles, total = instance.start.tiles, 0
    for i, (g, pose) in enumerate(zip(instance.world.graphs, instance.start_state.poses)):
        if instance.goal_cells[i] >= 0:
            total += int(walk_for(g, tiles).distances(instance.goal_cells[i])[pose])
    return total


def mapf_rows(folder: Path, maps=MAPS, agents=AGENTS, time_limit: float = 60.0, improve: float = 0.0,
              peers: dict | None = None):
    """Yield one result row per map and agent count, as soon as it is measured; with ``peers``
    (:func:`.peers.available`), each peer's row under ``row["peers"][name]``, run right after
    bille's on the same agents (interleaved, so that a loaded machine weighs on both alike), and
    bille warmed up first on two agents (its lazily imported modules and its compiled SUO table
    loaded, as the peers' own times leave out their start)."""
    from .peers import run_lacam3, run_pypibt

    if peers and maps:  # the peers' times leave out their start: bille's leave out its imports
        from bille.heuristics.lacam.scatter_compiled import warm_up

        warm = from_movingai(folder / f"{maps[0]}.map", folder / f"{maps[0]}{SCENARIO}", agents=2)
        solve(warm, "lacam", objective="sum-of-loss", time_limit=time_limit, improve=0.0)
        warm_up()
    for name in maps:
        map_file, scen = folder / f"{name}.map", folder / f"{name}{SCENARIO}"
        for k in agents:
            try:
                inst = from_movingai(map_file, scen, agents=k)
            except InstanceError as exc:  # the scenario has fewer agents on this map
                yield dict(map=name, agents=k, status="skipped", reason=str(exc))
                continue
            # sum of loss: lacam3's objective, whose improvements lower the sum of costs
            result = solved(solve(inst, "lacam", objective="sum-of-loss", time_limit=time_limit, improve=improve))
            row = dict(map=name, agents=k, status=result.status, time_s=result.time_s,
                       first_s=result.counters.first_s, scatter_s=result.counters.scatter_s,
                       lower=lower_soc(inst), peers={})
            if result.schedule is not None:
                row.update(soc=sum_of_costs(inst, result.schedule), makespan=result.metrics.makespan)
            if peers and "lacam3" in peers:
                row["peers"]["lacam3"] = run_lacam3(peers["lacam3"], map_file, scen, k, inst,
                                                    seconds=max(1, round(improve or time_limit)), anytime=improve > 0)
            if peers and "pypibt" in peers:
                row["peers"]["pypibt"] = run_pypibt(peers["pypibt"], map_file, scen, k, inst)
            yield row


def mapf_table(rows: list[dict]) -> list[str]:
    table = []
    for r in rows:
        solved = "soc" in r
        table.append([r["map"], str(r["agents"]), r["status"],
                      str(r["soc"]) if solved else "-", str(r["lower"]) if "lower" in r else "-",
                      f"{r['soc'] / r['lower']:.3f}" if solved and r.get("lower") else "-",
                      str(r["makespan"]) if solved else "-",
                      f"{r['first_s']:.3f}" if r.get("first_s") is not None else "-",
                      f"{r['time_s']:.2f}" if "time_s" in r else "-"])
    columns = ["map", "agents", "status", "sum of costs", "SOC lower bound", "ratio", "makespan",
               "first [s]", "total [s]"]
    return text_table(columns, table, right=set(columns[1:]) - {"status"})


def full_square(size: int, robots: int, seed: int = 0) -> Instance:
    """``robots`` S7 robots (heading north) on a fully tiled ``size`` square, random goal cells."""
    rnd = random.Random(seed)
    n = size * size
    tiles = np.ones(n, dtype=bool)
    grid = Grid.from_masks(size, size, np.zeros(n, dtype=bool), tiles)
    if 2 * robots > n:
        raise InstanceError(f"{robots} robots do not fit on a {size}x{size} square")
    placed = north_facing(tiles, size, robots, rnd)
    goals = tuple(grid.xy(c) for c in rnd.sample(range(n), robots))
    return check_instance(Instance(f"square-{size}-{robots}", load_moveset("S7"), grid, tuple(placed),
                                   robot_goals=goals))


def scale_rows(size: int, robot_counts, seed: int = 0):
    for robots in robot_counts:
        inst = full_square(size, robots, seed)
        result = solved(solve(inst, "lacam", improve=0.0, time_limit=120))
        yield dict(robots=robots, status=result.status, first_s=result.counters.first_s, time_s=result.time_s,
                   makespan=result.metrics.makespan if result.metrics else None, nodes=result.counters.nodes)
