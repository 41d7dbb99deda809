"""Reconfiguration by m robots: task allocation, the execution loop, load transfer (paper, Methods,
"Temporal A*" and "Load transfer").

The loop turns a reconfiguration sequence (:mod:`.sequence`) into a schedule, one time step at a
time. Each robot holds a list of *legs*: ``pick c`` (walk to a pose facing ``c``, pick the tile)
or ``place c`` (carry the tile to a pose facing ``c``, place it). Every step:

1. **Allocation.** The jobs of the sequence are handed out in order. The next job goes to the
   idle robot (no legs, no tile) nearest to its pick by pose-graph distance (walking to a pose
   facing the pick on the current structure; ties to the lower robot id); when no idle robot can
   reach it, allocation waits for the next step. A tile a robot holds at the start is that
   robot's delivery job.
2. **Load transfer** (``load_transfer=True``), equations (1)-(3) of the paper; see
   :meth:`Loop.transfers`.
3. **Goals.** A robot with legs is bound for the poses facing its next leg's cell, if that pick
   or place could happen now (step 4, robots aside); otherwise it has no goal for now, so that it
   gives way instead of holding a pose others need (a relay tile not dropped yet, a pick that
   must wait for another job); an idle robot
   for its goal cell if it has one; an idle robot standing on a tile that a pending job must
   pick for any pose whose feet are off those tiles; any other idle robot is free (it only keeps
   out of the way). Distance tables are cached per structure and goal.
4. **Manipulation.** A robot at a pose facing its leg's cell picks or places now when the
   rules allow it (a tile to pick, an empty cell to place on, no other robot on the cells) and
   the structure stays connected *and the rest of the sequence stays executable in order* from
   the tiles it leaves (so a pick that would disconnect, or that would strand a later place,
   waits until it would not). Robots are considered in the order of the priority queue ``Q``.
5. **Motion.** The other robots move with the motion planner: Temporal A* (the default;
   windows of ``H`` steps in the order of ``Q``, the manipulating robots' cells reserved first,
   a blocked robot moves up in ``Q``) or M* (a joint plan to the current goals, kept while the
   structure, the goals and the poses follow it, so paths are cached until goals change).
6. The joint action goes through the canonical rules (:func:`~bille.instances.rules.apply`).

The run ends when every job is done, no robot carries a tile and every robot with a goal cell
stands on it. It gives up with status ``unsolved`` (reason in ``stats["failure"]``) when no
sequence is found, at the step bound, when the motion planner finds no joint plan, or when the
robots are going round in circles after spending the budget of priority shifts; it stops with
``timeout`` at the time limit. Like Temporal A*, this loop is not complete.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, OptionError
from bille.instances.moveset import Kind
from bille.instances.rules import State, apply

from .joint import JointProblem, to_result
from .sequence import Job, NoSequence, apply_move, sequence_of
from .spacetime import reservation_step
from .temporal_astar import shift_up, timing
from bille.instances.walking import UNREACHABLE, Walk, walk_for

MOTIONS = ("temporal-astar", "mstar")
MSTAR_EXPANSIONS = 100_000  # per M* replan: a joint plan that needs more ends the run
MAX_BACKTRACKS = 20  # undone transfers per run before a deadlock ends it
PASSING = 2  # a blocked leg costs its free distance plus this many steps per cell between the two robots


def _nearest(walk: Walk, pose: int, cell: int) -> tuple[int, int]:
    """Steps from ``pose`` to the nearest pose facing ``cell`` plus one, and that pose."""
    facing = walk.facing_poses(cell)
    if len(facing) == 0 or not walk.standing[pose]:
        return UNREACHABLE, -1
    dist = walk.from_pose(pose)[facing]
    k = int(np.argmin(dist))
    if dist[k] >= UNREACHABLE:
        return UNREACHABLE, -1
    return int(dist[k]) + 1, int(facing[k])


@dataclass(frozen=True)
class Leg:
    """Pick (``kind`` PICK) or place (PLACE) at ``cell``, for job ``job`` of the sequence.
    ``relay`` marks the two legs of a load transfer (the drop at the transfer cell and the
    pick-up from it)."""

    kind: Kind
    cell: int
    job: int
    relay: bool = False


@dataclass(frozen=True)
class Transfer:
    """One load transfer chosen at a step: ``kind`` ``relay`` (equation 2: ``giver`` drops its
    tile at ``cell`` for ``taker``, and takes the taker's pick) or ``swap`` (equation 3: two
    carrying robots exchange drop-off cells); ``saving`` = old cost - new cost."""

    kind: str
    giver: int
    taker: int
    saving: int
    cell: int | None = None


def _facing_feet(world) -> dict[int, list[np.ndarray]]:
    """For each cell, per moveset, the feet ``int[k, 2]`` of the poses that pick or place there."""
    out: dict[int, list[np.ndarray]] = {}
    for graph, _ in world.groups:
        kinds = graph.kind
        manip = [a for a in range(graph.num_actions) if kinds[a] in (Kind.PICK, Kind.PLACE)]
        cells, poses = [], []
        for a in manip:
            p = np.flatnonzero(graph.valid & (graph.target[:, a] >= 0))
            cells.append(graph.target[p, a])
            poses.append(p)
        if not cells:
            continue
        cells, poses = np.concatenate(cells), np.concatenate(poses)
        order = np.argsort(cells, kind="stable")
        cells, poses = cells[order], poses[order]
        bounds = np.flatnonzero(np.diff(cells)) + 1
        for c, group in zip(cells[np.r_[0, bounds]], np.split(poses, bounds)):
            out.setdefault(int(c), []).append(graph.feet[np.unique(group)])
    return out


def plan(instance: Instance, *, motion: str = "temporal-astar", load_transfer: bool = False, d_tr: int = 5,
         epsilon: float = 1.0, horizon: int = 5, time_limit: float | None = None, max_steps: int | None = None,
         max_shifts: int | None = None, priorities: list[int] | None = None, method: str | None = None):
    """Run the reconfiguration loop (module docstring); returns a
    :class:`~bille.instances.result.Result` named ``method`` (default: ``motion``).

    ``motion``: ``temporal-astar`` or ``mstar``; ``load_transfer`` and ``d_tr``: equations
    (1)-(3); ``epsilon``, ``horizon``, ``priorities`` (the initial ``Q``): as for Temporal A*;
    ``max_steps``: the step bound (default: ten times the summed Manhattan carries plus ``W + H``
    per job, at least 200); ``max_shifts``: priority shifts allowed when going round in circles
    (default ``4 m^2 + 4 jobs``).
    """
    try:
        loop = Loop(instance, motion=motion, load_transfer=load_transfer, d_tr=d_tr, epsilon=epsilon,
                    horizon=horizon, time_limit=time_limit, max_steps=max_steps, max_shifts=max_shifts,
                    priorities=priorities)
    except NoSequence as exc:  # the loop gives up before its first step
        return to_result(instance, method or motion, "unsolved", None, stats={"failure": str(exc)})
    return loop.run(method or motion)


class Loop:
    """The state of one run; :meth:`run` drives it. Tests drive the parts (:meth:`transfers`)."""

    def __init__(self, instance: Instance, *, motion: str = "temporal-astar", load_transfer: bool = False,
                 d_tr: int = 5, epsilon: float = 1.0, horizon: int = 5, time_limit: float | None = None,
                 max_steps: int | None = None, max_shifts: int | None = None,
                 priorities: list[int] | None = None) -> None:
        m = instance.num_robots
        if motion not in MOTIONS:
            raise OptionError(f"unknown motion planner '{motion}' (expected one of: {', '.join(MOTIONS)})")
        if epsilon < 1:
            raise OptionError(f"{motion}: epsilon must be >= 1, got {epsilon}")
        if horizon < 1:
            raise OptionError(f"{motion}: the horizon H must be >= 1, got {horizon}")
        if d_tr < 0:
            raise OptionError(f"{motion}: d_tr must be >= 0, got {d_tr}")
        self.Q = list(range(m)) if priorities is None else list(priorities)
        if sorted(self.Q) != list(range(m)):
            raise OptionError(f"{motion}: priorities must order the robot ids 0..{m - 1}, got {priorities}")
        if m == 0:
            raise OptionError(f"instance '{instance.name}' has no robots to move its tiles")
        self.instance, self.world = instance, instance.world
        self.motion, self.load_transfer, self.d_tr = motion, load_transfer, d_tr
        self.epsilon, self.horizon = epsilon, horizon
        self.start_time = time.perf_counter()
        self.deadline = None if time_limit is None else self.start_time + time_limit
        self.jobs: list[Job] = sequence_of(instance)
        self.state: State = instance.start_state
        self.legs: list[list[Leg]] = [[] for _ in range(m)]
        self.next_job = 0
        for k, job in enumerate(self.jobs):
            if job.pick is None:  # a delivery: the carrier's job from the start
                self.legs[job.carrier] = [Leg(Kind.PLACE, job.place, k)]
                self.next_job = k + 1
        w, h = instance.width, instance.height
        carries = sum(abs(j.place % w - j.pick % w) + abs(j.place // w - j.pick // w)
                      for j in self.jobs if j.pick is not None)
        # default step bound: ten times the carries plus a crossing of the grid per job
        self.max_steps = max(200, 10 * (carries + len(self.jobs) * (w + h))) if max_steps is None else max_steps
        self.max_shifts = 4 * m * m + 4 * len(self.jobs) if max_shifts is None else max_shifts
        self.goal_cells = instance.goal_cells
        self.steps: list[tuple[int, ...]] = []
        self.stats: dict = {"motion": motion, "load_transfer": load_transfer, "d_tr": d_tr, "horizon": horizon,
                            "epsilon": epsilon, "jobs": len(self.jobs), "steps": 0, "relays": 0, "swaps": 0,
                            "pairs_considered": 0, "deferred_manipulations": 0, "priority_shifts": 0,
                            "circle_shifts": 0, "cautious_steps": 0, "replans": 0, "expanded": 0, "backtracks": 0,
                            "plan_ms_mean": 0.0, "plan_ms_max": 0.0}
        self._lists: dict = {}
        self._ready_key, self._ready = None, set()
        self._facing_feet = _facing_feet(self.world)
        # check facing poses of the sequence's picks and places only if the sequence has them
        # in order (derived sequences do; a given task list may not)
        self._stands = True
        self._stands = self._executable(self.state.tiles, self._pending_ops())
        self.tabu: set[tuple] = set()  # transfers that led into a deadlock: never again
        self._checkpoints: list[tuple] = []  # the loop's state before each step with transfers
        self._joint: list | None = None  # the cached M* plan: remaining joint actions
        self._joint_key = None  # the state, goals and manipulations the cached plan expects next

    # ---- the world as the robots see it -----------------------------------------------------

    def walk(self, i: int, carrying: bool | None = None) -> Walk:
        """Robot ``i``'s walking graph on the current tiles (carrying as now, unless given)."""
        carrying = self.state.carrying[i] if carrying is None else carrying
        return walk_for(self.world.graphs[i], self.state.tiles, carrying)

    def _pending_picks(self) -> set[int]:
        cells = {leg.cell for legs in self.legs for leg in legs if leg.kind == Kind.PICK}
        return cells | {j.pick for j in self.jobs[self.next_job:] if j.pick is not None}

    def _pending_cells(self) -> set[int]:
        cells = {leg.cell for legs in self.legs for leg in legs}
        return cells | {c for j in self.jobs[self.next_job:] for c in (j.pick, j.place) if c is not None}

    # ---- 1. allocation ----------------------------------------------------------------------

    def allocate(self) -> None:
        """Hand out the next jobs in order to the nearest idle robots (module docstring)."""
        poses = self.state.poses
        while self.next_job < len(self.jobs):
            job = self.jobs[self.next_job]
            idle = [i for i in range(len(poses)) if not self.legs[i] and not self.state.carrying[i]]
            best = None
            for i in idle:
                d = int(self.walk(i).facing_distances(job.pick)[poses[i]])
                if d < UNREACHABLE and (best is None or d < best[0]):
                    best = (d, i)
            if best is None:
                return
            self.legs[best[1]] = [Leg(Kind.PICK, job.pick, self.next_job), Leg(Kind.PLACE, job.place, self.next_job)]
            self.next_job += 1

    # ---- 2. load transfer -------------------------------------------------------------------

    def _manhattan(self, i: int, j: int) -> int:
        (xi, yi), (xj, yj) = (self.world.graphs[k].feet_xy(self.state.poses[k])[0] for k in (i, j))
        return abs(xi - xj) + abs(yi - yj)

    def _reach(self, i: int, carrying: bool, cell: int, pose: int | None = None,
               around: int | None = None) -> tuple[int, int]:
        """``(cost, pose)``: P (or D when ``carrying``) of the paper for robot ``i`` from
        ``pose`` (default: its pose now) to the cell: steps to the nearest pose facing it, plus
        one for the pick or place, walking around robot ``around`` where it stands now; and that
        pose. ``UNREACHABLE`` when there is none."""
        tiles = self.state.tiles
        if around is not None:
            tiles = tiles.copy()
            tiles[list(self._cells_now(around))] = False
        pose = self.state.poses[i] if pose is None else pose
        found = _nearest(walk_for(self.world.graphs[i], tiles, carrying), pose, cell)
        if found[0] >= UNREACHABLE and around is not None:
            # the partner is in the way: it must back off before this robot gets past
            free = _nearest(self.walk(i, carrying), pose, cell)
            if free[0] < UNREACHABLE:
                return free[0] + PASSING * self._manhattan(i, around), free[1]
        return found

    def transfer_cells(self, i: int) -> list[int]:
        """Candidate transfer cells for robot ``i``: empty cells that touch the structure, within
        Manhattan distance ``d_tr`` of its front foot, that no pending job or leg names, not
        next to a tile still to be picked (a relay tile hanging on it would hold that pick up),
        and not under any robot."""
        w, h = self.instance.width, self.instance.height
        tiles = self.state.tiles
        fx, fy = self.world.graphs[i].feet_xy(self.state.poses[i])[0]
        busy = self._pending_cells() | self._occupied_cells()
        picks = self._pending_picks()
        free = ~tiles & ~self.world.obstacles
        out = []
        for y in range(max(0, fy - self.d_tr), min(h, fy + self.d_tr + 1)):
            for x in range(max(0, fx - self.d_tr), min(w, fx + self.d_tr + 1)):
                c = y * w + x
                if abs(x - fx) + abs(y - fy) > self.d_tr or not free[c] or c in busy:
                    continue
                around = [(y + dy) * w + x + dx for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1))
                          if 0 <= x + dx < w and 0 <= y + dy < h]
                if any(tiles[n] for n in around) and picks.isdisjoint(around):
                    out.append(c)
        return out

    def transfers(self) -> list[Transfer]:
        """Check every pair of robots within Manhattan distance ``d_tr`` for a load transfer.

        - **Relay** (equations 1 and 2): robot ``i`` carries a tile to ``x1`` (its only leg),
          robot ``j`` is on its way to pick ``x2`` (then place it at ``a2``). With ``C = D_i(x1)
          + P_j(x2)`` and, for a transfer cell ``x3`` (:meth:`transfer_cells`), ``i`` placing at
          ``x3`` from pose ``s_i`` and ``j`` picking from ``s_j``: if ``D_i(x3) + P_i(s_i ->
          x2) + P_j(x3) + D_j(s_j -> x1) < C`` for the best ``x3``, then ``i`` drops its tile at
          ``x3`` and goes on with ``j``'s job (pick ``x2``, place ``a2``), and ``j`` picks the
          tile at ``x3`` and takes it to ``x1``.
        - **Swap** (equation 3): ``i`` and ``j`` both carry, to ``x1`` and ``x2``; if ``D_i(x2)
          + D_j(x1) < D_i(x1) + D_j(x2)`` they exchange drop-off cells.

        P and D are walking steps on the current structure to the nearest pose facing the cell
        plus one step for the pick or place (so a relay must save more than the two extra
        actions it costs), walking around the other robot of the pair where it stands now: the
        two cannot pass through each other, which is what makes a transfer pay on a one-tile-wide
        segment (without it, a relay in a straight corridor never lowers the summed distance). A
        leg that cannot get around the other robot costs its free distance plus ``PASSING``
        steps per cell between the two. Robots in the middle of a relay are left alone. When
        several transfers share a robot, the one that saves most is taken (ties: the lower robot
        ids), then the next that shares none with it, and so on.
        """
        m = len(self.legs)
        found: list[Transfer] = []
        carrying = self.state.carrying
        for i in range(m):
            for j in range(m):
                if i == j or self._manhattan(i, j) > self.d_tr:
                    continue
                li, lj = self.legs[i], self.legs[j]
                if not li or not lj or li[0].relay or lj[0].relay:
                    continue
                if i < j:
                    self.stats["pairs_considered"] += 1
                if carrying[i] and carrying[j] and i < j and len(li) == 1 and len(lj) == 1:
                    x1, x2 = li[0].cell, lj[0].cell
                    old = self._reach(i, True, x1, around=j)[0] + self._reach(j, True, x2, around=i)[0]
                    new = self._reach(i, True, x2, around=j)[0] + self._reach(j, True, x1, around=i)[0]
                    if new < old:
                        found.append(Transfer("swap", i, j, old - new))
                elif carrying[i] and not carrying[j] and len(li) == 1 and len(lj) == 2 and lj[0].kind == Kind.PICK:
                    best = self._relay(i, j)
                    if best is not None:
                        found.append(best)
        found = [t for t in found if self._tabu_key(t) not in self.tabu]
        found.sort(key=lambda t: (-t.saving, t.giver, t.taker))
        chosen, used = [], set()
        for t in found:
            if t.giver in used or t.taker in used:
                continue
            chosen.append(t)
            used |= {t.giver, t.taker}
        self.chosen_keys = {self._tabu_key(t) for t in chosen}
        for t in chosen:
            self._apply_transfer(t)
        return chosen

    def _tabu_key(self, t: Transfer) -> tuple:
        """A transfer as the jobs it moves: the same exchange of the same loads, at any step."""
        return (t.kind, self.legs[t.giver][0].job, self.legs[t.taker][0].job, t.cell)

    def _relay(self, i: int, j: int) -> Transfer | None:
        x1, x2 = self.legs[i][0].cell, self.legs[j][0].cell
        old = self._reach(i, True, x1, around=j)[0] + self._reach(j, False, x2, around=i)[0]
        best = None
        for x3 in self.transfer_cells(i):
            d_i_x3, s_i = self._reach(i, True, x3, around=j)
            p_j_x3, s_j = self._reach(j, False, x3, around=i)
            if d_i_x3 >= UNREACHABLE or p_j_x3 >= UNREACHABLE:
                continue
            p_i_x2 = self._reach(i, False, x2, s_i, around=j)[0]
            d_j_x1 = self._reach(j, True, x1, s_j, around=i)[0]
            new = d_i_x3 + p_i_x2 + p_j_x3 + d_j_x1
            if new < old and (best is None or (new, d_i_x3, x3) < best[0]):
                best = ((new, d_i_x3, x3), x3)
        if best is None:
            return None
        return Transfer("relay", i, j, min(old, UNREACHABLE) - best[0][0], best[1])

    def _apply_transfer(self, t: Transfer) -> None:
        i, j = t.giver, t.taker
        if t.kind == "swap":
            self.legs[i][0], self.legs[j][0] = self.legs[j][0], self.legs[i][0]
            self.stats["swaps"] += 1
            return
        carried = self.legs[i][0]  # place x1 of job k1
        self.legs[i] = [Leg(Kind.PLACE, t.cell, carried.job, relay=True)] + self.legs[j]
        self.legs[j] = [Leg(Kind.PICK, t.cell, carried.job, relay=True), carried]
        self.stats["relays"] += 1

    # ---- 3. goals ---------------------------------------------------------------------------

    def goal(self, i: int) -> np.ndarray | None:
        """Robot ``i``'s distance table to its current goal poses, or None (free)."""
        walk = self.walk(i)
        if self.legs[i]:
            if i not in self.ready():
                return None  # its pick or place cannot happen yet: give way meanwhile
            return walk.facing_distances(self.legs[i][0].cell)
        if self.goal_cells[i] >= 0:
            return walk.distances(self.goal_cells[i])
        needed = self._pending_picks()
        feet = self.world.graphs[i].feet
        if needed.intersection(feet[self.state.poses[i]].tolist()):  # off the tiles still to be picked
            def clear():
                return np.flatnonzero(walk.standing & ~np.isin(feet, list(needed)).any(axis=1))

            return walk.distances_to(("clear", frozenset(needed)), clear)
        return None

    def _as_lists(self, dist: np.ndarray | None):
        if dist is None:
            return None, None
        key = id(dist)
        got = self._lists.get(key)
        if got is None or got[0] is not dist:
            got = (dist, dist.tolist(), (dist == 0).tolist())
            self._lists[key] = got
            if len(self._lists) > 512:
                self._lists.pop(next(iter(self._lists)))
        return got[1], got[2]

    # ---- 4. manipulation --------------------------------------------------------------------

    def _cells_now(self, j: int) -> frozenset:
        """Robot ``j``'s feet and the tile it carries: cells every action of it touches."""
        return self.walk(j).cells(self.state.poses[j], self.world.graphs[j].wait)

    def _occupied_cells(self, but: int | None = None) -> set[int]:
        """Cells every action of the robots (except ``but``) touches this step."""
        out: set[int] = set()
        for j in range(len(self.legs)):
            if j != but:
                out |= self._cells_now(j)
        return out

    def _pending_ops(self) -> list[tuple[tuple, Kind, int, object]]:
        """Every pick and place still to do, in the order the sequence runs them: a relay's drop
        and pick-up first (the tile is borrowed), then by job, pick before place."""
        ops = []
        for i, legs in enumerate(self.legs):
            for leg in legs:
                if leg.relay:
                    key = (-2 if leg.kind == Kind.PLACE else -1, leg.job)
                else:
                    key = (leg.job, 0 if leg.kind == Kind.PICK else 1)
                ops.append((key, leg.kind, leg.cell, (i, leg)))
        for k in range(self.next_job, len(self.jobs)):
            job = self.jobs[k]
            if job.pick is not None:
                ops.append(((k, 0), Kind.PICK, job.pick, None))
            ops.append(((k, 1), Kind.PLACE, job.place, None))
        ops.sort(key=lambda o: o[0])
        return ops

    def _executable(self, tiles: np.ndarray, ops) -> bool:
        """Whether ``ops`` run in order from ``tiles``, each keeping the structure connected and,
        when the sequence allows it, with a pose facing its cell that stands on the tiles of that
        moment (an early pick must not take away the tile a later place needs to stand on)."""
        w, h = self.instance.width, self.instance.height
        tiles = tiles.copy()
        for _, kind, cell, _ in ops:
            if self._stands and not self._can_face(tiles, cell):
                return False
            if apply_move(tiles, kind == Kind.PICK, cell, w, h) is not None:
                return False
        return True

    def _can_face(self, tiles: np.ndarray, cell: int) -> bool:
        """Whether some robot could stand on ``tiles`` facing ``cell`` to pick or place there."""
        return any(bool(tiles[feet].all(axis=1).any()) for feet in self._facing_feet.get(cell, ()))

    def ready(self) -> set[int]:
        """Robots whose next pick or place could happen now as far as the tiles go: the cell
        holds a tile (pick) or not (place), and the structure and the rest of the sequence stay
        valid after it. Cached per tiles and legs."""
        key = (self.state.tiles.tobytes(), tuple(map(tuple, self.legs)), self.next_job)
        if self._ready_key != key:
            ops = self._pending_ops()
            out = set()
            for i, legs in enumerate(self.legs):
                rest = [op for op in ops if op[3] != (i, legs[0])] if legs else []
                if legs and self._allowed(self.state.tiles, legs[0], rest) is not None:
                    out.add(i)
            self._ready_key, self._ready = key, out
        return self._ready

    def _allowed(self, tiles: np.ndarray, leg: Leg, rest) -> np.ndarray | None:
        """The tiles after ``leg`` if it may happen on ``tiles`` with ``rest`` still to run."""
        trial = tiles.copy()
        if apply_move(trial, leg.kind == Kind.PICK, leg.cell, self.instance.width, self.instance.height):
            return None
        return trial if self._executable(trial, rest) else None

    def manipulations(self) -> tuple[dict[int, int], dict[int, frozenset]]:
        """The picks and places that happen this step, ``{robot: action}``, and the *intents*:
        ``{robot: cells}`` of robots that face their leg's cell and would manipulate now but for
        another robot on the cells (module docstring)."""
        tiles = self.state.tiles.copy()
        ops = self._pending_ops()
        taken: set[int] = set()
        out: dict[int, int] = {}
        intents: dict[int, frozenset] = {}
        for i in self.Q:
            if not self.legs[i]:
                continue
            leg, pose = self.legs[i][0], self.state.poses[i]
            walk = self.walk(i)
            action = walk.manipulation(pose, leg.cell, leg.kind)
            if action is None or self.state.carrying[i] != (leg.kind == Kind.PLACE):
                continue
            cells = walk.cells(pose, action)
            if not cells.isdisjoint(taken):
                continue
            rest = [op for op in ops if op[3] != (i, leg)]
            trial = self._allowed(tiles, leg, rest)
            if trial is None:
                self.stats["deferred_manipulations"] += 1
                continue
            if not cells.isdisjoint(self._occupied_cells(but=i)):
                intents[i] = cells
                continue
            tiles, ops = trial, rest
            out[i] = action
            taken |= cells
        return out, intents

    # ---- 5. motion --------------------------------------------------------------------------

    def _temporal(self, fixed: dict[int, int], goals: list, intents: dict[int, frozenset],
                  cautious: bool = False) -> tuple[list[int] | None, int | None]:
        """Temporal A* windows for the robots not in ``fixed``: ``(joint action, None)`` or
        ``(None, blocked robot)``. The manipulating robots' cells are reserved for the whole
        window; a robot with an intent waits, and the cells of its manipulation are reserved
        from the second step on, so that the robot standing there must leave. ``cautious``: a
        robot keeps off the lower-priority robots' cells for the whole window, not only the
        first step (with no intents, then no robot is ever blocked: waiting is always left)."""
        H, poses = self.horizon, self.state.poses
        reserved: list[set[int]] = [set() for _ in range(H + 1)]
        joint = [0] * len(poses)
        for i, a in fixed.items():
            cells = self.walk(i).cells(poses[i], a)
            for t in range(1, H + 1):
                reserved[t] |= cells
            joint[i] = a
        for i, cells in intents.items():
            here = self._cells_now(i)
            reserved[1] |= here
            for t in range(2, H + 1):
                reserved[t] |= here | cells
            joint[i] = self.world.graphs[i].wait
        order = [i for i in self.Q if i not in fixed and i not in intents]
        walks = {i: self.walk(i) for i in order}
        targets = {i: self._as_lists(goals[i]) for i in order}
        first, blocked = reservation_step(order, walks, targets, poses, H, reserved, self._cells_now,
                                          self.epsilon, self.stats, cautious)
        if first is None:
            return None, blocked
        for i, a in first.items():
            joint[i] = a
        return joint, None

    def _mstar(self, fixed: dict[int, int], goals: list) -> list[int] | None:
        """The next joint action of the cached M* plan (planned again when the structure, the
        goals or the poses left it); manipulations replace waits where they fit."""
        from .mstar import joint_plan

        poses = self.state.poses
        key = (self.state.key(), tuple(id(g) for g in goals), tuple(fixed))
        if self._joint_key != key or not self._joint:
            walks = [self.walk(i) for i in range(len(poses))]
            dists = [g if i not in fixed else walks[i].distances_to(("pose", poses[i]), lambda p=poses[i]: [p])
                     for i, g in enumerate(goals)]
            # a goal out of reach for now (the structure is changing) does not hold the others up
            dists = [None if d is not None and d[p] >= UNREACHABLE else d for d, p in zip(dists, poses)]
            problem = JointProblem.towards(self.instance, walks, dists, poses)
            left = None if self.deadline is None else max(0.1, self.deadline - time.perf_counter())
            status, steps, stats = joint_plan(problem, epsilon=self.epsilon, time_limit=left,
                                              max_expansions=MSTAR_EXPANSIONS)
            self.stats["replans"] += 1
            self.stats["expanded"] += stats["expanded"]
            if steps is None:
                self.stats["mstar_status"] = status
                return None
            self._joint = list(steps) or [tuple(walks[i].wait for i in range(len(poses)))]
        joint = list(self._joint.pop(0))
        used: set[int] = set()
        for i, a in enumerate(joint):
            if i not in fixed:
                used |= self.walk(i).cells(poses[i], a)
        for i, a in fixed.items():
            cells = self.walk(i).cells(poses[i], a)
            if joint[i] == self.world.graphs[i].wait and cells.isdisjoint(used):
                joint[i] = a
            used |= self.walk(i).cells(poses[i], joint[i])
        return joint

    # ---- the loop ---------------------------------------------------------------------------

    def done(self) -> bool:
        if self.next_job < len(self.jobs) or any(self.legs) or any(self.state.carrying):
            return False
        if not np.array_equal(self.state.tiles, self.instance.goal_tiles):
            return False
        return all(c < 0 or self.world.graphs[i].feet[p, 0] == c
                   for i, (c, p) in enumerate(zip(self.goal_cells, self.state.poses)))

    def _snapshot(self) -> tuple:
        """The loop's state before a step's transfers (the states seen are added if any are made)."""
        return (self.state, [list(legs) for legs in self.legs], self.next_job, len(self.steps), list(self.Q),
                {k: self.stats[k] for k in ("circle_shifts", "relays", "swaps")})

    def _backtrack(self) -> set:
        """Undo the latest step that made load transfers, and never make those transfers again.

        Returns the set of loop states seen before it. Called when the robots are going round
        in circles after a transfer: a relay can lead a robot into a crowd it cannot get through
        (the cost comparison of equation 2 knows distances, not congestion).
        """
        snap, seen, chosen = self._checkpoints.pop()
        state, legs, next_job, n_steps, Q, counts = snap
        self.tabu |= chosen
        self.state, self.legs, self.next_job, self.Q = state, legs, next_job, Q
        del self.steps[n_steps:]
        self.stats.update(counts)
        self.stats["backtracks"] += 1
        self._ready_key, self._joint, self._joint_key = None, None, None
        return seen

    def run(self, method: str):
        seen: set = set()
        step_times: list[float] = []

        def stop(reason: str, status: str = "unsolved"):
            self.stats["failure"] = reason
            timing(self.stats, step_times)
            return to_result(self.instance, method, status, None, stats=self.stats)

        while not self.done():
            if len(self.steps) >= self.max_steps:
                return stop("step bound")
            if self.deadline is not None and time.perf_counter() > self.deadline:
                return stop("time limit", status="timeout")
            t0 = time.perf_counter()
            self.allocate()
            if self.load_transfer:
                snap = self._snapshot()
                if self.transfers():
                    self._checkpoints.append((snap, set(seen), self.chosen_keys))
            key = (self.state.key(), tuple(map(tuple, self.legs)), self.next_job, tuple(self.Q))
            if key in seen:  # going round in circles
                if self.stats["circle_shifts"] >= self.max_shifts:
                    if self._checkpoints and self.stats["backtracks"] < MAX_BACKTRACKS:
                        seen = self._backtrack()
                        continue
                    return stop("deadlock")
                busy = [i for i in self.Q if self.legs[i] or self.goal(i) is not None] or list(self.Q)
                shift_up(self.Q, busy[-1])
                self.stats["priority_shifts"] += 1
                self.stats["circle_shifts"] += 1
                continue
            seen.add(key)
            fixed, intents = self.manipulations()
            goals = [self.goal(i) for i in range(len(self.legs))]
            if self.motion == "mstar":
                joint = self._mstar(fixed, goals)
                if joint is None:
                    why = self.stats.get("mstar_status")
                    return stop(f"M* found no joint plan ({why})", status="timeout" if why == "timeout" else "unsolved")
            else:
                joint, blocked = self._temporal(fixed, goals, intents)
                for _ in range(len(self.Q)):  # a blocked robot moves up in Q (the paper's rule)
                    if blocked is None:
                        break
                    shift_up(self.Q, blocked)
                    self.stats["priority_shifts"] += 1
                    self.stats["replans"] += 1
                    joint, blocked = self._temporal(fixed, goals, intents)
                if blocked is not None:  # still blocked: every robot keeps off the lower ones
                    self.stats["cautious_steps"] += 1
                    joint, blocked = self._temporal(fixed, goals, intents, cautious=True)
                    if blocked is not None:  # the intents cannot be made room for now
                        joint, _ = self._temporal(fixed, goals, {}, cautious=True)
            step_times.append(time.perf_counter() - t0)
            nxt = apply(self.world, self.state, joint, step=len(self.steps) + 1)
            if not isinstance(nxt, State):  # the planners respect the rules; this is a bug
                return stop(f"internal: {nxt}", status="error")
            for i, a in fixed.items():
                if joint[i] == a:
                    self.legs[i].pop(0)
            self.steps.append(tuple(joint))
            self.state = nxt
            if self.motion == "mstar" and not fixed:  # the cached plan holds while it is followed
                self._joint_key = (nxt.key(), tuple(id(g) for g in goals), ())
            self.stats["steps"] = len(self.steps)
        timing(self.stats, step_times)
        self.stats["final_priorities"] = list(self.Q)
        return to_result(self.instance, method, "feasible", self.steps, stats=self.stats)



__all__ = ["Leg", "Loop", "MOTIONS", "Transfer", "plan"]
