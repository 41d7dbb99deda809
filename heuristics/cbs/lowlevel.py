"""One robot's best path under its constraints (space-time A*), and the diagram of all of them.

The search is over ``(pose, time)`` on the robot's walking graph (:class:`~bille.instances.walking.
Walk`): ``g`` is the time, ``h`` the breadth-first distance to the goal (admissible and consistent),
so the first goal node taken is a path of least *cost*: the time after which the robot stands on
its goal for good (the sum-of-costs convention of joint A* and libMultiRobotPlanning). A node is a
goal when the robot's front foot is on its goal cell, the constraints allow it to arrive then
(``AFTER``) and to stand there for ever after. Among paths of least cost it prefers the one with
the fewest conflicts with the other robots' current paths (the *conflict-avoidance table*).

Past the latest time any constraint or other path names, nothing changes with time, so nodes
``(pose, t)`` from then on are one node per pose: the search space is finite and a robot that
cannot reach its goal is found out.

The *MDD* (multi-valued decision diagram, Sharon et al. 2013) of a robot at cost ``c`` holds every
``(pose, time)`` and every move on some path of cost ``c`` that keeps its constraints; a conflict
that every such path has is *cardinal* for the robot (any branch that forbids it raises its cost).
"""
from __future__ import annotations

import heapq
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Callable

from bille.instances.walking import UNREACHABLE

from .constraints import NEVER, Table

Move = tuple[int, int, frozenset]  # (action, next pose, collision cells)


@dataclass(frozen=True, eq=False)
class Agent:
    """What the low level needs of one robot."""

    index: int
    start: int
    moves: Callable[[int], list[Move]]  # wait first: its cells are the pose's own
    dist: list[int]  # steps to the goal per pose (0 everywhere without a goal)
    home: list[bool]  # whether a pose is a goal pose (every pose without a goal)
    goal: int  # front-foot goal cell, -1 for none
    arrays: tuple | None = None  # (succ, wait, dist, home) as numpy: a point robot searched compiled

    def stand(self, pose: int) -> frozenset:
        """The cells of standing still at ``pose``."""
        return self.moves(pose)[0][2]


@dataclass(frozen=True, eq=False)
class Path:
    """Poses at times ``0 .. cost``, the action and the collision cells of each step ``1 .. cost``
    (index 0 unused), and the cost: the time from which the robot stands still for ever (its
    arrival at its goal for good; for a robot without a goal, its last move)."""

    poses: tuple[int, ...]
    actions: tuple[int, ...]
    cells: tuple[frozenset, ...]
    cost: int


class Avoid:
    """The conflict-avoidance table: how often each cell is used at each step by the other
    robots' paths (a tie-breaker only: it never changes a cost)."""

    def __init__(self, paths: list[Path | None], skip: int, classic: bool, stand: list[Callable]) -> None:
        self.classic = classic
        others = [(k, p) for k, p in enumerate(paths) if k != skip and p is not None]
        self.last = max((p.cost for _, p in others), default=0)
        self.steps: list[dict[int, int]] = [{} for _ in range(self.last + 2)]
        self.moves: list[set] = [set() for _ in range(self.last + 2)]
        for k, path in others:
            for t in range(1, self.last + 2):
                if t <= path.cost:
                    if classic:
                        used = (path.poses[t],)
                        if path.poses[t - 1] != path.poses[t]:
                            self.moves[t].add((path.poses[t - 1], path.poses[t]))
                    else:
                        used = path.cells[t]
                else:
                    used = (path.poses[-1],) if classic else stand[k](path.poses[-1])
                row = self.steps[t]
                for c in used:
                    row[c] = row.get(c, 0) + 1

    def count(self, p: int, q: int, cells: frozenset, t: int) -> int:
        last = self.last
        row = self.steps[t if t <= last else last + 1]
        if not row:
            return 0
        if self.classic:
            if t <= last and (q, p) in self.moves[t]:
                return row.get(q, 0) + 1
            return row.get(q, 0)
        return sum(row.get(c, 0) for c in cells)


def allowed(table: Table, classic: bool, p: int, q: int, cells: frozenset, t: int) -> bool:
    """Whether a move from ``p`` to ``q`` with collision ``cells`` in step ``t`` keeps ``table``."""
    banned = table.at.get(t)
    if classic:
        if banned is not None and q in banned:
            return False
        edges = table.edges.get(t)
        if edges is not None and (p, q) in edges:
            return False
        start = table.ranges.get(q)
        return start is None or t < start
    if banned is not None and not banned.isdisjoint(cells):
        return False
    if table.range_cells and not table.range_cells.isdisjoint(cells):
        return all(t < table.ranges[c] for c in cells if c in table.ranges)
    return True


_UNSEEN = (NEVER, NEVER)


class Stopped(Exception):
    """The low level ran past its expansion cap, or the run's budget expired."""


def search(agent: Agent, table: Table, avoid: Avoid | None, classic: bool, *,
           cost_cap: int = NEVER, poll: Callable[[], bool] | None = None, stats: dict | None = None) -> Path | None:
    """The least-cost path of ``agent`` under ``table`` (fewest conflicts with ``avoid`` among
    them), or None if none exists (or none of cost at most ``cost_cap``). ``poll`` is called every
    1,024 expansions; when it returns True the search raises :class:`Stopped`."""
    dist, home, moves = agent.dist, agent.home, agent.moves
    start = agent.start
    if dist[start] >= UNREACHABLE:
        return None
    min_arrival = table.min_arrival
    cap = max(table.last, 0 if avoid is None else avoid.last) + 1
    banned_at, edges_at, ranges, range_cells = table.at.get, table.edges.get, table.ranges, table.range_cells
    count = None if avoid is None else avoid.count
    # classic collisions' table (.classic.ClassicAvoid): its count written out below, once per move
    at = getattr(avoid, "at", None) if classic else None
    if at is not None:
        at_get, at_moves, at_last, at_size = at.get, avoid.moves, avoid.last, avoid.size
    counter = 0
    frontier = [(max(dist[start], min_arrival), 0, 0, counter, start, 0)]
    # per node, the best (time, conflicts) that reached it; past ``cap`` one node holds all times
    # of a pose, and an earlier arrival there beats any later one, whatever its conflicts
    best = {(start, 0): (0, 0)}
    parent: dict[tuple[int, int], tuple[int, int, frozenset]] = {}
    expanded = 0
    found = None
    while frontier:
        f, k, _, _, p, t = heapq.heappop(frontier)
        if best[(p, t if t < cap else cap)] < (t, k):
            continue
        if f > cost_cap:
            break
        if home[p] and t >= min_arrival and t >= table.stay_from(p, agent.stand(p)):
            found = _unwind(parent, p, t)
            break
        expanded += 1
        if poll is not None and expanded % 1024 == 0 and poll():
            raise Stopped
        t1 = t + 1
        banned, edges = banned_at(t1), edges_at(t1)
        for a, q, cells in moves(p):
            d = dist[q]
            if d >= UNREACHABLE:
                continue
            if classic:
                if (banned is not None and q in banned) or (edges is not None and (p, q) in edges) \
                        or (q in ranges and t1 >= ranges[q]):
                    continue
            elif (banned is not None and not banned.isdisjoint(cells)) or \
                    (range_cells and not range_cells.isdisjoint(cells) and
                     any(t1 >= ranges[c] for c in cells if c in ranges)):
                continue
            if at is not None:  # ClassicAvoid.count
                if t1 > at_last:
                    k1 = k + at_get((at_last + 1) * at_size + q, 0)
                else:
                    k1 = k + at_get(t1 * at_size + q, 0) + (p != q and ((t1 * at_size + q) * at_size + p) in at_moves)
            else:
                k1 = k if count is None else k + count(p, q, cells, t1)
            key1 = (q, t1 if t1 < cap else cap)
            if (t1, k1) < best.get(key1, _UNSEEN):
                best[key1] = (t1, k1)
                parent[(q, t1)] = (p, a, cells)
                counter += 1
                f1 = t1 + d
                heapq.heappush(frontier, (f1 if f1 > min_arrival else min_arrival, k1, -t1, counter, q, t1))
    if stats is not None:
        stats["low_expanded"] = stats.get("low_expanded", 0) + expanded
    return found


def _unwind(parent: dict, pose: int, t: int) -> Path:
    poses, actions, cells = [pose], [], []
    while t > 0:
        p, a, c = parent[(pose, t)]
        poses.append(p)
        actions.append(a)
        cells.append(c)
        pose, t = p, t - 1
    return Path(tuple(poses[::-1]), (-1, *actions[::-1]), (frozenset(), *cells[::-1]), len(poses) - 1)


@dataclass(frozen=True, eq=False)
class MDD:
    """Every path of cost ``cost`` that keeps the constraints: ``levels[t]``, the poses at time
    ``t``; ``steps[t]``, the moves ``(p, q, cells)`` of step ``t``."""

    cost: int
    levels: Sequence[frozenset]  # a tuple, or read when asked for (.mdd_compiled)
    steps: Sequence[tuple[tuple[int, int, frozenset], ...]]


def mdd(agent: Agent, table: Table, classic: bool, cost: int) -> MDD:
    """The MDD of ``agent`` at ``cost`` (its least cost under ``table``)."""
    dist, moves = agent.dist, agent.moves
    levels: list[set[int]] = [{agent.start}]
    steps: list[list] = [[]]
    for t in range(1, cost + 1):
        level, step = set(), []
        for p in levels[-1]:
            for a, q, cells in moves(p):
                if t + dist[q] <= cost and allowed(table, classic, p, q, cells, t):
                    level.add(q)
                    step.append((p, q, cells))
        levels.append(level)
        steps.append(step)
    home = agent.home
    keep = {q for q in levels[cost] if home[q] and cost >= table.min_arrival
            and cost >= table.stay_from(q, agent.stand(q))}
    levels[cost] = keep
    for t in range(cost, 0, -1):
        steps[t] = [m for m in steps[t] if m[1] in levels[t]]
        levels[t - 1] = {m[0] for m in steps[t]}
    return MDD(cost, tuple(frozenset(level) for level in levels), tuple(tuple(s) for s in steps))


def meets_all(m: MDD | None, constraints: tuple) -> bool:
    """Whether every path of the MDD is on a cell of the VERTEX ``constraints`` at its time (so
    that forbidding them raises the robot's cost); False without an MDD."""
    if m is None:
        return False
    banned: dict[int, set[int]] = {}
    for _, cell, time in constraints:
        banned.setdefault(time, set()).add(cell)
    reach = set(m.levels[0]) - banned.get(0, set())
    for time in range(1, m.cost + 1):
        ban = banned.get(time, ())
        reach = {q for p, q, _ in m.steps[time] if p in reach and q not in ban}
        if not reach:
            return True
    later = [cells for time, cells in banned.items() if time > m.cost]
    return all(any(p in cells for cells in later) for p in reach)  # a survivor stays on its cell
