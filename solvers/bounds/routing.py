"""A lower bound on the makespan from the robots' routes: carrying *and* walking back for more
(a part of :mod:`.static`, "routing (LP)").

**The theorem.** Take any valid schedule of makespan ``T``. Each robot's actions split into
*carries* (from a pick to the next place: the pick, the motions, the place) and *walks* (from
its start or a place to its next pick or its end: motions only). A carry from a pose facing cell
``c`` to one facing ``d`` takes at least ``D(c, d) + 2`` actions, a walk between poses at least
their distance ``D``, both in the relaxed pose graph (obstacles only; the distances of
:mod:`bille.instances.distances`, which no schedule beats). Every robot takes one action per
step, so all robots together take at most ``m T`` actions: ``T >= cost / m`` for the total cost
of the carries and walks of the schedule.

The carries and walks form a flow of robots through *event* nodes, a pick node ``K_c`` and a
place node ``P_c`` per cell: each robot leaves its start (for a pick node, or a place node if it
carries a tile at the start, or straight for its end), enters a place node after each pick node
(a carry) and a pick node or its end after each place node (a walk); no robot ends carrying.
Tiles are conserved cell by cell: a cell ends with a tile iff it started with one plus the
places on it minus the picks from it, so ``places(c) - picks(c) = goal(c) - start(c)``, with
relays, tiles set aside and tiles that stay but move all counted. The schedule's flow is an
integer solution of that linear program (robot supply 1 per start, conservation at every event
node, the tile balance per cell) of cost at most ``m T``; the program's minimum over all real
solutions (a linear relaxation: event order, collisions and connectivity are left out, and
robots of different movesets share the distances of the nearest one) is at most the
schedule's cost. So ``T >= ceil(LP / m)``. An infeasible program would mean no flow exists,
which the carrying bound's assignment already says of these instances (it is not used as a
proof here).

Distances: ``D(c, d)`` is the least relaxed distance from a pose that picks at ``c`` to one that
places at ``d`` (over the robot types), and so on for each kind of arc; the end of a walk costs a
robot's distance to its goal cell (the least over the robots, since robots share the flow).

The program has two arcs per pair of cells, so it is built only for instances of at most
:data:`MAX_CELLS` cells that some robot can pick or place on.

**Split by robot** (``split``). The schedule's flow is the sum of one flow per robot: robot
``r``'s carries and walks, in order, are a path from its own start through the event nodes to its
end, a unit flow of integers, and it takes at most ``T`` actions, so the cost of its path is at
most ``T``. So ``T`` is at least the least ``t`` of an integer program: one copy of the arcs and
of the conservation rows per robot (robot ``r``'s copy leaves only its own start), the tile
balance and the groups on their sum, and each copy's cost at most ``t``. It is stronger where
the linear program shares the work out evenly in fractions that no robot's own path can take:
on lt-2's scenario with scaffold in every column of the bridge, 102 actions are 51 steps for
each of the two robots in fractions, but 52 for one of them in integers. The program is solved by HiGHS's
branch and bound (through OR-Tools); its proved bound is used, as the ceiling: the least ``t``
is the cost of some robot's path, an integer. It has ``m`` times the arcs and is an integer
program, seconds where the linear program takes a fraction of one, so it is solved only where
asked (:mod:`.scaffold`, for the scenario that holds its bound down).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linprog
from scipy.sparse import coo_matrix, vstack

from bille.instances import Instance
from bille.instances.distances import INF
from bille.instances.moveset import Kind
from bille.instances.run import Budget

MAX_CELLS = 200


def routing_bound(instance: Instance, ground, budget: Budget | None = None, places=(),
                  split: bool = False) -> int | None:
    """``ceil(LP / m)`` of the module docstring, or None when the program is not built (too
    many cells) or not solved (within ``budget``, or not at all: infeasible). ``ground``
    (:class:`.ground.Ground`) gives the relaxed graphs and the ``(pose, cell)`` pairs of the
    events; within a class of schedules, its ground's (the distances and events of every
    schedule of the class). ``places``: groups of cells, each of which the schedules considered
    place a tile on at least once (a row ``sum of the places on the group >= 1`` each: the flow
    of such a schedule meets it); a group no robot can place on gives None."""
    world = instance.world
    n = world.width * world.height
    graphs = list({id(g): g for g in world.graphs}.values())
    faces = _faces(ground, graphs, n)
    cells = sorted(set().union(*(per.keys() for kind in faces.values() for per in kind.values())))
    if not cells or len(cells) > MAX_CELLS:
        return None
    k = len(cells)
    start, goal = instance.start.tiles, instance.goal_tiles
    balance = np.array([int(goal[c]) - int(start[c]) for c in cells], dtype=float)
    outside = (goal & ~start).copy()
    outside[cells] = False
    if outside.any() or (start & ~goal & ~_mask(n, cells)).any():
        return None  # a cell to change that nobody can reach: the static proofs say so

    index = {c: j for j, c in enumerate(cells)}

    def from_sets(g, kind_from, kind_to):
        """``[i, j]``: least distance from a ``kind_from`` pose of ``cells[i]`` to a ``kind_to``
        pose of ``cells[j]`` for robots of ``g``."""
        relaxed = ground.relaxed(g)
        out = np.full((k, k), INF, dtype=np.int64)
        to = faces[kind_to][id(g)]
        dest = np.array([p for c in to for p in to[c]], dtype=np.int64)
        column = np.array([index[c] for c in to for _ in to[c]], dtype=np.int64)
        for c, src in faces[kind_from][id(g)].items():
            np.minimum.at(out[index[c]], column, relaxed.from_poses(src)[dest])
        return out

    carry = np.minimum.reduce([from_sets(g, Kind.PICK, Kind.PLACE) for g in graphs])
    walk = np.minimum.reduce([from_sets(g, Kind.PLACE, Kind.PICK) for g in graphs])
    m = instance.num_robots
    robot_rows, ends = _robot_rows(instance, ground, faces, cells)
    groups = [[index[c] for c in group if c in index] for group in places]
    if not all(groups):
        return None
    return _solve(k, m, balance, carry, walk, ends, robot_rows, budget, groups, split)


def _faces(ground, graphs, n: int) -> dict:
    """``kind -> graph id -> cell -> poses``: the poses of each graph whose pick (place) targets
    each cell, from ``ground``."""
    faces = {Kind.PICK: {}, Kind.PLACE: {}}
    for g in graphs:
        for kind in faces:
            poses, cells = ground.targets(g, kind, n)
            per = faces[kind].setdefault(id(g), {})
            for p, c in zip(poses.tolist(), cells.tolist()):
                per.setdefault(c, []).append(p)
    return faces


def _robot_rows(instance: Instance, ground, faces: dict, cells: list[int]):
    """Per robot ``(first, alone, carrying)``: the steps to its first event at each cell (a place
    if it carries, a pick otherwise), the steps to its end without any event, and whether it
    carries; and ``ends[j]``: the least walk from a place at ``cells[j]`` to some robot's end."""
    world, state, goal_cells = instance.world, instance.start_state, instance.goal_cells
    ends = np.full(len(cells), INF, dtype=np.int64)
    rows = []
    for r, (g, p) in enumerate(zip(world.graphs, state.poses)):
        relaxed = ground.relaxed(g)
        here = relaxed.from_pose(p)
        to_goal = relaxed.to_front(goal_cells[r]) if goal_cells[r] >= 0 else np.zeros(g.num_poses, np.int64)
        first = Kind.PLACE if state.carrying[r] else Kind.PICK
        row = np.array([here[faces[first][id(g)][c]].min() if c in faces[first][id(g)] else INF for c in cells])
        rows.append((row, int(to_goal[p]), bool(state.carrying[r])))
        place = faces[Kind.PLACE][id(g)]
        ends = np.minimum(ends, [to_goal[place[c]].min() if c in place else INF for c in cells])
    return rows, ends


def _mask(n: int, cells: list[int]) -> np.ndarray:
    out = np.zeros(n, bool)
    out[cells] = True
    return out


def _solve(k, m, balance, carry, walk, ends, robot_rows, budget: Budget | None, groups=(), split=False) -> int | None:
    """Build and solve the program: variables are arc flows; rows are the robot supplies (0 ..
    m-1), the conservation at the pick nodes (``K``) and the place nodes (``P``: inflow minus
    outflow is 0), and the tile balance per cell (``B``: arcs into its place node minus arcs
    into its pick node); then one inequality per group of place nodes (``groups``, indices of
    cells): the arcs into them sum to at least 1. With ``split``, the integer program of the
    module docstring's last section: one copy of the arcs and of ``K`` and ``P`` per robot."""
    arcs = []  # (robot, or None for every robot: cost, [(block, indices, values), ...])
    for r, (first, alone, carrying) in enumerate(robot_rows):
        j = np.flatnonzero(first < INF)
        one = np.ones(len(j))
        if carrying:  # its first event is a place
            arcs.append((r, first[j] + 1, [("supply", np.full(len(j), r), one), ("P", j, one), ("B", j, one)]))
        else:
            arcs.append((r, first[j] + 1, [("supply", np.full(len(j), r), one), ("K", j, one), ("B", j, -one)]))
            if alone < INF:  # it never picks
                arcs.append((r, np.array([alone]), [("supply", np.array([r]), np.ones(1))]))
    i, j = np.nonzero(carry < INF)  # a carry: the pick was paid on the way in, the place here
    one = np.ones(len(i))
    arcs.append((None, carry[i, j] + 1, [("K", i, -one), ("P", j, one), ("B", j, one)]))
    j, i = np.nonzero(walk < INF)  # a walk, and the pick it ends with
    one = np.ones(len(i))
    arcs.append((None, walk[j, i] + 1, [("P", j, -one), ("K", i, one), ("B", i, -one)]))
    j = np.flatnonzero(ends < INF)
    arcs.append((None, ends[j], [("P", j, -np.ones(len(j)))]))
    if budget is not None and budget.expired():
        return None
    if split:
        return _split(k, m, balance, arcs, budget, groups)
    first_row = {"supply": 0, "K": m, "P": m + k, "B": m + 2 * k}
    a, costs, _ = _matrix(arcs, lambda block, r: first_row[block], m + 3 * k, [None])
    b = np.concatenate([np.ones(m), np.zeros(2 * k), balance])
    options = {}
    if budget is not None and budget.seconds() is not None:
        options["time_limit"] = budget.seconds()
    bounds_ub = {}
    if groups:
        bounds_ub = {"A_ub": -(_members(groups, k) @ a[m + k:m + 2 * k].maximum(0)), "b_ub": -np.ones(len(groups))}
    got = linprog(costs, A_eq=a, b_eq=b, bounds=(0, None), method="highs", options=options, **bounds_ub)
    if got.status != 0:  # not solved (in time): no bound from the program
        return None
    return int(np.ceil(got.fun / m - 1e-6))


def _matrix(arcs, first_row, rows: int, owners):
    """The sparse matrix of ``arcs`` (:func:`_solve`), its column costs and each column's robot:
    the arcs of every robot once per owner in ``owners`` (``[None]``: once, shared), block
    ``block``'s rows of robot ``r`` starting at ``first_row(block, r)``."""
    entries, costs, owner, base = [], [], [], 0
    for who, cost, blocks in arcs:
        for r in owners if who is None else [who]:
            n = len(cost)
            for block, index, values in blocks:
                entries.append((first_row(block, r) + index, base + np.arange(n), values))
            costs.append(np.asarray(cost, dtype=float))
            owner.append(np.full(n, -1 if r is None else r))
            base += n
    rows_, cols, vals = (np.concatenate(part) for part in zip(*entries))
    return coo_matrix((vals, (rows_, cols)), shape=(rows, base)).tocsr(), np.concatenate(costs), np.concatenate(owner)


def _members(groups, k: int):
    """``[group, cell]``: whether the cell is in the group."""
    sizes = [len(g) for g in groups]
    return coo_matrix((np.ones(sum(sizes)), (np.repeat(np.arange(len(groups)), sizes), np.concatenate(groups))),
                      shape=(len(groups), k)).tocsr()


def _split(k, m, balance, arcs, budget: Budget | None, groups) -> int | None:
    """The per-robot integer program (module docstring), solved by HiGHS's branch and bound
    within ``budget``; the ceiling of its proved bound, or None where none is proved in time."""
    from ortools.linear_solver import pywraplp

    def first_row(block, r):  # per robot: its supply row, then its K and P rows; B shared
        return {"supply": 0, "K": m + 2 * k * r, "P": m + 2 * k * r + k, "B": m + 2 * k * m}[block]

    a, costs, owner = _matrix(arcs, first_row, m + 2 * k * m + k, range(m))
    b = np.concatenate([np.ones(m), np.zeros(2 * k * m), balance])
    solver = pywraplp.Solver.CreateSolver("HIGHS")
    if solver is None:  # an OR-Tools built without HiGHS
        return None
    solver.SetNumThreads(1)
    # HiGHS's reduced-cost heuristic at the root ignores the time limit on these programs (minutes)
    solver.SetSolverSpecificParametersAsString("mip_heuristic_run_root_reduced_cost = false\noutput_flag = false")
    infinity = solver.infinity()
    flow = [solver.IntVar(0, infinity, "") for _ in range(a.shape[1])]
    makespan = solver.NumVar(0, infinity, "T")
    rows = [a]
    if groups:
        into = [a[first_row("P", r):first_row("P", r) + k].maximum(0) for r in range(m)]
        rows.append(_members(groups, k) @ sum(into))
    bounds = [(v, v) for v in b] + [(1, infinity)] * len(groups)
    matrix = vstack(rows).tocsr()
    for row, (low, high) in enumerate(bounds):
        constraint = solver.Constraint(float(low), float(high))
        for col, value in zip(matrix.indices[matrix.indptr[row]:matrix.indptr[row + 1]],
                              matrix.data[matrix.indptr[row]:matrix.indptr[row + 1]]):
            constraint.SetCoefficient(flow[col], float(value))
    for r in range(m):  # robot r takes at most T actions
        constraint = solver.Constraint(-infinity, 0.0)
        constraint.SetCoefficient(makespan, -1.0)
        for col in np.flatnonzero(owner == r):
            constraint.SetCoefficient(flow[col], float(costs[col]))
    solver.Minimize(makespan)
    if budget is not None and budget.expired():
        return None
    if budget is not None and budget.seconds() is not None:
        solver.SetTimeLimit(max(1, int(1000 * budget.seconds())))
    status = solver.Solve()
    bound = solver.Objective().BestBound()
    if status not in (pywraplp.Solver.OPTIMAL, pywraplp.Solver.FEASIBLE) or not np.isfinite(bound):
        return None
    return int(np.ceil(bound - 1e-6))
