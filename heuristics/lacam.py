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
from bille.instances.options import option
from bille.instances.run import Budget, Run

from .joint import NO_WALK, JointProblem, to_result
from .loop.loop_options import LoopOptions
from .pibt import Bille, Classic, next_priorities
from .refine import Paths, refine_once
from .scatter import scatter

OBJECTIVES = ("makespan", "sum-of-loss")
RESTART = 0.001  # chance per iteration, while improving, to go back to the start configuration
SCATTER_MARGIN = 10  # steps an SUO path may take beyond the shortest (lacam3's default)
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
    objective: str = option("makespan", choices=OBJECTIVES)
    improve: float = option(1.0, at_least=0)
    max_nodes: int = option(2_000_000, at_least=1)
    seed: int = option(0, at_least=0)


def plan(instance: Instance, options: Options | None = None, run: Run | None = None):
    """LaCAM* on a fixed structure (:class:`Options`; the method ``lacam`` hands an instance that
    moves tiles to the reconfiguration loop with LaCAM* as its motion layer). Without a first
    schedule when the run's budget expires, status ``timeout`` (no run: no limit).

    Status ``optimal`` (with ``stats["objective"]``) when the improvement exhausts the search
    space, ``feasible`` otherwise; ``unsolved`` when the space holds no walking schedule (a
    schedule that moves tiles out of the way and back is outside it).
    """
    o = options or Options()
    problem = JointProblem.of(instance, "lacam")
    status, steps, stats = joint_plan(problem, objective=o.objective, budget=(run or Run()).budget,
                                      improve=o.improve, max_nodes=o.max_nodes, seed=o.seed)
    return to_result(instance, "lacam", status, steps, stats=stats)


def joint_plan(problem: JointProblem, *, objective: str = "makespan", budget: Budget | None = None,
               improve: float = 0.0, max_nodes: int = 2_000_000, seed: int = 0,
               pinned: dict[int, frozenset] | None = None) -> tuple[str, list | None, dict]:
    """LaCAM* on any :class:`JointProblem` within ``budget`` (None: no limit): ``(status, joint
    actions or None, stats)``.

    ``pinned``: robots that wait in the first step while holding the given cells (the
    reconfiguration loop's picks and places, which replace those waits); the search space is
    then the schedules that start so. ``objective`` and ``improve`` as in :class:`Options`,
    which checks them."""
    budget = budget or Budget()
    start = budget.now()
    rng = random.Random(seed)
    space = PoseSpace(problem, objective, rng, pinned or {})
    stats = {"objective": f"{objective}, walking only (no pick or place)"}
    if space.classic and space.alike and not pinned and all(c >= 0 for c in problem.goals) \
            and not space.unreachable():
        space.spread(budget.share(SCATTER_SHARE), seed)
        stats["scatter_s"] = round(budget.now() - start, 6)
    status, steps, stats = search(space, rng, budget=budget, improve=improve, max_nodes=max_nodes,
                                  stats=stats, start=start)
    if status == "exhausted":
        stats["failure"] = NO_WALK
        status = "unsolved"
    return status, steps, stats


class PoseSpace:
    """The configurations of :class:`JointProblem` (one pose per robot) as LaCAM*'s search space:
    its generator (:mod:`.pibt`), its objective's step cost and admissible estimate."""

    def __init__(self, problem: JointProblem, objective: str, rng: random.Random, pinned: dict) -> None:
        self.problem, self.pinned = problem, pinned
        self.m = len(problem.walks)
        self.makespan = objective == "makespan"
        self.classic = problem.instance.collisions == "classic"
        self.refining = False  # no refinement (:meth:`refine`) until the SUO paths are set
        self.generator = (Classic if self.classic else Bille)(problem, rng)
        # the SUO paths and their refinement walk on one set of neighbours, so only where every
        # robot walks alike (one moveset, one load): another robot's moves may not be among them
        self.alike = len({id(w) for w in problem.walks}) <= 1

    def spread(self, budget: Budget, seed: int) -> None:
        """Classic collisions: the generator prefers each robot's next cell on its SUO path
        (:mod:`.scatter`), planned within ``budget``; and the search may
        refine its schedules (:meth:`refine`)."""
        problem = self.problem
        self.goal_poses = [int(w.goal_poses(c)[0]) for w, c in zip(problem.walks, problem.goals)]
        self.generator.prefer = scatter(self.generator.nbrs, problem.dist_lists, list(problem.start),
                                        self.goal_poses, margin=SCATTER_MARGIN, budget=budget, seed=seed,
                                        arrays=problem.dists)
        self.refining = None

    def refine(self, configs: list[Poses] | None, rng: random.Random, budget: Budget) -> list[Poses] | None:
        """One neighbourhood of :mod:`.refine` on the best schedule (``configs``, given when it
        changed since the last call): the improved configurations, or None."""
        goals = self.goal_poses
        if configs is not None:
            paths = []
            for i, goal in enumerate(goals):
                end = len(configs) - 1
                while end > 0 and configs[end - 1][i] == goal:
                    end -= 1
                paths.append([c[i] for c in configs[:end + 1]])
            self.refining = Paths(paths, len(self.generator.nbrs))
        if not refine_once(self.refining, self.generator.nbrs, self.problem.dist_lists, goals, rng, budget):
            return None
        paths = self.refining.paths
        return [tuple(p[min(t, len(p) - 1)] for p in paths) for t in range(max(map(len, paths)))]

    def actions(self, a: Poses, b: Poses) -> tuple[int, ...]:
        """The joint action from configuration ``a`` to ``b``."""
        moves = self.problem.moves
        return tuple(next(act for act, q, _ in moves(i, p) if q == r) for i, (p, r) in enumerate(zip(a, b)))

    def start(self) -> Poses:
        return tuple(self.problem.start)

    def unreachable(self) -> list[int]:
        return self.problem.unreachable()

    def branches(self, config: Poses, forced: tuple, i: int) -> list[int]:
        """Robot ``i``'s moves that a constraint may add to ``forced`` (the others cannot be
        completed to a configuration, nor can any constraint that extends them)."""
        return self.generator.compatible(config, forced, i)

    def generate(self, config: Poses, order: list[int], forced: tuple, first: bool):
        return self.generator.generate(config, order, forced, self.pinned if first else {})

    def is_goal(self, config: Poses) -> bool:
        return self.problem.is_goal(config)

    def resting_all(self, config: Poses) -> list[bool]:
        return [home[p] for home, p in zip(self.problem.home_lists, config)]

    def first_priorities(self, config: Poses) -> list[float]:
        return [d[p] / 10_000 for d, p in zip(self.problem.dist_lists, config)]

    def h(self, config: Poses) -> int:
        ds = [d[p] for d, p in zip(self.problem.dist_lists, config)]
        return max(ds, default=0) if self.makespan else sum(ds)

    def cost(self, a: Poses, b: Poses) -> int:
        if self.makespan:
            return 1
        return sum(1 for home, p, q in zip(self.problem.home_lists, a, b) if not (p == q and home[q]))


def search(space, rng: random.Random, *, budget: Budget | None = None, improve: float = 0.0,
           max_nodes: int = 2_000_000, stats: dict | None = None,
           start: float | None = None) -> tuple[str, list | None, dict]:
    """LaCAM* over any search ``space`` (:class:`PoseSpace`, or whole states in
    :mod:`.lacam_states`): ``(status, joint actions or None, stats)`` with status ``optimal``
    (the improvement exhausted the space), ``feasible``, ``timeout``, ``unsolved`` (node cap or
    an unreachable goal; ``stats["failure"]``) or ``exhausted`` (no goal in the whole space:
    the caller says what that proves). ``budget`` None: no limit; ``start``: the budget's time
    the run began (default: now)."""
    return _LaCAM(space, rng, budget or Budget(), improve, max_nodes, stats or {}, start).run()


class _LaCAM:
    def __init__(self, space, rng: random.Random, budget: Budget, improve, max_nodes, stats: dict,
                 start: float | None) -> None:
        self.space = space
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
            self.stats["failure"] = "unreachable"
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
                        self.stats["failure"] = "node cap"
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
