"""The method ``lacam`` as ``solve()`` runs it: LaCAM* on a fixed structure; on an instance that
moves tiles, the reconfiguration loop with LaCAM* as its motion layer, then LaCAM* over whole
states where the loop gives up."""
from __future__ import annotations

from bille.instances import Instance, OptionError
from bille.instances.result import Result
from bille.instances.run import Run

from .search import Options, plan

# of the time limit, at most, for the loop before the complete search takes over: the loop
# either finishes in a second or two or not at all (measured on a random 10x8 instance with four
# robots and ten moved tiles, `bille gen random --robots 4 --moved 10 --seed 2`: its motion layer
# finds no joint plan in 60 s, where the whole-state search finds a schedule in 17 s)
LOOP_SHARE = 0.5


def method(instance: Instance, options: Options | None = None, run: Run | None = None) -> Result:
    """LaCAM* (:func:`.search.plan`). On an instance that moves tiles, the reconfiguration loop
    with LaCAM* as its motion layer (``load_transfer``, ``d_tr``, ``max_steps``, ``active`` as
    for the loop), and where the loop gives up, or runs out of its share of the time limit
    (:data:`LOOP_SHARE`), LaCAM* over whole states (every robot taking jobs; :mod:`.states`) with
    the time left: complete, so the method finds a schedule whenever one exists (time and memory
    permitting) and proves ``infeasible`` when its space is exhausted. ``objective`` is for path
    planning; ``improve``, ``max_nodes`` and ``seed`` for the searches over configurations."""
    o = options or Options()
    if not instance.is_reconfiguration:
        return plan(instance, o, run)
    from ..loop import reconfigure
    from . import states  # (and scipy's graph routines) for an instance that moves tiles

    if instance.collisions == "classic":
        raise OptionError(f"lacam: instance '{instance.name}' moves tiles under classic collisions; "
                          "the reconfiguration loop plans under the Bill-E rule only")
    run = run or Run()
    loop = reconfigure.plan(instance, o, run.part(run.budget.share(LOOP_SHARE)), motion="lacam")
    if loop.status not in ("unsolved", "timeout") or run.budget.expired():
        return loop
    whole = states.plan(instance, run=run, improve=o.improve, max_nodes=o.max_nodes, seed=o.seed)
    whole.stats["loop"] = {"status": loop.status, "failure": None if loop.failure is None else loop.failure.text,
                           "steps": loop.stats.get("steps", 0)}
    return whole


__all__ = ["LOOP_SHARE", "method"]
