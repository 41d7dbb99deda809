"""The pure-Python twin of the joint search (:mod:`bille.solvers.bfs`, ``engine=python``).

Every joint action of every reachable state is tried under the canonical rules, level by level,
so the first goal state found has the optimal makespan, and an exhausted search proves that no
schedule exists. Exponential in the number of robots: it is the yardstick the other solvers are
tested against, not a planner. It searches every schedule (the class ``all``) with the rules'
own :func:`~bille.instances.rules.apply`, so it shares no code with the compiled search it checks.
"""
from __future__ import annotations

import math
from itertools import product

import numpy as np

from bille.instances import Instance
from bille.instances.failure import cap
from bille.instances.limits import CHECK_EVERY
from bille.instances.rules import State, apply, goal_violation
from bille.instances.result import Result
from bille.instances.run import INTERRUPTED, Run
from bille.instances.schedule import Schedule
from bille.instances.successors import candidate_actions, disjoint_products


def plan(instance: Instance, options, run: Run | None = None) -> Result:
    """Optimal-makespan schedule by breadth-first search (``options``: :class:`bille.solvers.bfs.Options`,
    ``max_steps`` and ``max_states`` read, None for no cap); when the run's
    budget expires, status ``timeout`` (no run: no limit). ``infeasible`` means the whole
    reachable state space was exhausted.

    Whenever it stops, every state within the depth reached has been checked, so the lower bound
    it reports (that depth + 1) is proved. Interrupted (Ctrl-C), the level under way may not all
    be checked: status ``interrupted`` with the depth reached as the bound.
    """
    max_steps = math.inf if options.max_steps is None else options.max_steps
    max_states = math.inf if options.max_states is None else options.max_states
    run = run or Run()
    budget, events = run.budget.child(), run.events
    world = instance.world
    goal_tiles, goal_cells = instance.goal_tiles, instance.goal_cells
    root = instance.start_state
    parent: dict = {root.key(): None}
    frontier = [root]
    depth, expanded, truncated = 0, 0, False

    def stats():
        return {"expanded": expanded, "states": len(parent), "depth": depth}

    def stopped() -> Result | None:
        """The run's end if out of time or states; every state within ``depth`` steps has been
        checked (the goal test of each level), so the optimum is larger than ``depth``."""
        out_of_time = budget.expired()
        if not out_of_time and len(parent) <= max_states:
            return None
        return Result("bfs", "timeout" if out_of_time else "unsolved", lower_bound=depth + 1,
                      stats=stats(), time_s=budget.elapsed(),
                      failure=budget.why() if out_of_time else cap("state cap"))

    try:
        while frontier:
            for n, s in enumerate(frontier, 1):
                if n % CHECK_EVERY == 0 and budget.expired():  # levels below this one were checked
                    return Result("bfs", "timeout", lower_bound=depth, stats=stats(),
                                  time_s=budget.elapsed(), failure=budget.why())
                if goal_violation(world, s, goal_tiles, goal_cells, depth) is None:
                    schedule = _unwind(instance, parent, s)
                    events.schedule(schedule)
                    return Result("bfs", "optimal", schedule, lower_bound=depth, stats=stats(),
                                  time_s=budget.elapsed())
            if depth == max_steps:
                truncated = True
                break
            nxt = []
            for s in frontier:
                if (end := stopped()) is not None:
                    return end
                expanded += 1
                options = [candidate_actions(instance, s, i) for i in range(instance.num_robots)]
                joints = product(*options) if world.classic else disjoint_products(instance, s, options)
                for n, joint in enumerate(joints, 1):
                    if n % CHECK_EVERY == 0 and (end := stopped()) is not None:
                        return end  # many robots: one state has millions of joint actions
                    new = apply(world, s, joint)
                    if isinstance(new, State):
                        key = new.key()
                        if key not in parent:
                            parent[key] = (s.key(), joint)
                            nxt.append(new)
            frontier = nxt
            depth += 1
            events.bound(depth)  # every state within depth - 1 steps was tested: none is a goal
            events.progress({"lower": depth, "best": None, "elapsed": budget.elapsed(), "depth": depth,
                             "states": len(parent)})
    except KeyboardInterrupt:  # every level above the one under way was checked: a proved bound
        return Result("bfs", "interrupted", lower_bound=depth, stats=stats(), time_s=budget.elapsed(),
                      failure=INTERRUPTED)
    if truncated:  # no goal within max_steps
        return Result("bfs", "unsolved", lower_bound=max_steps + 1, stats=stats(), time_s=budget.elapsed(),
                      failure=cap("step bound"))
    return Result("bfs", "infeasible", stats=stats(), time_s=budget.elapsed())


def _unwind(instance: Instance, parent: dict, state: State) -> Schedule:
    steps = []
    key = state.key()
    while parent[key] is not None:
        key, joint = parent[key]
        steps.append(joint)
    ids = np.array(steps[::-1], dtype=np.int64).T.reshape(instance.num_robots, len(steps))
    return Schedule.from_ids(instance, ids, meta={"method": "bfs"})
