"""Joint states of all robots walking on a fixed structure (paper, Methods, "Graph representation").

Shared by joint A* and M*. A joint state is a tuple of poses plus, per robot, a *debt*: the
number of steps it has waited at its goal for free. The objective is the sum of costs: each
robot pays 1 per step until it reaches its goal for the last time, waiting included. A step
that starts and ends at the goal is free but adds to the debt, and a robot that leaves its goal
pays its debt then. States are tuples of ints; costs are pairs ``(sum of costs, makespan)``,
compared lexicographically ("ties broken by makespan").
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Iterator

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.claim import EVERY, Claim
from bille.instances.failure import Failure, no_schedule
from bille.instances.limits import CHECK_EVERY, check_budget
from bille.instances.result import Result
from bille.instances.run import Budget
from bille.instances.schedule import Schedule
from bille.instances.successors import backtrack
from bille.instances.walking import UNREACHABLE, Walk, walk_for

Poses = tuple[int, ...]
Debts = tuple[int, ...]
# what joint A* and M* minimize: the sum of costs, then the makespan, over walking schedules
CLAIM = Claim("sum-of-costs", then="makespan", walking_only=True)


class OutOfTime(Exception):
    """The time limit passed in the middle of one state's joint actions."""


@dataclass
class JointProblem:
    """A path-planning instance as a search problem over joint states."""

    instance: Instance
    walks: list[Walk]
    goals: tuple[int, ...]  # front-foot goal cell per robot, -1 = anywhere
    dists: list[np.ndarray]  # per robot: steps from each pose to its goal (0 everywhere if none)
    starts: tuple[int, ...] | None = None  # start poses (default: the instance's)
    homes: list[np.ndarray] | None = None  # per robot: goal poses (default: front foot on the goal)

    # plain lists for the inner loops (indexing numpy per call costs more than the search),
    # made when first read (the compiled generators read the arrays instead)
    @cached_property
    def dist_lists(self) -> list[list[int]]:
        """``dist_lists[i][p] = dists[i][p]``."""
        return [d.tolist() for d in self.dists]

    @cached_property
    def home_lists(self) -> list[list[bool]]:
        """``home_lists[i][p]``: pose ``p`` is one of robot ``i``'s goal poses."""
        if self.homes is not None:
            return [h.tolist() for h in self.homes]
        return [[True] * w.succ.shape[0] if c < 0 else _flags(w.succ.shape[0], w.graph.feet[:, 0] == c)
                for w, c in zip(self.walks, self.goals)]

    @cached_property
    def dist_table(self) -> np.ndarray:
        """``dists`` stacked as one ``int64`` array ``[robot, pose]`` (robots on one pose graph)."""
        if not self.dists:
            return np.zeros((0, self.walks[0].succ.shape[0] if self.walks else 0), np.int64)
        return np.stack([np.asarray(d, dtype=np.int64) for d in self.dists])

    @cached_property
    def home_table(self) -> np.ndarray:
        """``home_table[i, p]``: pose ``p`` is one of robot ``i``'s goal poses (robots on one pose
        graph), as ``home_lists``."""
        if self.homes is not None:
            return np.stack([np.asarray(h, dtype=np.bool_) for h in self.homes])
        walk = self.walks[0]
        goals = np.array(self.goals, dtype=np.int64)[:, None]
        return np.where(goals < 0, True, walk.graph.feet[:, 0][None, :] == goals)

    @classmethod
    def of(cls, instance: Instance, method: str = "astar") -> "JointProblem":
        require_path_planning(instance, method)
        check_tables(instance, method)
        tiles = instance.start.tiles
        walks = [walk_for(g, tiles) for g in instance.world.graphs]
        goals = instance.goal_cells
        dists = [w.distances(c) if c >= 0 else np.zeros(w.succ.shape[0], np.int32) for w, c in zip(walks, goals)]
        return cls(instance, walks, goals, dists)

    @classmethod
    def towards(cls, instance: Instance, walks: list[Walk], dists: list[np.ndarray | None],
                starts: tuple[int, ...]) -> "JointProblem":
        """Robots on ``walks`` from ``starts``, robot ``i`` bound for the poses where
        ``dists[i]`` is 0 (None: no goal). The reconfiguration loop plans its steps with this."""
        goals = tuple(-1 if d is None else 0 for d in dists)
        full = [np.zeros(w.succ.shape[0], np.int32) if d is None else d for w, d in zip(walks, dists)]
        homes = [np.ones(w.succ.shape[0], bool) if d is None else d == 0 for w, d in zip(walks, dists)]
        return cls(instance, walks, goals, full, starts, homes)

    @property
    def start(self) -> Poses:
        return tuple(self.instance.start_state.poses) if self.starts is None else tuple(self.starts)

    def unreachable(self) -> list[int]:
        """Robots that cannot reach their goal cell even alone."""
        return [i for i, (d, p) in enumerate(zip(self.dists, self.start)) if d[p] >= UNREACHABLE]

    def at_goal(self, i: int, pose: int) -> bool:
        return self.home_lists[i][pose]

    def is_goal(self, poses: Poses) -> bool:
        return all(home[p] for home, p in zip(self.home_lists, poses))

    def h(self, poses: Poses) -> tuple[int, int]:
        """Admissible, consistent estimate: (sum, max) of the robots' distances to their goals."""
        ds = [d[p] for d, p in zip(self.dist_lists, poses)]
        return sum(ds), max(ds, default=0)

    def step_cost(self, i: int, p: int, q: int, debt: int) -> tuple[int, int]:
        """(cost, new debt) of robot ``i`` moving from pose ``p`` to ``q`` in one step."""
        if self.goals[i] < 0:
            return 0, 0
        home = self.home_lists[i]
        if home[p]:
            return (0, debt + 1) if home[q] else (1 + debt, 0)
        return 1, 0

    def moves(self, i: int, pose: int, only: int | None = None):
        """Robot ``i``'s walking moves from ``pose``: ``(action, next pose, cells)``; with
        ``only`` given, just the move to that pose."""
        options = self.walks[i].moves(pose)
        return options if only is None else [m for m in options if m[1] == only][:1]

    def joint_moves(self, poses: Poses, options: list[list],
                    budget: Budget | None = None) -> Iterator[tuple[tuple[int, ...], Poses]]:
        """Joint actions from per-robot move lists whose collision sets are pairwise disjoint
        (docs/rules.md, rule 3; rules 1, 2 and 4 hold for every walking move on a fixed structure).
        Once ``budget`` expires (looked at every :data:`CHECK_EVERY` joint actions: ten robots
        give millions of them) raises :class:`OutOfTime`."""
        moves = self._classic_moves(poses, options) if self.instance.collisions == "classic" \
            else self._disjoint_moves(options)
        if budget is None:
            yield from moves
            return
        for n, move in enumerate(moves, 1):
            if n % CHECK_EVERY == 0 and budget.expired():
                raise OutOfTime
            yield move

    def _disjoint_moves(self, options: list[list]):
        """Joint actions whose collision sets are pairwise disjoint (the Bill-E rule)."""
        def admit(i, option, used, chosen):
            return used | option[2] if used.isdisjoint(option[2]) else None

        for chosen in backtrack(options, admit, frozenset()):
            yield tuple(a for a, _, _ in chosen), tuple(q for _, q, _ in chosen)

    def _classic_moves(self, poses: Poses, options: list[list]):
        """Joint actions without vertex or swap conflicts (docs/rules.md, "Classic collisions"; point
        robots, whose pose is their cell)."""
        at = {p: k for k, p in enumerate(poses)}

        def admit(i, option, ends, chosen):
            q = option[1]
            k = at.get(q)
            if q in ends or (k is not None and k < i and q != poses[i] and chosen[k][1] == poses[i]):
                return None
            return ends | {q}

        for chosen in backtrack(options, admit, frozenset()):
            yield tuple(a for a, _, _ in chosen), tuple(q for _, q, _ in chosen)

    def transition(self, poses: Poses, debts: Debts, nxt: Poses) -> tuple[int, Debts]:
        """Sum-of-costs increment and new debts of a joint step."""
        total, new = 0, []
        for i, (p, q, d) in enumerate(zip(poses, nxt, debts)):
            cost, debt = self.step_cost(i, p, q, d)
            total += cost
            new.append(debt)
        return total, tuple(new)


NO_WALK = no_schedule("no walking schedule on the fixed structure (a schedule that moves tiles may exist)")


def table_bytes(instance: Instance) -> int:
    """Bytes of the robots' distance tables: per robot and pose an int32, a list entry of an int
    and one of a flag (the inner loops read lists)."""
    return 40 * sum(g.num_poses for g in instance.world.graphs)


def check_tables(instance: Instance, method: str) -> None:
    """Refuse, before allocating, a problem whose per-robot distance tables (a numpy table and
    two plain lists per robot, for the inner loops) would not fit in memory."""
    check_budget(table_bytes(instance), lambda size: f"{method}: {instance.num_robots} robots on a {instance.width}x"
                 f"{instance.height} grid need about {size} of distance tables", OptionError)


def require_path_planning(instance: Instance, method: str = "astar") -> None:
    """The walking planners plan on a structure that does not change."""
    if instance.is_reconfiguration:
        others = "bfs and auto plan it (classic collisions)" if instance.collisions == "classic" else \
            "temporal-astar, mstar and lacam run the reconfiguration loop"
        raise OptionError(f"instance '{instance.name}' moves tiles; {method} plans robot paths on a fixed structure "
                          f"(path-planning instances); {others}")


def _flags(n: int, mask: np.ndarray) -> list[bool]:
    """``mask`` as a list of bools, built from its few set entries (ten times faster than
    ``tolist`` on a large, sparse mask: 500 robots on a 10,000-pose map)."""
    out = [False] * n
    for k in np.flatnonzero(mask).tolist():
        out[k] = True
    return out


def schedule_ids(instance: Instance, steps: list[tuple[int, ...]]) -> np.ndarray:
    """``int[m, L]`` action ids from a list of joint actions."""
    m = instance.num_robots
    if not steps:
        return np.zeros((m, 0), dtype=np.int64)
    return np.array(steps, dtype=np.int64).T.reshape(m, len(steps))


def to_result(instance: Instance, method: str, status: str, steps: list | None, *, stats: dict,
              claim: Claim = EVERY, failure: Failure | None = None):
    """A :class:`~bille.instances.result.Result` from a list of joint actions (or None). The
    planners prove no lower bound: ``solve()`` adds the static one; ``claim``: what an
    ``optimal`` status is optimal for; ``failure``: why there is no schedule."""
    schedule = None
    if steps is not None:
        schedule = Schedule.from_ids(instance, schedule_ids(instance, steps), meta={"method": method})
    return Result(method, status, schedule, stats=stats, claim=claim, failure=failure)


def unwind(parent: dict, key) -> list:
    """The joint actions from the root to ``key`` in a search tree stored as
    ``parent[key] = (parent key, joint action)`` (None at the root)."""
    steps = []
    while parent[key] is not None:
        key, actions = parent[key]
        steps.append(actions)
    return steps[::-1]
