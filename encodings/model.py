"""The time-expanded model of an instance over horizon ``T`` (docs/rules.md), as clauses.

One variable layout serves both back ends (:mod:`.cpsat`, :mod:`.cnf`): Boolean variables with
integer ids, clauses, and exactly-one / at-most-one groups.

Variables (``t`` counts time points 0..T; step ``t`` leads from ``t-1`` to ``t``):

- ``y[i, t, p, a]``: robot ``i`` is at pose ``p`` at ``t-1`` and takes action ``a`` at step ``t``;
- ``x[i, t, p]``: robot ``i`` is at pose ``p`` at ``t``;
- ``carry[i, t]``: robot ``i`` carries a tile at ``t``;
- ``tile[t, c]``: cell ``c`` holds a tile at ``t``;
- ``occ[i, t, c]``: robot ``i``'s collision set of step ``t`` contains ``c`` (only where two robots
  could need ``c``);
- ``done[k]``: (assumption) every robot waits after step ``k``: the makespan is at most ``k``;
- ``root``, ``none_before``, ``reach``: the eager connectivity encoding.

Constraints: one action per robot per step (exactly-one over ``y``); poses follow the actions;
pick needs a tile and no load, place a load and an empty cell; carrying and tiles change only by
picks and places; new feet on tiles; per cell and step at most one robot's collision set
(carried-tile cells only while carrying); the goal at ``T``; and the tiles 4-connected at every
step, either eagerly (``reach``: layered reachability from the first tile, i.e. unary distance
labels) or lazily (:func:`connectivity_cuts`, added when a solution breaks it).

Pruning (each can be switched off to measure it), and why no schedule of makespan at most ``T``
is lost (a shorter one is padded with waits, which keep every pose, load and tile):

- *reach* keeps a pose at ``t`` only if the robot can walk there from its start in ``t`` steps and
  on to its goal cell in ``T - t`` steps, in the relaxed pose graph (obstacles only,
  :mod:`bille.instances.distances`). Every step of a schedule is an edge of that graph or leaves
  the pose alone (wait, pick, place), so a pose a schedule visits at ``t`` is that close to both.
- *cells* keeps tile variables only for cells that can ever hold a tile: start or goal tiles, or
  the target of a place action from a pose some robot may have. Only a place creates a tile, so
  every other cell is empty at every time; a pose whose feet need such a cell is never used.
- *change windows*: a cell can change only at a step where some robot may stand at a pose whose
  pick or place targets it; before the first such step it holds its start value, after the last
  its goal value (the value at ``T``), since only picks and places change cells.
- Tiles have no identity: a cell holds a tile or not, so symmetric assignments of tiles to cells
  never arise. The connectivity encodings are argued in :mod:`.connectivity`.
"""
from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from bille.instances import Instance
from bille.instances.run import Budget
from bille.instances.moveset import Kind

from .connectivity import eager_connectivity
from .ends import add_end_constraints, end_roles
from .prune import change_window, prune

CONNECTIVITY = ("eager", "lazy", "cuts")
# the action kinds as plain ints, compared in the inner loops (an enum's attribute lookup costs
# there)
WAIT, MOTION, PICK, PLACE = (int(k) for k in (Kind.WAIT, Kind.MOTION, Kind.PICK, Kind.PLACE))


class OutOfTime(Exception):
    """The budget expired while the model was built."""


@dataclass(frozen=True)
class Options:
    """How to build the model: pruning switches, the connectivity encoding, and three restrictions.

    ``no_scaffold`` restricts the schedules to those that never have a tile on a cell empty both
    at the start and in the goal: nothing is set down, even for a while, where neither has a
    tile (the class ``no-scaffold`` of :mod:`bille.solvers.bounds.classes`). Those cells are constants:
    empty at every step.
    ``keep_structure`` restricts the schedules to those that pick and place only on the cells
    where the start and the goal differ: a tile of both stays where it is, a cell empty in both
    stays empty (no stepping stone, nothing of the structure moved aside and back).
    ``single_carry`` restricts them further to those that carry every tile once, straight from
    its start cell to its goal cell: each of those cells changes once (no tile is set down on the
    way or handed over). It is the baseline of the cooperative gadget (docs/generators.md), whose
    optimum needs a hand-over.
    """

    prune_reach: bool = True
    prune_cells: bool = True
    prune_tiles: bool = True  # reachability in time with the tiles (:mod:`.reach`)
    connectivity: str = "eager"
    single_carry: bool = False
    keep_structure: bool = False
    no_scaffold: bool = False

    @property
    def kept(self) -> bool:
        """Whether the cells where the start and the goal agree never change."""
        return self.single_carry or self.keep_structure

    @property
    def restricted(self) -> bool:
        """Whether no tile is ever on a cell empty at the start and in the goal (each
        restriction implies it)."""
        return self.kept or self.no_scaffold


@dataclass
class Model:
    """Clauses and cardinality groups over variables ``1 .. num_vars`` (DIMACS numbering)."""

    T: int
    names: list = field(default_factory=lambda: [None])
    clauses: list[list[int]] = field(default_factory=list)
    exactly_one: list[list[int]] = field(default_factory=list)
    at_most_one: list[list[int]] = field(default_factory=list)
    y: dict = field(default_factory=dict)  # (i, t) -> list of (var, pose, action)
    tile: dict = field(default_factory=dict)  # (t, cell) -> literal
    done: dict = field(default_factory=dict)  # k -> var
    motion: list[int] = field(default_factory=list)  # y variables of motion actions
    true: int = 0
    candidates: np.ndarray | None = None  # cells that may ever hold a tile
    ends: dict = field(default_factory=dict)  # robot -> [(robot whose end state, x literal)] (:mod:`.ends`)
    families: dict = field(default_factory=dict)  # constraint family -> its share of size(), in build order

    @property
    def num_vars(self) -> int:
        return len(self.names) - 1

    def var(self, name) -> int:
        self.names.append(name)
        return len(self.names) - 1

    def size(self) -> dict:
        return {"variables": self.num_vars, "clauses": len(self.clauses),
                "exactly_one": len(self.exactly_one), "at_most_one": len(self.at_most_one)}

    def dump(self, path) -> None:
        """Write the model as DIMACS CNF for inspection (:func:`.dimacs.dump`)."""
        from .dimacs import dump

        dump(self, path)


def build(instance: Instance, T: int, options: Options = Options(), min_done: int | None = None,
          budget: Budget | None = None, end=None, swap: bool = False) -> Model:
    """The model of ``instance`` with horizon ``T``. With ``min_done``, ``done[k]`` literals for
    ``k = min_done .. T`` are added for an incremental makespan search by assumptions. Raises
    :class:`OutOfTime` once ``budget`` expires while building (its time spent, or the run cancelled).

    With ``end`` (a :class:`~bille.instances.State`), every robot ends at ``T`` in exactly its pose
    and load in ``end`` (robot goal cells are then ignored); the tiles at ``T`` are the goal
    tiles as always. A window of a schedule re-solved this way fits back in its place. With
    ``swap``, interchangeable robots may end in one another's end states (:mod:`.ends`)."""
    return _Builder(instance, T, options, budget, end, swap).build(min_done)


class _Builder:
    def __init__(self, instance: Instance, T: int, options: Options, budget: Budget | None = None,
                 end=None, swap: bool = False) -> None:
        self.budget, self.end = budget, end
        self.roles = end_roles(instance, swap and end is not None)
        if options.connectivity not in CONNECTIVITY:
            raise ValueError(f"connectivity must be one of {CONNECTIVITY}")
        self.inst, self.T, self.opt = instance, T, options
        self.world = instance.world
        self.m = Model(T)
        self.m.true = self.m.var(("true",))
        self.m.clauses.append([self.m.true])
        self.state = instance.start_state

    def tick(self) -> None:
        if self.budget is not None and self.budget.expired():
            raise OutOfTime

    # ---- literals of fixed values ----------------------------------------------------------------

    def const(self, value: bool) -> int:
        return self.m.true if value else -self.m.true

    def build(self, min_done: int | None) -> Model:
        pruned = prune(self.inst, self.T, self.opt, self.end, self.roles)
        self.R, self.cand, self.cells, self.timed = pruned.poses, pruned.cand, pruned.cells, pruned.timed
        self.m.candidates = pruned.cand
        self._family("tiles, loads and poses", self._variables)
        self._family("actions", self._actions)  # with the poses they lead to and the new feet on tiles
        if self.end is not None:
            self._family("window ends", add_end_constraints, self)
        self.tick()
        self._family("picks, places and loads", self._dynamics)
        self.tick()
        self._family("collisions", self._collisions)
        if self.opt.connectivity == "eager":
            self._family("connectivity", eager_connectivity, self)
        if min_done is not None:
            self._family("makespan (done)", self._done, min_done)
        return self.m

    def _family(self, name: str, add, *args) -> None:
        """Add one family of constraints, and record its share of the model (``Model.families``)."""
        before = self.m.size()
        add(*args)
        self.m.families[name] = {k: v - before[k] for k, v in self.m.size().items()}

    # ---- variables ---------------------------------------------------------------------------

    def _variables(self) -> None:
        self._tile_variables()
        self._carry_variables()
        m, T, inst = self.m, self.T, self.inst
        self.x = {}
        for i in range(inst.num_robots):
            self.x[(i, 0, self.state.poses[i])] = m.true
            for t in range(1, T + 1):
                poses = []
                for p in np.flatnonzero(self.R[i][t]).tolist():
                    self.x[(i, t, p)] = m.var(("x", i, t, p))
                    poses.append(self.x[(i, t, p)])
                # one pose at a time: implied by the actions (one per step, each from one pose to
                # one), and said outright it lets the solver conclude sooner (docs/decisions.md)
                m.exactly_one.append(poses)

    def _tile_variables(self) -> None:
        """A tile's presence per step and cell: a constant where the pruning or the class fixes
        it, a variable otherwise; with ``single_carry``, a changing cell changes once."""
        m, T, inst = self.m, self.T, self.inst
        goal, start = inst.goal_tiles, inst.start.tiles
        window = change_window(inst, self.R, T) if self.opt.prune_cells else {}
        for c in self.cells:
            # a cell never in reach keeps its start value; if the goal differs, the clauses of
            # step T contradict and this horizon is infeasible
            lo, hi = window.get(c, (T + 1, T + 1)) if self.opt.prune_cells else (1, T)
            for t in range(T + 1):
                m.tile[(t, c)] = self._tile_at(t, c, lo, hi)
            if self.opt.single_carry and start[c] != goal[c]:
                # the cell changes once, from its start value to its goal value
                for t in range(1, T + 1):
                    before, after = m.tile[(t - 1, c)], m.tile[(t, c)]
                    m.clauses.append([-before, after] if goal[c] else [before, -after])

    def _tile_at(self, t: int, c: int, lo: int, hi: int) -> int:
        """Cell ``c``'s tile at step ``t``, which may change only in steps ``lo .. hi - 1``."""
        goal, start = self.inst.goal_tiles, self.inst.start.tiles
        if t == self.T:
            return self.const(bool(goal[c]))
        if t < lo:
            return self.const(bool(start[c]))
        if t >= hi:
            return self.const(bool(goal[c]))
        if self.timed is not None and not self.timed.tiles[t, c]:
            return self.const(False)
        if self.opt.kept and start[c] == goal[c]:
            return self.const(bool(goal[c]))
        return self.m.var(("tile", t, c))

    def _carry_variables(self) -> None:
        """Whether each robot carries at each step: its start's, its end's where that is known,
        false where the timed reach says so, a variable otherwise."""
        m, T = self.m, self.T
        self.carry = {}
        for i in range(self.inst.num_robots):
            for t in range(T + 1):
                if t == 0:
                    self.carry[(i, t)] = self.const(self.state.carrying[i])
                elif t == T and (self.end is None or len({self.end.carrying[j] for j in self.roles[i]}) == 1):
                    self.carry[(i, t)] = self.const(self.end is not None and bool(self.end.carrying[i]))
                elif self.timed is not None and not self.timed.carry[i, t]:
                    self.carry[(i, t)] = self.const(False)
                else:
                    self.carry[(i, t)] = m.var(("carry", i, t))

    def tile(self, t: int, c: int) -> int:
        return self.m.tile.get((t, c), -self.m.true)

    # ---- actions and poses -------------------------------------------------------------------

    def _actions(self) -> None:
        m, T = self.m, self.T
        for i, g in enumerate(self.world.graphs):
            kind_of = g.kind.tolist()
            manip = np.isin(g.kind, (PICK, PLACE))[None, :]
            for t in range(1, T + 1):
                self.tick()
                prev, nxt = self.R[i][t - 1], self.R[i][t]
                ps = np.flatnonzero(prev)
                succ = g.succ[ps]
                ok = (succ >= 0) & nxt[np.maximum(succ, 0)]
                tgt = g.target[ps]
                ok &= ~manip | ((tgt >= 0) & self.cand[np.maximum(tgt, 0)])
                rows, acts = np.nonzero(ok)
                group = []
                for r, a in zip(rows.tolist(), acts.tolist()):
                    p = int(ps[r])
                    v = m.var(("y", i, t, p, a))
                    group.append((v, p, a))
                    if kind_of[a] == MOTION:
                        m.motion.append(v)
                m.y[(i, t)] = group
                m.exactly_one.append([v for v, _, _ in group])
                incoming, outgoing = defaultdict(list), defaultdict(list)
                for v, p, a in group:
                    q = int(g.succ[p, a])
                    m.clauses.append([-v, self.x[(i, t - 1, p)]])
                    m.clauses.append([-v, self.x[(i, t, q)]])
                    incoming[q].append(v)
                    outgoing[p].append(v)
                for p in np.flatnonzero(nxt).tolist():
                    m.clauses.append([-self.x[(i, t, p)]] + incoming.get(p, []))
                # and a pose leads on by one of its actions: implied (one action per step, from
                # the one pose), said outright for the solver (docs/decisions.md)
                for p in ps.tolist():
                    if self.x[(i, t - 1, p)] != m.true:
                        m.clauses.append([-self.x[(i, t - 1, p)]] + outgoing.get(p, []))
                # new feet on tiles (rule 4)
                for p in np.flatnonzero(nxt).tolist():
                    for c in set(g.feet[p].tolist()):
                        m.clauses.append([-self.x[(i, t, p)], self.tile(t, c)])

    def _dynamics(self) -> None:
        """Preconditions (rule 1), carrying, and tiles appearing and vanishing."""
        m, T = self.m, self.T
        picks, places = defaultdict(list), defaultdict(list)
        for i, g in enumerate(self.world.graphs):
            kind_of = g.kind.tolist()
            for t in range(1, T + 1):
                was, now = self.carry[(i, t - 1)], self.carry[(i, t)]
                my_picks, my_places = [], []
                for v, p, a in m.y[(i, t)]:
                    kind = kind_of[a]
                    if kind == PICK:
                        c = int(g.target[p, a])
                        m.clauses += [[-v, -was], [-v, now], [-v, self.tile(t - 1, c)], [-v, -self.tile(t, c)]]
                        picks[(t, c)].append(v)
                        my_picks.append(v)
                    elif kind == PLACE:
                        c = int(g.target[p, a])
                        m.clauses += [[-v, was], [-v, -now], [-v, -self.tile(t - 1, c)], [-v, self.tile(t, c)]]
                        places[(t, c)].append(v)
                        my_places.append(v)
                    elif not g.carry_ok[p, a]:
                        m.clauses.append([-v, -was])  # a carried tile would leave the workspace
                m.clauses.append([-now, was] + my_picks)
                m.clauses.append([-was, now] + my_places)
        for t in range(1, T + 1):
            for c in self.cells:
                m.clauses.append([-self.tile(t, c), self.tile(t - 1, c)] + places[(t, c)])
                m.clauses.append([-self.tile(t - 1, c), self.tile(t, c)] + picks[(t, c)])

    def _collisions(self) -> None:
        """Per step and cell, at most one robot's collision set (rule 3). A robot's feet before
        and after the step are implied to be in it by its poses at ``t - 1`` and ``t``, the other
        cells (swept, target) by its action, and the carried-tile cells by its action and its load.
        The poses say the same as the actions that leave and reach them (a robot has one pose at
        a time, and every action from a pose needs its feet), in fewer clauses, and the solver
        decides faster with them (docs/decisions.md)."""
        m = self.m
        if self.inst.num_robots < 2:
            return
        shared = {id(g): g.feet.tolist() for g in self.world.graphs}  # once per moveset, not per robot
        feet_of = [shared[id(g)] for g in self.world.graphs]  # robot -> pose -> its feet' cells
        for t in range(1, self.T + 1):
            self.tick()
            users = defaultdict(lambda: defaultdict(dict))  # cell -> robot -> {(literal, conditional?)}
            for i, g in enumerate(self.world.graphs):
                for v, p, a in m.y[(i, t)]:
                    q = int(g.succ[p, a])
                    feet = {c: self.x[(i, t, q)] for c in feet_of[i][q]}
                    feet.update({c: self.x[(i, t - 1, p)] for c in feet_of[i][p]})
                    for c in g.coll[p, a].tolist():
                        if c >= 0:
                            users[c][i][feet.get(c, v), False] = None
                    for c in g.carry[p, a].tolist():
                        if c >= 0:
                            users[c][i][v, True] = None
            for c, by_robot in users.items():
                if len(by_robot) < 2:
                    continue
                group = []
                for i, uses in by_robot.items():
                    occ = m.var(("occ", i, t, c))
                    group.append(occ)
                    was = self.carry[(i, t - 1)]
                    for v, conditional in uses:
                        m.clauses.append([-v, -was, occ] if conditional else [-v, occ])
                m.at_most_one.append(group)

    def _done(self, min_done: int) -> None:
        """``done[k]``: every robot waits at every step after ``k`` (a clause per later step; no
        chain ``done[k] -> done[k + 1]``, which steers the solvers worse: docs/decisions.md)."""
        m, first = self.m, max(0, min_done)
        waits = {(i, t): [v for v, p, a in m.y[(i, t)] if g.kind[a] == WAIT]
                 for i, g in enumerate(self.world.graphs) for t in range(first + 1, self.T + 1)}
        for k in range(first, self.T + 1):
            d = m.var(("done", k))
            m.done[k] = d
            for i in range(len(self.world.graphs)):
                for t in range(k + 1, self.T + 1):
                    m.clauses.append([-d] + waits[(i, t)])
