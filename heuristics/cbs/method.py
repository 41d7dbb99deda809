"""``cbs``: conflict-based search as a method of ``solve()``: options, proofs, result."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import partial

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.claim import Claim
from bille.instances.failure import Failure, cap
from bille.instances.grid import neighbour_table
from bille.instances.moveset import Kind
from bille.instances.options import MethodOptions, option
from bille.instances.result import Result
from bille.instances.run import INTERRUPTED, Run
from bille.instances.schedule import Schedule

from ..joint import NO_WALK, JointProblem, check_tables, require_path_planning
from .lowlevel import Agent, Stopped
from .search import FOCALS, HEURISTICS, OBJECTIVES, Node, OutOfBudget, Settings, Tree

def agents_of(problem: JointProblem, compiled: bool = False) -> list[Agent]:
    """The robots as the low level sees them; ``compiled``: with the arrays of its compiled search
    (point robots, :mod:`.lowlevel_compiled`)."""
    agents = []
    for k, (walk, goal) in enumerate(zip(problem.walks, problem.goals)):
        agents.append(Agent(k, problem.start[k], walk.moves, problem.dist_lists[k], problem.home_lists[k], goal,
                            arrays_of(problem, k) if compiled else None))
    return agents


def arrays_of(problem: JointProblem, k: int) -> tuple:
    """Robot ``k``'s arrays for the compiled low level: its walk's moves, wait action, distances
    to its goal and goal poses."""
    walk = problem.walks[k]
    return walk.succ, walk.wait, problem.dist_table[k], problem.home_table[k]


def _check_movesets(instance: Instance) -> None:
    """A robot's cost is the step after which it stands still on its goal; that is joint A*'s
    (a move between two poses on the goal is free) only if every motion moves the front foot,
    as in the shipped movesets. A user's moveset with a motion that pivots on the front foot is
    refused, not answered with a cost defined otherwise."""
    for ms in instance.movesets:
        for a in ms.actions:
            if a.kind == Kind.MOTION and tuple(a.front) == (0, 0):
                raise OptionError(f"cbs: moveset {ms.name}'s motion '{a.name}' keeps the front foot in place; "
                                  "conflict-based search needs every motion to move it (astar and mstar plan "
                                  "with such movesets)")


def _reversible(instance: Instance) -> bool:
    """Whether every robot is a point whose every move can be undone by another (a move by
    ``(dx, dy)`` has one by ``(-dx, -dy)``): corridor reasoning's graph, where a corridor is
    entered and left only at its ends (:mod:`.corridor`)."""
    for ms in instance.movesets:
        steps = {tuple(a.front) for a in ms.actions if a.kind == Kind.MOTION}
        if ms.footprint != "point" or any((-dx, -dy) not in steps for dx, dy in steps):
            return False
    return True


def _grid_steps(instance: Instance) -> bool:
    """Whether every robot is a point that moves one cell across or down at a time (rectangle
    reasoning's grid, :mod:`.rectangle`)."""
    return all(ms.footprint == "point" and all(abs(a.front[0]) + abs(a.front[1]) == 1 for a in ms.actions
                                               if a.kind == Kind.MOTION) for ms in instance.movesets)


def closed_world(instance: Instance) -> bool:
    """Whether walking schedules are all the schedules that matter: no robot carries a tile and
    no free cell (neither tile nor obstacle) is next to a tile. A tile is set down next to the
    front foot of a robot, which stands on a tile; by induction the tiles are always a part of
    the start's (a pick removes one, a place can only fill a cell a pick emptied). Replacing
    every pick and place by a wait then keeps every rule (the feet still stand on the start's
    tiles, a wait's collision set is inside the pick's or place's, the tiles never change so the
    connectivity rule is not called on, the goal's tiles are the start's) and every robot's
    poses, so the walking optimum is the optimum. Maps converted from MAPF benchmarks are such
    worlds: every free cell is a tile, or cut off from the tiles by obstacles. A moveset that sets
    a tile down elsewhere than next to the front foot (a file of the user's) makes no closed world."""
    start = instance.start
    if any(instance.start_state.carrying):
        return False
    beside = {(0, -1), (1, 0), (0, 1), (-1, 0)}
    if any(a.place is not None and tuple(a.place) not in beside for ms in instance.movesets for a in ms.actions):
        return False
    empty = ~(start.tiles | start.obstacles)
    nbr = neighbour_table(instance.width, instance.height)
    tiles = np.append(start.tiles, False)  # index -1 (outside) is no tile
    return not bool((empty & tiles[nbr].any(axis=1)).any())


@dataclass(frozen=True)
class Options(MethodOptions):
    """Options of conflict-based search.

    ``objective``: ``sum-of-costs`` (each robot's arrival at its goal for good, added up; ties
    not broken) or ``makespan`` (the latest arrival). ``w``: suboptimality: the sum of costs
    found is at most ``w`` times optimal; 1 is optimal. ``focal``: with ``w > 1``, how a node is
    chosen among those within the bound: ``conflicts`` (the fewest) or ``ees`` (explicit
    estimation, EECBS's high level). ``heuristic``: ``wdg``, ``cg`` or ``none`` (sum of costs
    only). ``prioritize``, ``bypass``, ``target``, ``rectangle``, ``corridor``: the improvements
    of :mod:`.search` (rectangle and corridor reasoning apply under classic collisions;
    rectangles to robots that move one cell at a time, corridors to robots whose every move can
    be undone). ``max_nodes``: constraint-tree nodes expanded before giving up."""

    METHOD = "cbs"
    objective: str = option("sum-of-costs", choices=OBJECTIVES,
                            help="sum-of-costs (arrivals for good, added up) or makespan (the latest arrival)")
    w: float = option(1.0, at_least=1,
                      help="suboptimality: the sum of costs found is at most w times optimal; 1 is optimal")
    heuristic: str = option("wdg", choices=HEURISTICS,
                            help="high-level heuristic: wdg (weighted dependency graph), cg (cardinal conflicts) or "
                                 "none")
    prioritize: bool = option(True, help="resolve cardinal conflicts first, then semi-cardinal, then the rest")
    bypass: bool = option(True, help="adopt a child's path of equal cost and fewer conflicts instead of branching")
    target: bool = option(True, help="target reasoning: a robot resting at its goal is split on 'arrives after t'")
    rectangle: bool = option(True,
                             help="rectangle reasoning: one split for a rectangle of conflicts (classic, one-cell "
                                  "moves)")
    corridor: bool = option(True,
                            help="corridor reasoning: one split for robots meeting in a corridor (classic, reversible "
                                 "moves)")
    focal: str = option("conflicts", choices=FOCALS,
                        help="with w > 1, which node within the bound is expanded: conflicts (fewest) or ees (EECBS)")
    max_nodes: int = option(1_000_000, at_least=1, help="constraint-tree nodes expanded before giving up")

    def check(self) -> None:
        if self.focal != "conflicts" and self.w == 1:
            raise OptionError(f"cbs: focal={self.focal} chooses among nodes within w of the bound; give w > 1 with it")
        if self.w > 1 and self.objective != "sum-of-costs":
            raise OptionError("cbs: w > 1 bounds the sum of costs; use it with objective=sum-of-costs")


def plan(instance: Instance, options: Options | None = None, run: Run | None = None) -> Result:
    """Conflict-based search on a path-planning instance (module docstring, :class:`Options`).
    When the run's budget expires: status ``timeout``, with the lower bound reached (no run: no
    limit).

    On a map whose free cells are all tiles (no robot carrying) walking schedules are all the
    schedules there are (:func:`closed_world`), so the optimum is over every schedule and a robot
    that cannot walk to its goal proves the instance infeasible; elsewhere the proofs are over
    walking-only schedules, as joint A*'s.
    """
    o = options or Options()
    objective, w, heuristic, focal, max_nodes = o.objective, o.w, o.heuristic, o.focal, o.max_nodes
    require_path_planning(instance, "cbs")
    _check_movesets(instance)
    check_tables(instance, "cbs")
    run = run or Run()
    budget = run.budget
    problem = JointProblem.of(instance, "cbs")
    agents = agents_of(problem)
    closed = closed_world(instance)
    claim = Claim(objective, walking_only=not closed)
    stats: dict = {"w": w, "heuristic": heuristic, "expanded": 0, "generated": 0, "low_expanded": 0}

    settings = Settings(objective, heuristic, o.prioritize, o.bypass, o.target, o.rectangle,
                        o.corridor and _reversible(instance), w, focal, max_nodes)
    def told(lower: int, expanded: int) -> None:
        run.events.progress({"lower": None, "best": None, "elapsed": budget.elapsed(),
                             "cost_lower": lower, "objective": objective, "expanded": expanded})

    tree = Tree(agents, instance.collisions == "classic", settings, budget.expired, stats,
                instance.width if _grid_steps(instance) else None, told,
                arrays_of=partial(arrays_of, problem) if instance.collisions == "classic" else None)
    try:
        unreachable = problem.unreachable()
        if unreachable:
            stats["unreachable"] = unreachable
            return _no_schedule(instance, closed, stats, f"robots {unreachable} cannot walk to their goals")
        root = tree.root()
        if root is None:
            return _no_schedule(instance, closed, stats, "a robot cannot walk to its goal")
        stats["root_cost"] = root.g
        found = tree.run(root)
    except (OutOfBudget, Stopped):
        over = budget.expired()
        failure = budget.why() if over else cap(f"node limit ({max_nodes} expanded)")
        return _proved("timeout" if over else "unsolved", None, tree.lower, claim, stats, failure)
    except KeyboardInterrupt:
        return _proved("interrupted", None, tree.lower, claim, stats, INTERRUPTED)
    if found is None:
        return _no_schedule(instance, closed, stats, "no schedule keeps every constraint")
    result = _result(instance, agents, found, tree, claim, stats)
    run.events.schedule(result.schedule)
    return result


def _no_schedule(instance: Instance, closed: bool, stats: dict, why: str) -> Result:
    if closed:
        stats["why"] = why
        return Result("cbs", "infeasible", stats=stats)
    stats["why"] = why
    return Result("cbs", "unsolved", stats=stats, failure=NO_WALK)


def _proved(status: str, schedule: Schedule | None, lower: int, claim: Claim, stats: dict,
            failure: Failure | None = None) -> Result:
    """A result with the bound the tree proved: the result's ``lower_bound`` for the makespan over
    every schedule, the claim's otherwise (the sum of costs, or over walking schedules only)."""
    if claim.unconditional:
        return Result("cbs", status, schedule, lower_bound=lower, stats=stats, claim=claim, failure=failure)
    return Result("cbs", status, schedule, stats=stats, claim=dataclasses.replace(claim, lower=lower), failure=failure)


def _result(instance: Instance, agents: list[Agent], node: Node, tree: Tree, claim: Claim, stats: dict) -> Result:
    length = max((p.cost for p in node.paths), default=0)
    ids = np.zeros((len(agents), length), dtype=np.int64)
    for k, path in enumerate(node.paths):
        wait = instance.movesets[k].wait
        row = list(path.actions[1:]) + [wait] * (length - path.cost)
        ids[k, :] = row
    schedule = Schedule.from_ids(instance, ids, meta={"method": "cbs"})
    soc = sum(p.cost for a, p in zip(agents, node.paths) if a.goal >= 0)
    stats["sum_of_costs"] = soc
    optimal = tree.settings.w == 1
    return _proved("optimal" if optimal else "feasible", schedule, node.g if optimal else min(tree.lower, node.g),
                   claim, stats)

