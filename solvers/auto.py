"""``auto``: the method picked by the instance, the default of ``bille solve``
(docs/decisions.md, "The solve() contract").

On a small joint state space the brute force (:mod:`.bfs`) gives the optimum with its proof,
where the time-expanded model may find nothing (tiny crowded maps with long schedules: a 3x3 map
with two robots and optimum 36, a 5x4 map with eight tiles and optimum 23); it gets a share of
the time limit (:data:`BFS_SHARE`), and if it runs out, anytime certified solving (:mod:`.anytime`)
takes the rest, starting from the depth the brute force proved. Otherwise anytime solving from
the start.

Classic MAPF instances (classic collisions: point robots on a fixed structure) go to conflict-based
search (:mod:`bille.heuristics.cbs`): the optimal sum of costs, the convention of MAPF benchmarks,
with proof; it gets :data:`CBS_SHARE` of the time limit, and if it runs out, LaCAM* finds a
schedule with the rest. The brute force is not used there: it explores picks and places that
cannot help on such a map, and its estimate counts none of the robots' interplay (two robots
swapping in libMultiRobotPlanning's ``mapf_swap2`` took it 30 s; CBS, 0.01 s).

The size of the joint state space is estimated, not counted (:func:`joint_states`): each robot's
poses on the start's tiles, with and without a load, times the ways of placing the tiles that
must move and one more among the free cells (a tile set aside). Measured with the compiled
search (``bille solve NAME -m bfs --time-limit 20``, 2-core machine): every bundled instance
with an estimate up to 6.3 x 10^7 is proved in 1.5 s or less (crowded-2, compare-2, corridor-2,
point-4, crowded-3, compare-3); from 3.5 x 10^8 up (bridge-2, bridge-3, reconfig-30, the
compare maps with four robots and more) it is not within 20 s, save lt-4 (11 s: the estimate
counts tiles that never move there), so the cut is :data:`SMALL`.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from bille.instances import Instance
from bille.instances.options import MethodOptions
from bille.instances.result import Result
from bille.instances.run import Run

from .estimate import joint_states

SMALL = 100_000_000  # estimated joint states up to which the brute force goes first
BFS_SHARE = 0.5  # of the time limit, at most, for the brute force before anytime takes over
CBS_SHARE = 0.5  # of the time limit, at most, for conflict-based search before LaCAM* takes over


@dataclass(frozen=True)
class AutoOptions(MethodOptions):
    """auto takes no options: it picks a method and runs it with that method's defaults."""

    METHOD = "auto"


def plan(instance: Instance, options: AutoOptions | None = None, run: Run | None = None, *, bounds=None) -> Result:
    """The brute force with proof on a small joint state space, anytime solving otherwise
    (module docstring); ``stats.auto`` says which method ran and why. The run's budget covers
    the whole run (``solve()`` gives 60 s unless told otherwise; no run: no limit); ``bounds``:
    the static bound from ``solve()``, handed on with what the brute force proved."""
    from . import anytime, bfs

    run = run or Run()
    budget = run.budget
    if instance.collisions == "classic" and not instance.is_reconfiguration:
        return _classic(instance, run)
    size = joint_states(instance)
    if instance.collisions == "classic":  # a classic reconfiguration: the brute force is the method that moves tiles
        found = bfs.plan(instance, run=run)
        return _told(found, {"method": "bfs", "why": "classic collisions with tiles to move: the brute force, the "
                                                   "method that plans them"})
    if size > SMALL:
        chosen = {"method": "anytime", "why": f"about {size:.1e} joint states, more than {SMALL:.0e}"}
        lower = None
    else:
        part = budget.share(BFS_SHARE)
        share = part.left()
        found = bfs.plan(instance, run=run.part(part))
        why = f"about {size:,.0f} joint states (at most {SMALL:,}): the brute force, with proof"
        if found.status not in ("timeout", "unsolved"):
            return _told(found, {"method": "bfs", "why": why})
        lower = found.lower_bound
        chosen = {"method": "anytime", "why": f"{why}, ran out of its {share:.0f} s ({found.failure}, "
                                               f"optimum above {lower - 1} steps); anytime with the rest"}
    if bounds is not None and lower is not None and lower > bounds.lower:
        bounds = dataclasses.replace(bounds, lower=lower, parts={**bounds.parts, "brute force": lower})
    result = anytime.plan(instance, run=run, bounds=bounds)
    if lower is not None and result.status != "infeasible" and (result.lower_bound or 0) < lower:
        result = dataclasses.replace(result, lower_bound=lower)
    return _told(result, chosen)


def _classic(instance: Instance, run: Run) -> Result:
    """Conflict-based search with its share of the time, LaCAM* with the rest (module docstring)."""
    from . import registry

    part = run.budget.share(CBS_SHARE)
    share = part.left()
    found = registry.METHODS["cbs"](instance, run=run.part(part))
    why = "classic MAPF: conflict-based search, optimal sum of costs with proof"
    if found.status not in ("timeout", "unsolved"):
        return _told(found, {"method": "cbs", "why": why})
    result = registry.METHODS["lacam"](instance, run=run)
    proved = found.claim.lower  # cbs's claim: the sum of costs, its bound proved
    if proved is not None and result.status != "optimal":
        result = dataclasses.replace(result, claim=found.claim)
    return _told(result, {"method": "lacam", "why": f"{why}, ran out of its {share:.0f} s (sum of costs at least "
                                                     f"{proved}); lacam with the rest"})


def _told(result: Result, chosen: dict) -> Result:
    """The result with ``stats.auto``: the method that ran and why."""
    return dataclasses.replace(result, stats={"auto": chosen, **result.stats})
