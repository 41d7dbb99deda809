"""LaCAM*: a complete, anytime search over joint configurations (Okumura, AAAI 2023, IJCAI 2023).

The high level is a depth-first search over *configurations* (one pose per robot). Each node
lazily enumerates *constraints*: "robot ``order[0]`` makes move ``k0``", then also "robot
``order[1]`` makes move ``k1``", and so on, one robot deeper each time a constraint is taken
(a breadth-first tree of constraints under every node; a move that collides with the moves
already fixed is left out, as no configuration completes it). A constraint is handed to the
*configuration generator*, which completes it to a next configuration or says it cannot. The
first successor of a node is the generator's free choice; as the search comes back to a node,
ever more robots are pinned, until every joint move has been tried. A configuration seen before
is not a new node: the search goes back to it (and, LaCAM*, records the edge and rewires the
cheaper parent with a Dijkstra update). So the search is **complete** on its finite space:
every joint walking move of every reachable configuration is eventually generated, and the
search ends only when a goal configuration is found or the space is exhausted. After the first
schedule it keeps going (**anytime**): nodes whose cost plus an admissible estimate cannot beat
the best schedule are dropped, and when nothing is left the best schedule is optimal for the
objective (among walking schedules).

**The configuration generator** (:mod:`.pibt`) is PIBT adapted to robots whose moves occupy
collision sets (docs/rules.md, rule 3), or the original PIBT under classic collisions. Robots are
decided in the order of the node's priorities: a robot away from its goal gains priority every
step, one that arrives drops back (LaCAM's rule), so no robot is starved.

Objectives (``objective``): ``makespan`` (every step costs 1; estimate: the largest distance
to a goal) or ``sum-of-loss`` (every step costs the number of robots not resting at their goal;
estimate: the summed distances), both over walking schedules (no pick or place).
"""
from __future__ import annotations

import random
from collections import deque
from dataclasses import dataclass, field

from bille.instances import Instance
from bille.instances.claim import Claim
from bille.instances.failure import CANNOT_REACH, cap
from bille.instances.options import option, refuse
from bille.instances.run import Budget, Run

from ..joint import NO_WALK, JointProblem, to_result
from .space import PoseSpace
from ..loop.loop_options import LoopOptions
from .pibt import next_priorities

OBJECTIVES = ("makespan", "sum-of-loss")
RESTART = 0.001  # chance per iteration, while improving, to go back to the start configuration
SCATTER_SHARE = 0.5  # of the time limit, at most, for the SUO paths (lacam3's share)
REFINE_RATIO = 3  # while improving: time refining per time searching (lacam3 refines in 4 threads)
Poses = tuple[int, ...]


@dataclass(eq=False)
class _Node:
    """A configuration in the high-level search."""

    config: Poses
    parent: "_Node | None"
    actions: tuple[int, ...] | None  # the joint action from the parent
    g: int
    h: int
    priority: list[float]
    order: list[int]
    tree: deque = field(default_factory=deque)  # constraints still to try: tuples of (robot, move)
    edges: dict = field(default_factory=dict)  # successor node -> (joint action, cost)


@dataclass(frozen=True)
class Options(LoopOptions):
    """``objective``: ``makespan`` or ``sum-of-loss`` (module docstring; path planning only);
    ``improve``: seconds spent improving the first schedule (0: stop at the first one), within
    the run's budget; ``max_nodes``: configurations stored before giving up (``unsolved``) or
    stopping the improvement; ``seed``: the generator's tie-breaking (results are repeatable for
    a seed)."""

    METHOD = "lacam"
    objective: str = option("makespan", choices=OBJECTIVES,
                            help="what the improvement lowers: makespan or sum-of-loss (path planning)")
    improve: float = option(1.0, at_least=0,
                            help="seconds spent improving the first schedule (0: stop at the first one)")
    max_nodes: int = option(2_000_000, at_least=1,
                            help="configurations stored before giving up or stopping the improvement")
    seed: int = option(0, at_least=0, help="tie-breaking of the generator: results repeat for a seed")

    def check_instance(self, instance) -> None:
        """The loop's options (:class:`LoopOptions`); ``objective`` is path planning's: an
        instance that moves tiles is planned for its makespan."""
        super().check_instance(instance)
        if instance.is_reconfiguration:
            refuse(self, ("objective",),
                   "is for path planning; an instance that moves tiles is planned for its makespan")


def plan(instance: Instance, options: Options | None = None, run: Run | None = None):
    """LaCAM* on a fixed structure (:class:`Options`; the method ``lacam`` hands an instance that
    moves tiles to the reconfiguration loop with LaCAM* as its motion layer). Without a first
    schedule when the run's budget expires, status ``timeout`` (no run: no limit).

    Status ``optimal`` (of ``objective`` over walking schedules: the result's claim) when the
    improvement exhausts the search space, ``feasible`` otherwise; ``unsolved`` when the space
    holds no walking schedule (a schedule that moves tiles out of the way and back is outside
    it).
    """
    o = options or Options()
    problem = JointProblem.of(instance, "lacam")
    run = run or Run()
    status, steps, stats = joint_plan(problem, objective=o.objective, budget=run.budget, improve=o.improve,
                                      max_nodes=o.max_nodes, seed=o.seed, progress=run.events.on_progress)
    result = to_result(instance, "lacam", status, steps, stats=stats, claim=Claim(o.objective, walking_only=True),
                       failure=stats.pop("failure", None))
    if result.schedule is not None:
        run.events.schedule(result.schedule)
    return result


def joint_plan(problem: JointProblem, *, objective: str = "makespan", budget: Budget | None = None,
               improve: float = 0.0, max_nodes: int = 2_000_000, seed: int = 0,
               pinned: dict[int, frozenset] | None = None, progress=None) -> tuple[str, list | None, dict]:
    """LaCAM* on any :class:`JointProblem` within ``budget`` (None: no limit): ``(status, joint
    actions or None, stats)``, why there is no schedule in ``stats["failure"]`` (a
    :class:`~bille.instances.failure.Failure`, for the result); ``progress`` (a run's progress
    receiver, or None) hears of each cheaper schedule found.

    ``pinned``: robots that wait in the first step while holding the given cells (the
    reconfiguration loop's picks and places, which replace those waits); the search space is
    then the schedules that start so. ``objective`` and ``improve`` as in :class:`Options`,
    which checks them."""
    budget = budget or Budget()
    start = budget.now()
    rng = random.Random(seed)
    space = PoseSpace(problem, objective, rng, pinned or {})
    stats: dict = {}
    if space.classic and space.alike and not pinned and all(c >= 0 for c in problem.goals) \
            and not space.unreachable():
        began = budget.now()
        space.spread(budget.share(SCATTER_SHARE), seed)
        stats["scatter_s"] = round(budget.now() - began, 6)  # the SUO paths alone, as lacam3 times them
    status, steps, stats = search(space, rng, budget=budget, improve=improve, max_nodes=max_nodes,
                                  stats=stats, start=start, progress=progress)
    if status == "exhausted":
        stats["failure"] = NO_WALK
        status = "unsolved"
    return status, steps, stats


def search(space, rng: random.Random, *, budget: Budget | None = None, improve: float = 0.0,
           max_nodes: int = 2_000_000, stats: dict | None = None,
           start: float | None = None, progress=None) -> tuple[str, list | None, dict]:
    """LaCAM* over any search ``space`` (:class:`PoseSpace`, or whole states in
    :mod:`.states`): ``(status, joint actions or None, stats)`` with status ``optimal``
    (the improvement exhausted the space), ``feasible``, ``timeout``, ``unsolved`` (node cap or
    an unreachable goal; ``stats["failure"]``) or ``exhausted`` (no goal in the whole space:
    the caller says what that proves). ``budget`` None: no limit; ``start``: the budget's time
    the run began (default: now); ``progress``: told each cheaper schedule (``cost``, and as
    ``best`` where the cost is the makespan)."""
    return _LaCAM(space, rng, budget or Budget(), improve, max_nodes, stats or {}, start, progress).run()


class _LaCAM:
    def __init__(self, space, rng: random.Random, budget: Budget, improve, max_nodes, stats: dict,
                 start: float | None, progress=None) -> None:
        self.space, self.progress = space, progress
        self.m = space.m
        self.budget = budget
        self.start = budget.now() if start is None else start
        self.improve, self.max_nodes = improve, max_nodes
        self.rng = rng
        self.stats: dict = {**stats, "nodes": 0, "generated": 0, "improvements": []}

    def node(self, config, parent: _Node | None, actions, g: int) -> _Node:
        space = self.space
        if parent is None:
            priority = space.first_priorities(config)
        else:
            priority = next_priorities(parent.priority, space.resting_all(config))
        order = sorted(range(self.m), key=lambda i: -priority[i])
        node = _Node(config, parent, actions, g, space.h(config), priority, order)
        node.tree.append(())
        self.stats["nodes"] += 1
        return node

    # ---- the search -------------------------------------------------------------------------------

    def run(self) -> tuple[str, list | None, dict]:
        space = self.space
        if space.unreachable():
            self.stats["unreachable"] = space.unreachable()
            self.stats["failure"] = CANNOT_REACH
            return "unsolved", None, self.stats
        root = self.node(space.start(), None, None, 0)
        explored = {root.config: root}
        refining = getattr(space, "refining", False)
        self.next_refine, self.refined = 0.0, None
        self.open: list[_Node] = [root]
        self.best: _Node | None = None
        stop = self.budget  # then, from the first schedule on, a child of it for the improvement
        exhausted = True
        while self.open:
            if stop.expired():
                exhausted = False
                break
            if self.best is not None and self.rng.random() < RESTART:
                self.open.append(root)  # lacam3's random insertion: search again from the start
            if self.best is not None and refining is not False and stop.now() >= self.next_refine:
                self._refine(explored, stop)
            node = self.open[-1]
            if self.best is not None and node.g + node.h >= self.best.g:
                self.open.pop()
                continue
            if space.is_goal(node.config):
                self._found(node)
                self.open.pop()
                if self.improve == 0:
                    exhausted = False
                    break
                stop = self.budget.child(self.improve)
                continue
            if not node.tree:
                self.open.pop()
                continue
            forced = node.tree.popleft()
            if len(forced) < self.m:
                i = node.order[len(forced)]
                moves = space.branches(node.config, forced, i)
                self.rng.shuffle(moves)
                node.tree.extend(forced + ((i, k),) for k in moves)
            got = space.generate(node.config, node.order, forced, node is root)
            if got is None:
                continue
            actions, nxt = got
            self.stats["generated"] += 1
            cost = space.cost(node.config, nxt)
            known = explored.get(nxt)
            if known is None:
                if len(explored) >= self.max_nodes:
                    exhausted = False
                    if self.best is None:
                        self.stats["failure"] = cap("node cap")
                    break
                child = self.node(nxt, node, actions, node.g + cost)
                node.edges[child] = (actions, cost)
                explored[nxt] = child
                self.open.append(child)
            else:
                node.edges.setdefault(known, (actions, cost))
                self._rewire(node)
                self.open.append(known)
        self.stats["time_s"] = round(self.budget.now() - self.start, 6)
        if self.best is None:
            if "failure" in self.stats:
                return "unsolved", None, self.stats
            if exhausted:
                return "exhausted", None, self.stats
            self.stats["failure"] = self.budget.why()
            return "timeout", None, self.stats
        self.stats["cost"] = self.best.g
        return ("optimal" if exhausted else "feasible"), self._steps(self.best), self.stats

    def _refine(self, explored: dict, budget: Budget) -> None:
        """One refinement of the best schedule (:meth:`PoseSpace.refine`, within ``budget``), its
        configurations added to the search as lacam3 does (known ones rewired); the search then
        runs as long."""
        began = budget.now()
        changed = self.refined is not self.best
        configs = self._configs(self.best) if changed else None
        self.refined = self.best
        plan = self.space.refine(configs, self.rng, budget)
        if plan is not None:
            node = explored[plan[0]]
            for a, b in zip(plan, plan[1:]):
                actions, cost = self.space.actions(a, b), self.space.cost(a, b)
                known = explored.get(b)
                if known is None:
                    known = explored[b] = self.node(b, node, actions, node.g + cost)
                    node.edges[known] = (actions, cost)
                    self.open.append(known)
                else:
                    node.edges.setdefault(known, (actions, cost))
                    self._rewire(node)
                node = known
            if self.space.is_goal(node.config):
                self._found(node)
            self.refined = self.best
            self.stats["refined"] = self.stats.get("refined", 0) + 1
        now = budget.now()
        self.next_refine = now + (now - began) / REFINE_RATIO

    @staticmethod
    def _configs(node: _Node) -> list:
        configs = []
        while node is not None:
            configs.append(node.config)
            node = node.parent
        return configs[::-1]

    def _found(self, node: _Node) -> None:
        """A goal node: the best if cheaper than the best so far (whose cost a rewiring may have
        lowered in place: ``improvements`` records the costs as they were found)."""
        known = self.stats["improvements"]
        if self.best is None or node.g < known[-1][1]:
            elapsed = round(self.budget.now() - self.start, 6)
            if self.best is None:
                self.stats["first_s"], self.stats["first_cost"] = elapsed, node.g
            self.best = node
            known.append([elapsed, node.g])
            if self.progress is not None:
                makespan = getattr(self.space, "makespan", True)  # whole states: always the makespan
                self.progress({"lower": None, "best": node.g if makespan else None, "elapsed": elapsed,
                               "cost": node.g, "nodes": self.stats["nodes"]})

    def _rewire(self, root: _Node) -> None:
        """LaCAM*'s Dijkstra update: lower the cost of every node reachable from ``root`` through
        known edges where ``root``'s path is cheaper, re-parenting it; a node whose estimate now
        beats the best schedule goes back on the stack."""
        queue = deque([root])
        while queue:
            node = queue.popleft()
            for child, (actions, cost) in node.edges.items():
                if node.g + cost < child.g:
                    child.g, child.parent, child.actions = node.g + cost, node, actions
                    queue.append(child)
                    if self.best is not None and child.g + child.h < self.best.g:
                        self.open.append(child)
                    if self.space.is_goal(child.config):
                        self._found(child)

    @staticmethod
    def _steps(node: _Node) -> list[tuple[int, ...]]:
        steps = []
        while node.parent is not None:
            steps.append(node.actions)
            node = node.parent
        return steps[::-1]
