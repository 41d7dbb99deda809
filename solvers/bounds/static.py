"""Lower bounds on the makespan, and static proofs that no schedule exists.

Every part is a theorem about *every* valid schedule of the instance, under the full rules:
several robots, tiles that are picked and placed again (a tile that stays may leave its cell and
come back, another tile may take its place), relays and hand-overs (a tile set down by one robot
and picked up by another), tiles carried at the start. Distances are those of the relaxed pose
graph (:mod:`bille.instances.distances`): no schedule walks between two poses faster. The parts:

``robot goals``
    A robot with a goal cell must stand on it after the last step, so the makespan is at least its
    relaxed distance from its start to a pose with the front foot there.
``manipulations``
    Let ``R`` be the cells that hold a tile at the start and not in the goal (``k = |R|``), ``F``
    those that hold one in the goal and not at the start, and ``c`` the robots carrying at the
    start; tiles are conserved, so ``|F| = k + c``. Only a pick empties a cell and only a place
    fills one, so every cell of ``R`` is picked at least once and every cell of ``F`` placed at
    least once: at least ``k`` picks and ``k + c`` places. If every robot picks and places on one
    and the same cell from a pose (Bill-E: the cell ahead of its front foot), at least ``k`` more
    motions: the last pick at a cell of ``R`` takes a tile that its robot must set down (no robot
    carries at the end) somewhere else (were it set down on the same cell, that cell would end
    with a tile), which needs the robot to have moved in between; these picks are distinct, and
    so are their carries. A robot takes one action per step, so ``m`` robots need at least
    ``ceil(actions / m)`` steps.
``first place on every cell to fill``
    Take the last place on a cell ``v`` of ``F`` and the robot that makes it, standing at a pose
    ``p`` facing ``v``. It carries a tile; either it has carried one since the start (then the
    step is at least ``dist(start, p) + 1``), or its last pick before happened at some pose
    ``q``, at a step at least ``dist(start, q) + 1``, and then the place comes at least
    ``dist(q, p) + 1`` steps later. The minimum over robots and poses of these bounds that step,
    and so the makespan, for every ``v`` of ``F``: the bound is the maximum over ``F``. A pick
    from *any* cell counts (a tile that stays may be the one carried, and another tile refill
    its cell), which is what makes the bound hold for relays.
``last pick from every cell to empty``
    The last pick at a cell ``u`` of ``R`` happens at a pose ``q`` facing ``u``, at a step at
    least ``dist(start, q) + 1``; its tile is set down later, at least one step later, and at
    least two if the robot picks and places ahead of itself (it must move first; see above).
``carrying (matching)``
    A carry segment (pick at ``u``, place at ``v``, one robot) takes a pick, a place, and at
    least the relaxed distance from a pose picking at ``u`` to one placing at ``v`` in motions:
    its *cost* in actions. Chaining segments through intermediate cells (relays, tiles set aside)
    gives the shortest-path closure ``d*(u, v)``, in which every intermediate cell costs its
    place and its pick again (a tile set down on one side of a cell and picked up from the
    other moves two cells for those two actions, never for free). The multiset of all segments
    of a schedule is a flow in which every cell of ``R`` sends one unit more than it receives
    and every cell of ``F`` receives one more than it sends (the tiles carried at the start add
    sources of their own). Decomposing it into paths and cycles, the paths leaving ``R`` end at
    distinct cells of ``F``, each costing at least ``d*`` of its ends, and the paths from the
    carried tiles end with a place each: the segments, which are different actions, cost at
    least a minimum-cost assignment of ``R`` to distinct cells of ``F`` under ``d*``, plus ``c``:
    ``ceil((assignment + c) / m)`` steps.

``crossings``
    Tiles that must cross a line between two columns or rows, each in one robot's trip from a
    pick on one side to a place on the other: with more such tiles than robots, a robot makes
    the trip and the way back more than once (:mod:`.crossings`, whose docstring proves it).
``routing (LP)``
    The carries together with the walks back for more tiles, as a flow of robots through pick
    and place events with tiles conserved cell by cell: a linear program whose minimum bounds
    the actions of every schedule (:mod:`.routing`, whose docstring proves it).
``scaffold scenarios (LP)``
    The same program split by which thin columns (or rows) of the map ever hold a tile set down
    where neither the start nor the goal has one, with the places that scaffold costs: the least
    over those scenarios, by a branch and bound that may stop at any time (:mod:`.scaffold`,
    whose docstring proves it).

Static infeasibility (``impossible``): tiles to move and no robot; a robot whose goal cell is unreachable; a cell of ``F``
that no robot can ever place on (the bound above is infinite); a cell of ``R`` that no robot
can ever pick at; cells of ``R`` that cannot all be assigned to cells of ``F`` at a finite
closure distance. Each contradicts a part above, which holds for every schedule.

Within a class of schedules (:mod:`.classes`: e.g. those that never set a tile down where
neither the start nor the goal has one) the same parts are theorems about the schedules of the
class when computed on its *ground* (:class:`Ground`): the cells a foot can stand on, and the
cells a pick and a place can target, in any schedule of the class. Every proof above uses the
schedule only through the poses it stands in, its picks and its places, and their distances in
the relaxed graph; in a schedule of the class, each of those lies on the ground, so the relaxed
graph restricted to the ground (:func:`~bille.instances.distances.relaxed_for` with ``ground``)
and the events restricted to it give bounds, and proofs of emptiness, for the class.

Checked against the brute-force search (``bille solve -m bfs``) on random tiny instances by
``tests/test_soundness.py``: no part may exceed a proved optimum.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from bille.instances import Instance
from bille.instances.distances import INF, manipulates_ahead
from bille.instances.moveset import Kind
from bille.instances.run import Budget

from .crossings import crossings_bound
from .ground import EVERYWHERE, Ground
from .routing import routing_bound
from .scaffold import Scenarios, scaffold_search


def _scaffold_budget(budget: Budget | None) -> Budget | None:
    """The scaffold scenarios' time: a quarter of what is left of ``budget`` (at most
    :data:`.scaffold.SECONDS`)."""
    return None if budget is None else budget.share(0.25)


@dataclass
class Bounds:
    """Lower bound on the makespan, its parts, and reasons why no schedule exists (if any);
    ``classes``: the bounds of the classes of schedules (:func:`.classes.class_bounds`) where
    ``solve()`` computed them with this bound; ``scaffold``: the scaffold scenarios' search
    where more time can raise its part (:class:`.scaffold.Scenarios`: ``anytime`` takes it
    further)."""

    lower: int
    parts: dict
    impossible: list[str]
    classes: dict | None = None
    scaffold: Scenarios | None = None


def lower_bound(instance: Instance, *, budget: Budget | None = None, ground: Ground = EVERYWHERE) -> Bounds:
    """The makespan lower bound of the module docstring, and static proofs of infeasibility;
    for the schedules that keep to ``ground`` (a class's, :mod:`.classes`) if given.

    ``budget`` limits the linear program of the routing part, the one part that can take long:
    once it has expired (time spent, or the run cancelled), that part is left out (None)."""
    world = instance.world
    state = instance.start_state
    start, goal = instance.start.tiles, instance.goal_tiles
    remove, fill = start & ~goal, goal & ~start
    relaxed = [ground.relaxed(g) for g in world.graphs]
    m = max(1, instance.num_robots)
    parts: dict = {}
    impossible: list[str] = []
    scaffold = None

    goal_steps = 0
    for i, cell in enumerate(instance.goal_cells):
        if cell < 0:
            continue
        d = int(relaxed[i].to_front(cell)[state.poses[i]])
        if d >= INF:
            impossible.append(f"robot {i} can never reach its goal cell {world.xy(cell)}")
        else:
            goal_steps = max(goal_steps, d)
    parts["robot goals"] = goal_steps

    k, carried = int(remove.sum()), int(sum(state.carrying))
    if k and not instance.num_robots:
        impossible.append(f"the goal moves {k} tiles and there is no robot")
    elif k or carried:
        ahead = {id(g): manipulates_ahead(g) for g, _ in world.groups}  # per moveset graph
        actions = 2 * k + carried + (k if all(ahead.values()) else 0)
        parts["manipulations"] = -(-actions // m)
        from_start = [r.from_pose(p) for r, p in zip(relaxed, state.poses)]
        place = _first_places(world, ground, from_start, state.carrying, fill)
        parts["first place on every cell to fill"] = _worst(place, fill, world, impossible,
                                                            "no robot can ever place a tile on {}")
        pick = _last_picks(world, ground, from_start, ahead)
        parts["last pick from every cell to empty"] = _worst(pick, remove, world, impossible,
                                                             "no robot can ever pick the tile at {}")
        carry = _transport(world, ground, remove, fill)
        if carry is None:
            impossible.append("the tiles that must go cannot all be carried to cells that must be filled")
        else:
            parts["carrying (matching)"] = -(-(carry + carried) // m)
            parts["crossings"] = crossings_bound(instance, ground, budget)
            parts["routing (LP)"] = routing_bound(instance, ground, budget)
            if ground is EVERYWHERE:  # within a class's ground, scaffold is already priced or ruled out
                best = max([v for v in parts.values() if v is not None] + [0])
                scaffold = scaffold_search(instance, _scaffold_budget(budget), floor=best)
                parts["scaffold scenarios (LP)"] = scaffold.value
    lower = max([v for v in parts.values() if v is not None] + [0])
    return Bounds(lower, parts, impossible, scaffold=None if scaffold is None or scaffold.finished else scaffold)


def _worst(earliest: np.ndarray, cells: np.ndarray, world, impossible: list[str], why: str) -> int | None:
    """The largest of the per-cell bounds ``earliest`` over the cells of the mask; an unreachable
    cell is a proof of infeasibility (its bound is None then)."""
    values = earliest[cells]
    if not len(values):
        return 0
    if (values >= INF).any():
        bad = np.flatnonzero(cells & (earliest >= INF))[0]
        impossible.append(why.format(world.xy(int(bad))))
        return None
    return int(values.max())


def _first_places(world, ground: Ground, from_start, carrying, fill) -> np.ndarray:
    """Per cell: the earliest step at which any robot can place a tile there (``INF`` if never),
    carrying from the start or after a pick anywhere (module docstring)."""
    n = world.width * world.height
    best = np.full(n, INF, dtype=np.int64)
    if not fill.any():
        return best
    for i, g in enumerate(world.graphs):
        picks, _ = ground.targets(g, Kind.PICK, n)
        offsets = np.full(g.num_poses, INF, dtype=np.int64)
        picked = np.unique(picks)
        offsets[picked] = np.where(from_start[i][picked] < INF, from_start[i][picked] + 1, INF)
        if carrying[i]:
            offsets = np.minimum(offsets, from_start[i])
        loaded = ground.relaxed(g).from_offsets(offsets)  # earliest arrival at each pose with a tile
        poses, cells = ground.targets(g, Kind.PLACE, n)
        arrive = loaded[poses]
        ok = arrive < INF
        np.minimum.at(best, cells[ok], arrive[ok] + 1)
    return best


def _last_picks(world, ground: Ground, from_start, ahead: dict) -> np.ndarray:
    """Per cell: the earliest step by which a tile picked there can have been set down again
    (``ahead``: per graph id, whether its robots pick and place on one cell from a pose)."""
    n = world.width * world.height
    best = np.full(n, INF, dtype=np.int64)
    for i, g in enumerate(world.graphs):
        poses, cells = ground.targets(g, Kind.PICK, n)
        reach = from_start[i][poses]
        ok = reach < INF
        down = 2 + (1 if ahead[id(g)] else 0)
        np.minimum.at(best, cells[ok], reach[ok] + down)
    return best


def _transport(world, ground: Ground, remove: np.ndarray, fill: np.ndarray) -> int | None:
    """Least cost in actions of carrying the tiles that must go: a minimum-cost assignment of the
    cells that must empty to distinct cells that must fill under the closure ``d*`` of the module
    docstring. None if no assignment of finite cost exists.

    ``d*`` is a shortest path in one graph: the relaxed poses of every robot type, plus a node
    per cell; a cell leads to the poses that pick at it and a pose to the cells it places at,
    each edge one action (the pick, the place).
    """
    rm, fl = np.flatnonzero(remove), np.flatnonzero(fill)
    if not len(rm):
        return 0
    if len(fl) < len(rm):
        return None
    n = world.width * world.height
    rows, cols, weights = [], [], []
    base = n  # cells are nodes 0 .. n-1, then each robot type's poses
    for g in {id(g): g for g in world.graphs}.values():
        e = ground.relaxed(g).edges.tocoo()
        rows += [e.row + base]
        cols += [e.col + base]
        weights += [e.data]
        p, c = ground.targets(g, Kind.PICK, n)
        rows, cols, weights = rows + [c], cols + [p + base], weights + [np.ones(len(p))]
        p, c = ground.targets(g, Kind.PLACE, n)
        rows, cols, weights = rows + [p + base], cols + [c], weights + [np.ones(len(p))]
        base += g.num_poses
    graph = csr_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), shape=(base, base))
    d = dijkstra(graph, indices=rm)[:, fl]
    if not np.isfinite(d).any(axis=1).all():
        return None
    big = 1e12
    cost = np.where(np.isfinite(d), np.round(d), big)
    r, c = linear_sum_assignment(cost)
    total = cost[r, c].sum()
    return None if total >= big else int(total)
