"""Temporal A*: prioritized planning in a receding time window (paper, Methods, "Temporal A*").

Symbols of the paper: ``H`` the time horizon (steps planned ahead), ``Q`` the priority queue
(robot ids, highest priority first), ``epsilon`` the heuristic weight.

Every step, the robots plan their next ``H`` moves one after another in the order of ``Q``
(:func:`~.spacetime.window`). A robot avoids the cells that higher-priority robots have planned
for each of the ``H`` steps; it sees lower-priority robots only at the first step (their current
feet), assuming that later they move out of the way. All robots then make the first move of
their plan, and the window recedes by one step.

Deadlocks. If a robot finds no walk at all (not even waiting), it moves up one place in ``Q`` and
the step is planned again. If the robots come back to a joint state they were in before with
the same ``Q``, they are going round in circles: the lowest-priority robot not at its goal moves
up one place. Both count against a budget of priority shifts; when it is spent, or the step
bound is reached, the planner gives up with status ``unsolved`` and the reason in
``stats["failure"]`` (``timeout`` when the time limit ended it). Temporal A* is not complete:
giving up is not a proof that no schedule exists.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.options import option
from bille.instances.run import Run
from bille.instances.rules import State, apply

from .joint import JointProblem, to_result
from .loop.loop_options import LoopOptions
from .spacetime import reservation_step


@dataclass(frozen=True)
class Options(LoopOptions):
    """``epsilon``: heuristic weight of each robot's window search; ``horizon``: ``H``, the
    number of steps each robot plans ahead; ``max_shifts``: budget of priority shifts (default:
    4 m^2 for m robots; in the loop ``4 m^2 + 4 jobs``); ``shift_priorities``: False keeps ``Q``
    fixed (for comparison): a blocked robot then ends the run (path planning only);
    ``priorities``: the initial ``Q`` (default: robot ids in order). On a fixed structure
    ``max_steps`` defaults to 4 x the robots' summed distances to their goals, at least 100."""

    METHOD = "temporal-astar"
    epsilon: float = option(1.0, at_least=1)
    horizon: int = option(5, at_least=1)
    max_shifts: int | None = option(None, at_least=0)
    shift_priorities: bool = option(True)
    priorities: list[int] | None = option(None)


def plan(instance: Instance, options: Options | None = None, run: Run | None = None):
    """Temporal A* on a fixed structure (:class:`Options`; the method ``temporal-astar`` hands an
    instance that moves tiles to the reconfiguration loop, :mod:`.reconfigure`, instead). When
    the run's budget expires, status ``timeout`` (no run: no limit).
    """
    o = options or Options()
    epsilon, horizon, max_steps, max_shifts = o.epsilon, o.horizon, o.max_steps, o.max_shifts
    shift_priorities, priorities = o.shift_priorities, o.priorities
    m = instance.num_robots
    Q = list(range(m)) if priorities is None else list(priorities)
    if sorted(Q) != list(range(m)):
        raise OptionError(f"temporal-astar: priorities must order the robot ids 0..{m - 1}, got {priorities}")
    budget = (run or Run()).budget
    problem = JointProblem.of(instance, "temporal-astar")
    stats = {"horizon": horizon, "epsilon": epsilon, "steps": 0, "priority_shifts": 0, "replans": 0,
             "expanded": 0, "plan_ms_mean": 0.0, "plan_ms_max": 0.0}
    if problem.unreachable():
        stats["unreachable"] = problem.unreachable()
        stats["failure"] = "unreachable"
        return to_result(instance, "temporal-astar", "unsolved", None, stats=stats)
    total = sum(int(d[p]) for d, p in zip(problem.dists, problem.start))
    max_steps = max(100, 4 * total) if max_steps is None else max_steps
    max_shifts = 4 * m * m if max_shifts is None else max_shifts
    dists = [d if c >= 0 else None for d, c in zip(problem.dist_lists, problem.goals)]
    shared: dict[int, list] = {}  # one feet table per pose graph, read by every robot on it
    for w in problem.walks:
        if id(w.graph) not in shared:
            shared[id(w.graph)] = w.graph.feet.tolist()
    feet = [shared[id(w.graph)] for w in problem.walks]

    state = instance.start_state
    steps: list[tuple[int, ...]] = []
    seen: set = set()
    step_times: list[float] = []

    def stop(reason: str):
        stats["failure"] = reason
        timing(stats, step_times)
        status = "timeout" if reason == "time limit" else "unsolved"
        return to_result(instance, "temporal-astar", status, None, stats=stats)

    while not problem.is_goal(state.poses):
        if len(steps) >= max_steps:
            return stop("step bound")
        if budget.expired():
            return stop("time limit")
        if (state.poses, tuple(Q)) in seen:  # going round in circles
            if not shift_priorities or stats["priority_shifts"] >= max_shifts:
                return stop("deadlock")
            stuck = [i for i in Q if not problem.at_goal(i, state.poses[i])]
            shift_up(Q, stuck[-1])
            stats["priority_shifts"] += 1
            continue
        seen.add((state.poses, tuple(Q)))

        t0 = budget.now()
        while True:  # plan the step; a blocked robot moves up in Q and the step is planned again
            first, blocked = _plan_step(problem, state.poses, Q, horizon, epsilon, dists, feet, stats)
            if blocked is None:
                break
            if not shift_priorities or stats["priority_shifts"] >= max_shifts:
                step_times.append(budget.now() - t0)
                return stop("deadlock")
            if budget.expired():  # many robots: many replans
                step_times.append(budget.now() - t0)
                return stop("time limit")
            shift_up(Q, blocked)
            stats["priority_shifts"] += 1
            stats["replans"] += 1
        step_times.append(budget.now() - t0)

        nxt = apply(instance.world, state, first, step=len(steps) + 1)
        if not isinstance(nxt, State):  # cannot happen if the windows respect the reservations
            stats["failure"] = f"internal: {nxt}"
            return to_result(instance, "temporal-astar", "error", None, stats=stats)
        steps.append(tuple(first))
        state = nxt
        stats["steps"] = len(steps)
    timing(stats, step_times)
    stats["final_priorities"] = list(Q)
    return to_result(instance, "temporal-astar", "feasible", steps, stats=stats)


def _plan_step(problem: JointProblem, poses, Q: list[int], H: int, epsilon: float, dists, feet, stats):
    """Plan every robot's window in the order of ``Q`` (:func:`.spacetime.reservation_step`;
    lower robots are seen by their feet at the first step). Returns ``(first actions, None)`` or
    ``(None, robot)`` for the first robot that finds no walk."""
    reserved: list[set[int]] = [set() for _ in range(H + 1)]
    goals = list(zip(dists, problem.home_lists))
    first, blocked = reservation_step(Q, problem.walks, goals, poses, H, reserved,
                                      lambda j: feet[j][poses[j]], epsilon, stats)
    return (None, blocked) if first is None else ([first[i] for i in range(len(poses))], None)


def shift_up(Q: list[int], robot: int) -> None:
    """Move ``robot`` up one place in the priority queue ``Q``."""
    k = Q.index(robot)
    if k > 0:
        Q[k - 1], Q[k] = Q[k], Q[k - 1]


def timing(stats: dict, step_times: list[float]) -> None:
    """Mean and largest planning time per step, in ms, into ``stats``."""
    if step_times:
        stats["plan_ms_mean"] = round(1000 * float(np.mean(step_times)), 3)
        stats["plan_ms_max"] = round(1000 * float(np.max(step_times)), 3)
