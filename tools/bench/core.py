"""Benchmark of the core: validating a long schedule, compiling pose tables.

``bille bench core`` (or ``python -m bille.tools.bench_core``) prints, measured in the same run:

- validation of a random valid ``steps``-step schedule of ``robots`` robots on a ``size x size``
  structure with holes (so picks and places happen), against two baselines: parsing the
  schedule file, and a bare replay of the poses without any rule checks;
- compiling the S5, S7 and point pose tables of a ``compile_size`` square all-tile structure:
  time, table size and peak memory, against allocating tables of the same size.
"""
from __future__ import annotations

import random
import time
import tracemalloc

import numpy as np

from bille.instances import Grid, Instance, Robot, compile_posegraph, load_moveset, posegraph
from bille.instances.grid import is_connected
from bille.instances.rules import State, apply
from bille.solvers import Schedule, bind, dump_schedule, schedule_from_text, validate
from bille.instances.successors import candidate_actions


def holey_square(size: int, rnd: random.Random) -> np.ndarray:
    """Flat tile mask of a ``size`` square with about 8% holes, kept 4-connected."""
    n = size * size
    tiles = np.ones(n, dtype=bool)
    for c in rnd.sample(range(n), n // 12):
        tiles[c] = False
        if not is_connected(tiles, size, size):
            tiles[c] = True
    return tiles


def north_facing(tiles: np.ndarray, size: int, robots: int, rnd: random.Random) -> list[Robot]:
    """``robots`` biped starts heading north at random spots of a ``size`` square's tiles, feet
    apart (the caller makes sure they fit)."""
    placed, used = [], set()
    while len(placed) < robots:
        x, y = rnd.randrange(size), rnd.randrange(size - 1)
        f, b = (x, y), (x, y + 1)
        if tiles[y * size + x] and tiles[(y + 1) * size + x] and not {f, b} & used:
            placed.append(Robot(f, b))
            used |= {f, b}
    return placed


def random_instance(size: int, robots: int, seed: int) -> Instance:
    """An all-tile square with ~8% holes (kept connected) and robots on random free spots."""
    rnd = random.Random(seed)
    n = size * size
    tiles = holey_square(size, rnd)
    grid = Grid.from_masks(size, size, np.zeros(n, bool), tiles)
    placed, used = [], set()
    while len(placed) < robots:
        x, y = rnd.randrange(1, size - 1), rnd.randrange(1, size - 2)
        f, b = (x, y), (x, y + 1)
        if tiles[y * size + x] and tiles[(y + 1) * size + x] and not {f, b, (x, y - 1)} & used:
            placed.append(Robot(f, b))
            used |= {f, b, (x, y - 1)}
    return Instance("bench", load_moveset("S7"), grid, tuple(placed))


def random_walk(inst: Instance, steps: int, seed: int) -> Schedule:
    """A valid schedule by random moves checked with the rules.

    In the last 50 steps robots pick no more and prefer to place; if a robot still carries a
    tile after ``steps`` steps the walk goes on until none does.
    """
    rnd = random.Random(seed)
    state: State = inst.start_state
    columns = []
    wait = [ms.wait for ms in inst.movesets]
    t = 0
    while t < steps or any(state.carrying):
        finishing = t >= steps - 50
        t += 1
        choice = []
        for i in range(inst.num_robots):
            options = candidate_actions(inst, state, i)
            if finishing:  # put tiles down, pick no more
                kinds = inst.world.graphs[i].kind
                places = [a for a in options if kinds[a] == 3]
                options = places or [a for a in options if kinds[a] != 2]
            choice.append(rnd.choice(options))
        nxt = apply(inst.world, state, choice)
        if not isinstance(nxt, State):  # fall back to robots one by one, others waiting
            choice = list(wait)
            for i in rnd.sample(range(inst.num_robots), inst.num_robots):
                trial = list(choice)
                trial[i] = rnd.choice(candidate_actions(inst, state, i))
                if isinstance(apply(inst.world, state, trial), State):
                    choice = trial
            nxt = apply(inst.world, state, choice)
        columns.append(choice)
        state = nxt
    ids = np.array(columns, dtype=np.int64).T
    return Schedule.from_ids(inst, ids), state


def walk_instance(size: int = 64, robots: int = 20, steps: int = 1000, seed: int = 0) -> tuple[Instance, Schedule]:
    """A random instance and a valid random-walk schedule for it (the goal is where it ends)."""
    inst = random_instance(size, robots, seed)
    sched, final = random_walk(inst, steps, seed)
    goal = Grid.from_masks(size, size, inst.start.obstacles, final.tiles)
    return Instance(inst.name, inst.moveset, inst.start, inst.robots, goal=goal), sched


def bench_validate(size: int = 64, robots: int = 20, steps: int = 1000, seed: int = 0, repeat: int = 3) -> dict:
    inst, sched = walk_instance(size, robots, steps, seed)
    text = dump_schedule(sched)

    def best(fn):
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        return min(times), out

    t_parse, parsed = best(lambda: schedule_from_text(text))
    t_replay, _ = best(lambda: _bare_replay(inst, sched))
    t_validate, report = best(lambda: validate(inst, parsed))
    if not report.valid:
        raise RuntimeError(f"the benchmark's random walk is invalid: {report.violation}")
    return dict(size=size, robots=robots, steps=sched.length, valid=report.valid, metrics=report.metrics,
                t_parse=t_parse, t_replay=t_replay, t_validate=t_validate)


def _bare_replay(inst: Instance, sched: Schedule):
    """Baseline: follow the successor tables with no rule checks at all."""
    ids = bind(inst, sched)
    poses = np.array(inst.start_state.poses)
    g = inst.world.graphs[0]
    for t in range(ids.shape[1]):
        poses = g.succ[poses, ids[:, t]]
    return poses


def bench_compile(size: int = 128) -> list[dict]:
    out = []
    obstacles = np.zeros(size * size, dtype=bool)
    for name in ("S5", "S7", "point"):
        ms = load_moveset(name)
        tracemalloc.start()
        posegraph._CACHE.clear()  # time a real compilation, not a cache hit
        t0 = time.perf_counter()
        g = compile_posegraph(ms, size, size, obstacles)
        t_compile = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        t0 = time.perf_counter()
        _alloc = [np.full(getattr(g, f).shape, -1, dtype=getattr(g, f).dtype)
                  for f in ("feet", "valid", "succ", "coll", "carry", "carry_ok", "need", "target")]
        t_alloc = time.perf_counter() - t0
        out.append(dict(moveset=name, poses=g.num_poses, actions=g.num_actions, t_compile=t_compile,
                        t_alloc=t_alloc, table_mb=g.nbytes / 1e6, peak_mb=peak / 1e6))
        del g, _alloc
    return out


def report(size: int = 64, robots: int = 20, steps: int = 1000, compile_size: int = 128, seed: int = 0) -> list[str]:
    v = bench_validate(size, robots, steps, seed)
    m = v["metrics"]
    lines = [
        f"validate: {v['steps']} steps x {v['robots']} robots on {v['size']}x{v['size']} "
        f"(valid={v['valid']}, {m.tiles_traveled} motions, {m.picks} picks, {m.places} places)",
        f"  parse schedule text   {v['t_parse']*1e3:8.1f} ms   (baseline)",
        f"  bare pose replay      {v['t_replay']*1e3:8.1f} ms   (baseline, no rules)",
        f"  validate (all rules)  {v['t_validate']*1e3:8.1f} ms   = {v['t_validate']/v['t_parse']:.1f}x parse, "
        f"{v['t_validate']/v['t_replay']:.1f}x bare replay   [target < 1000 ms]",
        f"compile pose tables of a {compile_size}x{compile_size} all-tile structure:",
    ]
    for c in bench_compile(compile_size):
        lines.append(
            f"  {c['moveset']:<5} {c['poses']:>6} poses x {c['actions']:>2} actions: {c['t_compile']*1e3:7.1f} ms "
            f"(= {c['t_compile']/max(c['t_alloc'], 1e-9):.1f}x allocating the tables), tables {c['table_mb']:.1f} MB, "
            f"peak {c['peak_mb']:.1f} MB   [target < 2000 ms, < 100 MB]")
    return lines


def main() -> None:
    for line in report():
        print(line, flush=True)


if __name__ == "__main__":
    main()
