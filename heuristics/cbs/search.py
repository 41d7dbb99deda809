"""The constraint tree: best-first over sets of constraints, each node one path per robot.

A node's cost ``g`` is the sum (or the largest) of its robots' least costs under its constraints;
it is a lower bound on every schedule in its subtree, since each of those keeps the node's
constraints. ``f = g + h`` adds an admissible estimate of the extra sum of costs (:mod:`.cover`
over the node's conflicts: ``cg`` counts cardinal conflicts, ``wdg`` weighs each conflicting pair
by solving it alone), and a child's ``f`` is at least its parent's. Expanding the node of least
``f`` that has no conflict gives an optimal schedule; the least ``f`` of the open nodes is at all
times a proved lower bound on the optimum.

Improvements (each can be switched off, for measurements):

- *prioritizing conflicts*: a cardinal conflict (both branches raise a cost, told by MDDs) is split
  first, then semi-cardinal, then the rest, the earliest first;
- *bypassing*: a child of a non-cardinal conflict with its parent's cost and fewer conflicts
  replaces the parent's paths instead of branching;
- *target reasoning*: a robot that passes over another's goal after that one arrived is split on
  the arrival time (:mod:`.conflicts`);
- *rectangle reasoning* (point robots on a 4-connected grid): a vertex conflict of two robots
  that came straight from their starts at right angles is split on two barriers instead, when
  that raises at least as many costs (:mod:`.rectangle`);
- *corridor reasoning* (point robots): a vertex or swap conflict of two robots meeting head-on in
  a corridor is split on which one goes through first (:mod:`.corridor`), when that raises at
  least as many costs;
- *focal search* with ``w > 1`` (:mod:`.frontier`): among the nodes whose ``g`` is within ``w``
  times the lower bound, the one with the fewest conflicts (or, with ``focal="ees"``, explicit
  estimation as in EECBS's high level); the schedule's sum of costs is at most ``w`` times
  optimal, and the lower bound is reported.

Under the makespan objective ``g`` is the largest cost and no estimate is added.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

from bille.instances.jit import loaded

from .classic import ClassicAvoid, matrix, meeting
from .conflicts import EDGEC, KIND_NAMES, TARGET, VERTEXC, branches, first_conflict, forced
from .constraints import Table
from .corridor import Corridors
from .cover import cover
from .frontier import BestFirst, Explicit, Focal
from .lowlevel import MDD, Agent, Avoid, Path, mdd, search
from .rectangle import rectangle

OBJECTIVES = ("sum-of-costs", "makespan")
HEURISTICS = ("wdg", "cg", "none")
FOCALS = ("conflicts", "ees")
PAIR_NODES = 64  # constraint-tree nodes for solving one pair of robots alone (WDG)
SWITCH = 200_000  # low-level expansions in Python (a few tenths of a second) before loading the compiled one


class OutOfBudget(Exception):
    """The run's time or node budget ran out."""


@dataclass(eq=False)
class Node:
    constraints: tuple[tuple, ...]  # per robot
    paths: list[Path]
    costs: list[int]
    conflicts: dict[tuple[int, int], tuple]
    g: int
    h: int = 0
    depth: int = 0
    estimated: bool = False  # h computed for this node's own conflicts
    fhat: float = 0.0  # the estimate of focal search (w > 1, :mod:`.frontier`)
    closed: bool = False
    kinds: dict = field(default_factory=dict)  # conflict -> 2 cardinal, 1 semi-cardinal, 0 non

    @property
    def f(self) -> int:
        return self.g + self.h


@dataclass
class Settings:
    objective: str = "sum-of-costs"
    heuristic: str = "wdg"
    prioritize: bool = True
    bypass: bool = True
    target: bool = True
    rectangle: bool = True
    corridor: bool = True
    w: float = 1.0
    focal: str = "conflicts"
    max_nodes: int = 1_000_000


class Tree:
    """One constraint-tree search over ``agents`` (all robots, or a pair for WDG); ``width``: the
    grid's, where rectangle reasoning applies (point robots moving one cell at a time)."""

    def __init__(self, agents: list[Agent], classic: bool, settings: Settings, poll, stats: dict,
                 width: int | None = None, told=None, corridors: tuple | None = None, arrays_of=None) -> None:
        self.agents, self.classic, self.settings = agents, classic, settings
        self.width = width if classic and settings.rectangle else None
        self.corridors = Corridors(agents, corridors) if classic and settings.corridor else None
        self.poll, self.stats = poll, stats
        self.soc = settings.objective == "sum-of-costs"
        self._tables: dict[tuple, Table] = {}
        self._mdds: dict[tuple, MDD] = {}
        self._pairs: dict[tuple, int | None] = {}
        self.lower = 0
        self.told = told  # told(lower, expanded) each time the proved bound rises (the top-level search)
        self.arrays_of = arrays_of  # robot index -> its compiled search's arrays (point robots), or None
        self.scratch = None  # the compiled low level's working arrays, shared with the pairs' trees

    # ---- paths ------------------------------------------------------------------------------

    def table(self, constraints: tuple) -> Table:
        found = self._tables.get(constraints)
        if found is None:
            if len(self._tables) > 200_000:
                self._tables.clear()
            found = self._tables[constraints] = Table(constraints)
        return found

    def _agent(self, k: int) -> Agent:
        """Robot ``k``; the robots given their compiled search's arrays first, where this tree can
        have them (``arrays_of``) and Numba is loaded or the searches in Python have taken
        :data:`SWITCH` expansions (the two searches find the same paths)."""
        agent = self.agents[k]
        if agent.arrays is None and self.arrays_of is not None and (
                loaded() or self.stats.get("low_expanded", 0) >= SWITCH):
            for i, other in enumerate(self.agents):
                self.agents[i] = replace(other, arrays=self.arrays_of(other.index))
            agent = self.agents[k]
        return agent

    def cost(self, k: int, path: Path) -> int:
        if self.agents[k].goal < 0 and self.soc:
            return 0
        return path.cost

    def replan(self, k: int, constraints: tuple, paths: list[Path | None]) -> Path | None:
        agent = self._agent(k)
        if self.classic:  # a pose is a cell: one count per cell and time, from numpy
            avoid = ClassicAvoid(paths, k, len(agent.dist))
            if agent.arrays is not None:
                from . import lowlevel_compiled

                if self.scratch is None:
                    self.scratch = lowlevel_compiled.Scratch()
                return lowlevel_compiled.search(agent, agent.arrays, self.table(constraints), avoid, self.scratch,
                                                poll=self.poll, stats=self.stats)
        else:
            avoid = Avoid(paths, k, self.classic, [a.stand for a in self.agents])
        return search(self.agents[k], self.table(constraints), avoid, self.classic, poll=self.poll, stats=self.stats)

    def mdd(self, k: int, node: Node) -> MDD | None:
        if self.agents[k].goal < 0:
            return None
        key = (k, node.constraints[k], node.paths[k].cost)
        found = self._mdds.get(key)
        if found is None:
            if len(self._mdds) > 20_000:
                self._mdds.clear()
            agent, table, cost = self._agent(k), self.table(node.constraints[k]), node.paths[k].cost
            if agent.arrays is not None:
                from .mdd_compiled import mdd as compiled_mdd

                found = compiled_mdd(agent, agent.arrays, table, cost)
            else:
                found = mdd(agent, table, self.classic, cost)
            self._mdds[key] = found
        return found

    # ---- nodes ------------------------------------------------------------------------------

    def root(self, constraints: tuple[tuple, ...] | None = None, paths: list[Path] | None = None) -> Node | None:
        m = len(self.agents)
        constraints = constraints or ((),) * m
        if paths is None:
            paths = [None] * m
            for k in range(m):
                if self.poll is not None and self.poll():  # a thousand robots: seconds of avoidance tables
                    raise OutOfBudget
                paths[k] = self.replan(k, constraints[k], paths)
                if paths[k] is None:
                    return None
        conflicts = {}
        cells = self._cells(paths)  # one matrix for every robot's look-up
        for i in range(m):
            for j in self.others(paths, i, cells):
                if j > i:
                    c = first_conflict(self.agents, i, paths[i], j, paths[j], self.classic)
                    if c is not None:
                        conflicts[(i, j)] = c
        costs = [self.cost(k, p) for k, p in enumerate(paths)]
        return Node(constraints, list(paths), costs, conflicts, self.total(costs))

    def others(self, paths: list[Path], k: int, cells=None):
        """The robots whose paths robot ``k``'s may conflict with: under classic collisions
        those it meets at all (:func:`.classic.meeting`, on ``cells`` if given), otherwise every
        other robot."""
        if cells is None:
            cells = self._cells(paths)
        return range(len(paths)) if cells is None else meeting(cells, k)

    def _cells(self, paths: list[Path]):
        """The paths as :func:`.classic.matrix` where :meth:`others` uses it (classic, 8 robots
        or more), else None."""
        if not self.classic or len(paths) < 8:
            return None
        return matrix(paths, max(p.cost for p in paths) + 1)

    def total(self, costs: list[int]) -> int:
        return sum(costs) if self.soc else max(costs, default=0)

    def child(self, node: Node, k: int, added: tuple) -> Node | None:
        constraints = node.constraints[:k] + (node.constraints[k] + added,) + node.constraints[k + 1:]
        path = self.replan(k, constraints[k], node.paths)
        if path is None:
            return None
        paths = list(node.paths)
        paths[k] = path
        costs = list(node.costs)
        costs[k] = self.cost(k, path)
        conflicts = {pair: c for pair, c in node.conflicts.items() if k not in pair}
        for other in self.others(paths, k):
            if other != k:
                i, j = min(k, other), max(k, other)
                c = first_conflict(self.agents, i, paths[i], j, paths[j], self.classic)
                if c is not None:
                    conflicts[(i, j)] = c
        g = self.total(costs)
        child = Node(constraints, paths, costs, conflicts, g, depth=node.depth + 1)
        child.h = max(0, node.f - g)  # the subtree is part of the parent's
        self.stats["generated"] = self.stats.get("generated", 0) + 1
        return child

    # ---- conflicts and the estimate ----------------------------------------------------------

    def classify(self, node: Node) -> None:
        """Cardinal (2), semi-cardinal (1) or not (0), for each conflict of the node."""
        for c in node.conflicts.values():
            if c in node.kinds:
                continue
            if not (self.settings.prioritize or self.settings.heuristic != "none"):
                node.kinds[c] = 0
                continue
            _, i, j, _, _ = c
            node.kinds[c] = sum(forced(self.agents[k], self.mdd(k, node), c, side, self.classic)
                                for side, k in enumerate((i, j)))

    def estimate(self, node: Node) -> int | None:
        """An admissible estimate of the node's extra cost (module docstring); None when a pair
        of its robots has no schedule under the node's constraints (the subtree is empty)."""
        if not self.soc or self.settings.heuristic == "none":
            return 0
        wdg = self.settings.heuristic == "wdg" and len(self.agents) > 2  # with two robots, the pair is the problem
        edges = {}
        for pair, c in node.conflicts.items():
            if node.kinds.get(c) == 2:
                edges[pair] = 1
            if wdg:
                w = self.pair_weight(node, *pair, floor=edges.get(pair, 0))
                if w is None:
                    return None
                if w > 0:
                    edges[pair] = w
        return cover(edges)

    def pair_weight(self, node: Node, i: int, j: int, floor: int) -> int | None:
        """What robots ``i`` and ``j`` alone must pay above their costs under the node's
        constraints (at least ``floor``): the least f a small search over the two proves."""
        key = (i, j, node.constraints[i], node.constraints[j])
        if key in self._pairs:
            found = self._pairs[key]
            return None if found is None else max(found, floor)
        pair = Tree([self.agents[i], self.agents[j]], self.classic,
                    Settings(heuristic="cg", rectangle=self.settings.rectangle, corridor=self.settings.corridor,
                             max_nodes=PAIR_NODES), self.poll, {},
                    self.width, corridors=None if self.corridors is None else self.corridors.caches,
                    arrays_of=self.arrays_of)
        pair.scratch = self.scratch
        start = pair.root((node.constraints[i], node.constraints[j]), [node.paths[i], node.paths[j]])
        found = pair.best(start)
        base = node.costs[i] + node.costs[j]
        weight = None if found is None else max(0, found - base)
        self._pairs[key] = weight
        self.stats["pairs"] = self.stats.get("pairs", 0) + 1
        return None if weight is None else max(weight, floor)

    def choose(self, node: Node):
        """The conflict to split: cardinal first, then semi-cardinal; targets first among equals;
        the earliest."""
        return min(node.conflicts.values(),
                   key=lambda c: (-node.kinds.get(c, 0), c[0] != TARGET, c[3], c[1], c[2]))

    def symmetry(self, node: Node, conflict, kind: int):
        """A corridor or rectangle split in place of a vertex or swap ``conflict`` of
        cardinality ``kind``, where one applies and raises at least as many costs."""
        _, i, j, _, _ = conflict
        mdds = (self.mdd(i, node), self.mdd(j, node))
        found = None if self.corridors is None else self.corridors.split(conflict, node.paths, mdds)
        if found is None and self.width is not None and conflict[0] == VERTEXC:
            found = rectangle(conflict, node.paths, mdds, (self.agents[i].goal, self.agents[j].goal), self.width)
            if found is not None and found[1] == 0:
                found = None
        return found if found is not None and found[1] >= kind else (conflict, kind)

    # ---- the search --------------------------------------------------------------------------

    def best(self, root: Node | None) -> int | None:
        """The optimal cost for a pair (WDG): the cost of a conflict-free node, or the least f
        proved when the node budget runs out; None if the pair has no schedule."""
        try:
            found = self.run(root)
        except OutOfBudget:
            return self.lower
        return None if found is None else found.g

    def run(self, root: Node | None) -> Node | None:
        """The optimal (``w > 1``: bounded-suboptimal) conflict-free node, or None if there is
        none. Raises :class:`OutOfBudget` (``self.lower`` then holds the bound proved)."""
        if root is None:
            return None
        settings = self.settings
        if settings.w == 1:
            lists = BestFirst()
        else:
            lists = Explicit(settings.w, self.settle) if settings.focal == "ees" else Focal(settings.w)
        lists.push(root)
        expanded = 0
        while True:
            low = lists.lower()
            if low is None:
                return None
            if low > self.lower:
                self.lower = low
                if self.told is not None:
                    self.told(low, expanded)
            node = lists.select(self.lower)
            if self.poll is not None and self.poll():
                raise OutOfBudget
            if not node.conflicts:
                node.closed = True
                return node
            if not node.estimated:  # best-first: the estimate is computed when a node comes first
                f = node.f
                if not self.settle(node):
                    node.closed = True
                    continue
                if node.f > f:
                    lists.push(node)
                    continue
            node.closed = True
            expanded += 1
            self.stats["expanded"] = self.stats.get("expanded", 0) + 1
            if expanded > settings.max_nodes:
                raise OutOfBudget
            children: list[Node] = []
            self.expand(node, lambda child: (children.append(child), lists.push(child)))
            lists.learn(node, children)

    def settle(self, node: Node) -> bool:
        """Give ``node`` its own estimate (raising ``h`` where it is higher than inherited);
        False when its subtree is empty."""
        self.classify(node)
        h = self.estimate(node)
        node.estimated = True
        if h is None:
            return False
        node.h = max(node.h, h)
        return True

    def expand(self, node: Node, push) -> None:
        conflict = self.choose(node)
        kind = node.kinds.get(conflict, 0)
        if conflict[0] in (VERTEXC, EDGEC) and (self.corridors is not None or self.width is not None):
            conflict, kind = self.symmetry(node, conflict, kind)
        self.stats.setdefault("split", {}).setdefault(KIND_NAMES[conflict[0]], 0)
        self.stats["split"][KIND_NAMES[conflict[0]]] += 1
        children = []
        for k, added in branches(conflict) if self.settings.target or conflict[0] != TARGET \
                else _plain(conflict, self.classic):
            child = self.child(node, k, added)
            if child is None:
                continue
            if self.settings.bypass and kind < 2 and child.g == node.g and len(child.conflicts) < len(node.conflicts):
                self.stats["bypassed"] = self.stats.get("bypassed", 0) + 1
                adopted = Node(node.constraints, child.paths, child.costs, child.conflicts, node.g, node.h,
                               node.depth)
                push(adopted)
                return
            children.append(child)
        for child in children:
            push(child)


def _plain(conflict, classic: bool):
    """A target conflict split as an ordinary one (target reasoning off)."""
    from .conflicts import CELLS, VERTEXC

    kind, i, j, t, where = conflict
    return branches((VERTEXC if classic else CELLS, i, j, t, where))
