"""Benchmarks of the exact solvers (``bille bench exact``).

1. Time to the proved optimum of each bundled map, CP-SAT and SAT, as a scaling table
   (robots, tiles, makespan, model size, time) with the SAT / CP-SAT time ratio.
2. Connectivity: eager against lazy (time, cuts), ratio lazy / eager.
3. Pruning: model size at the optimal horizon with and without it, and the time to the optimum.
4. CP-SAT presolve on against off.
5. Before and after, on every bundled instance and both back ends: the encoding without the
   reachability in time with the tiles (``prune_tiles=false``, the encoding before it) against
   the current one: model size at the last horizon, each horizon's answer and time, and the time
   to the proved optimum (makespan only).
6. The SAT back end's solver and horizons per model (``chunk``): CaDiCaL with 8 (the default
   before) against Glucose and MiniSat, one horizon per model (the default now) and 8.
7. Where a proof's time goes: the infeasible horizon just below each optimum, for all schedules
   and for the two restrictions of the model (the structure kept, every tile carried once).
8. Where the model's size goes: variables and clauses per constraint family at those horizons.

Every run gets the same time limit; unfinished runs show their status instead of a time.
"""
from __future__ import annotations

import time

from bille.encodings.model import Options, build
from bille.instances import load_instance
from bille.instances.bundled import bundled_path
from bille.instances.run import Budget
from bille.solvers import solve

from ..common import solved

MAPS = ["crowded-3", "compare-2", "compare-3", "compare-4", "compare-5", "compare-6", "crowded-2", "point-4",
        "corridor-2", "reconfig-30"]
WITH_PICKS = ["point-4", "corridor-2", "reconfig-30"]


def _run(name, method, time_limit, **options):
    inst = load_instance(bundled_path(name))
    result = solved(solve(inst, method, time_limit=time_limit, **options))
    rows = result.stats.get("horizons") or [{}]
    last = next((h for h in rows if h.get("answer") == "sat"), rows[-1])  # the optimum's model, else the last
    return inst, result, last


def _time(result) -> str:
    return f"{result.time_s:.1f}" if result.status == "optimal" else result.status


def optimum_table(time_limit: float, threads: int, echo) -> None:
    echo(f"1. time to the proved optimum (CP-SAT {threads} threads, SAT Glucose 4.2; limit {time_limit:g} s per run)")
    echo(f"   {'map':<12} {'robots':>6} {'tiles':>5} {'moved':>5} {'T*':>4} {'vars':>8} {'clauses':>9} "
         f"{'cpsat [s]':>10} {'sat [s]':>9} {'sat/cpsat':>9}")
    for name in MAPS:
        inst, cp, last = _run(name, "cpsat", time_limit, threads=threads)
        _, sat, _ = _run(name, "sat", time_limit)
        moved = int((inst.start.tiles & ~inst.goal_tiles).sum()) + sum(r.carrying for r in inst.robots)
        makespan = cp.metrics.makespan if cp.metrics else (sat.metrics.makespan if sat.metrics else "-")
        ratio = f"{sat.time_s / cp.time_s:.2f}" if cp.status == sat.status == "optimal" else "-"
        echo(f"   {name:<12} {inst.num_robots:>6} {int(inst.start.tiles.sum()):>5} {moved:>5} {makespan:>4} "
             f"{last.get('variables', 0):>8} {last.get('clauses', 0):>9} {_time(cp):>10} {_time(sat):>9} {ratio:>9}")


def connectivity_table(time_limit: float, threads: int, echo) -> None:
    echo("2. connectivity: eager (reachability layers) against lazy (cuts), CP-SAT and SAT")
    echo(f"   {'map':<12} {'method':<6} {'eager [s]':>9} {'lazy [s]':>9} {'cuts':>6} {'lazy/eager':>10}")
    for name in WITH_PICKS:
        for method, opts in (("cpsat", {"threads": threads}), ("sat", {})):
            _, eager, _ = _run(name, method, time_limit, connectivity="eager", **opts)
            _, lazy, _ = _run(name, method, time_limit, connectivity="lazy", **opts)
            ratio = f"{lazy.time_s / eager.time_s:.2f}" if eager.status == lazy.status == "optimal" else "-"
            echo(f"   {name:<12} {method:<6} {_time(eager):>9} {_time(lazy):>9} {lazy.counters.cuts or 0:>6} {ratio:>10}")


def pruning_table(time_limit: float, threads: int, echo) -> None:
    echo("3. pruning (reachability, candidate cells, change windows) at the optimal horizon")
    echo(f"   {'map':<12} {'T*':>4} {'vars':>8} {'unpruned':>9} {'ratio':>6} {'clauses':>9} {'unpruned':>9} {'ratio':>6} "
         f"{'time [s]':>9} {'unpruned':>9}")
    for name in ("compare-4", "point-4", "corridor-2", "reconfig-30"):
        inst = load_instance(bundled_path(name))
        _, on, _ = _run(name, "cpsat", time_limit, threads=threads, minimize_travel=False)
        _, off, _ = _run(name, "cpsat", time_limit, threads=threads, minimize_travel=False, prune=False)
        T = on.metrics.makespan if on.metrics else on.lower_bound
        a = build(inst, T, Options()).size()
        b = build(inst, T, Options(prune_reach=False, prune_cells=False)).size()
        echo(f"   {name:<12} {T:>4} {a['variables']:>8} {b['variables']:>9} {a['variables'] / b['variables']:>6.2f} "
             f"{a['clauses']:>9} {b['clauses']:>9} {a['clauses'] / b['clauses']:>6.2f} {_time(on):>9} {_time(off):>9}")


def presolve_table(time_limit: float, threads: int, echo) -> None:
    echo("4. CP-SAT presolve (makespan search only)")
    echo(f"   {'map':<12} {'off [s]':>8} {'on [s]':>8} {'on/off':>7}")
    for name in ("compare-5", "corridor-2", "reconfig-30"):
        _, off, _ = _run(name, "cpsat", time_limit, threads=threads, minimize_travel=False)
        _, on, _ = _run(name, "cpsat", time_limit, threads=threads, minimize_travel=False, presolve=True)
        ratio = f"{on.time_s / off.time_s:.2f}" if on.status == off.status == "optimal" else "-"
        echo(f"   {name:<12} {_time(off):>8} {_time(on):>8} {ratio:>7}")


def before_after_table(time_limit: float, threads: int, echo) -> None:
    from bille.instances.bundled import bundled_names

    echo(f"5. before (prune_tiles=false) and after, every bundled instance (limit {time_limit:g} s per run)")
    echo(f"   {'map':<12} {'method':<6} {'run':<7} {'vars':>8} {'clauses':>9} {'time [s]':>9}  horizons (T answer s)")
    for name in bundled_names():
        for method, opts in (("cpsat", {"threads": threads}), ("sat", {})):
            times = {}
            for label, tiles in (("before", False), ("after", True)):
                _, result, last = _run(name, method, time_limit, minimize_travel=False, prune_tiles=tiles, **opts)
                times[label] = result
                steps = " ".join(f"{h['T']}{h['answer'][0]}{h['time_s']:.1f}" for h in result.stats.get("horizons", [])
                                 if "time_s" in h)
                echo(f"   {name:<12} {method:<6} {label:<7} {last.get('variables', 0):>8} {last.get('clauses', 0):>9} "
                     f"{_time(result):>9}  {steps}")
            before, after = times["before"], times["after"]
            if before.status == after.status == "optimal" and after.time_s > 0:
                echo(f"   {'':<12} {method:<6} {'before/after':<7} {before.time_s / after.time_s:.2f}")


SAT_CONFIGS = (("cadical195", 8), ("cadical195", 1), ("glucose42", 8), ("glucose42", 1), ("minisat22", 1))


def sat_solver_table(time_limit: float, threads: int, echo) -> None:
    echo(f"6. the SAT back end: solver and horizons per model (chunk); seconds to the proved optimal makespan "
         f"(limit {time_limit:g} s per run; before = cadical195, 8)")
    head = " ".join(f"{f'{s},{c}':>14}" for s, c in SAT_CONFIGS)
    echo(f"   {'map':<12} {head} {'before/default':>15}")
    for name in ("compare-5", "point-4", "corridor-2", "compare-6", "lt-4", "reconfig-30"):
        cells, times = [], {}
        for solver, chunk in SAT_CONFIGS:
            _, result, _ = _run(name, "sat", time_limit, solver=solver, chunk=chunk, minimize_travel=False)
            times[solver, chunk] = result.time_s if result.status == "optimal" else None
            cells.append(f"{result.time_s:>14.2f}" if result.status == "optimal" else f"{result.status:>14}")
        before, default = times[SAT_CONFIGS[0]], times["glucose42", 1]
        ratio = f"{before / default:.2f}" if before and default else "-"
        echo(f"   {name:<12} {' '.join(cells)} {ratio:>15}")


# maps and the horizon just below their proved optimum (docs/exact.md): the infeasible horizon
# whose proof decides each optimum
BELOW_OPTIMUM = (("corridor-2", 12), ("reconfig-30", 11), ("lt-4", 11), ("lt-7", 12), ("bridge-3", 14),
                 ("bridge-2", 22))
FREEDOMS = (("all", Options()), ("keep_structure", Options(keep_structure=True)),
            ("single_carry", Options(single_carry=True)))


def freedom_table(time_limit: float, threads: int, echo) -> None:
    from bille.encodings.backend import open_backend

    echo(f"7. where a proof's time goes: the horizon below the optimum, all schedules against those that keep "
         f"the structure (keep_structure) and those that carry every tile once (single_carry); one CP-SAT worker, "
         f"limit {time_limit:g} s")
    head = " ".join(f"{label:>30}" for label, _ in FREEDOMS)
    echo(f"   {'map':<12} {'T':>3} {head}   (vars, answer, seconds)")
    for name, T in BELOW_OPTIMUM:
        inst = load_instance(bundled_path(name))
        cells = []
        for _, options in FREEDOMS:
            model = build(inst, T, options)
            backend = open_backend("cpsat", model, inst)
            answer = backend.solve(budget=Budget(time_limit)).status
            cells.append(f"{model.num_vars:>9} {answer:>8} {backend.stats['solve_s']:>9.1f}")
        echo(f"   {name:<12} {T:>3} {' '.join(f'{c:>30}' for c in cells)}")


def families_table(time_limit: float, threads: int, echo) -> None:
    echo("8. where the model's size goes: variables / clauses per constraint family, at the horizon below the "
         "optimum (thousands)")
    for name, T in BELOW_OPTIMUM:
        model = build(load_instance(bundled_path(name)), T, Options())
        size = model.size()
        parts = "  ".join(f"{family} {part['variables'] / 1e3:.1f} / {part['clauses'] / 1e3:.1f}"
                          for family, part in model.families.items())
        echo(f"   {name:<12} T={T:<3} all {size['variables'] / 1e3:.1f} / {size['clauses'] / 1e3:.1f}:  {parts}")


def report(time_limit: float = 120.0, threads: int = 2, sections=("optimum", "connectivity", "pruning", "presolve"),
           echo=print) -> None:
    start = time.perf_counter()
    tables = {"optimum": optimum_table, "connectivity": connectivity_table, "pruning": pruning_table,
              "presolve": presolve_table, "before-after": before_after_table, "sat-solver": sat_solver_table,
              "freedom": freedom_table, "families": families_table}
    for key in sections:
        tables[key](time_limit, threads, echo)
        echo("")
    echo(f"total {time.perf_counter() - start:.0f} s")
