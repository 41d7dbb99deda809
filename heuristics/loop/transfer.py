"""Load transfer, step 2 of the reconfiguration loop: equations (1)-(3) of the paper (Methods,
"Load transfer"), the tabu list of transfers that led into a deadlock, and backtracking.

Symbols: ``P_i(x)`` the cost for robot ``i`` to reach and pick at cell ``x``, ``D_i(x)`` to
carry its tile to ``x`` and place it; ``d_tr`` the Manhattan distance within which two robots
consider a transfer. See :meth:`LoadTransfer.decide`.
"""
from __future__ import annotations

from collections import Counter

import numpy as np

from bille.instances import Instance
from bille.instances.moveset import Kind
from bille.instances.walking import UNREACHABLE, walk_for

from .legs import Transfer, nearest
from .loopstate import LoopState

MAX_BACKTRACKS = 20  # undone transfers per run before a deadlock ends it
PASSING = 2  # a blocked leg costs its free distance plus this many steps per cell between the two robots



class LoadTransfer:
    """Chooses the load transfers of a step (:meth:`decide`; the loop applies them with
    :meth:`.LoopState.transfer`) and keeps what backtracking needs: the state before each step
    that made transfers, and the tabu list of transfers that led into a deadlock."""

    def __init__(self, instance: Instance, d_tr: int = 5, stats: dict | None = None) -> None:
        self.world, self.d_tr = instance.world, d_tr
        self.width, self.height = instance.width, instance.height
        self.stats = Counter() if stats is None else stats
        self.tabu: set[tuple] = set()  # transfers that led into a deadlock: never again
        self._checkpoints: list[tuple] = []  # (state, states seen, counts, transfers) before each step with transfers

    # ---- the costs of the paper -------------------------------------------------------------

    def _fronts(self, s: LoopState) -> tuple[np.ndarray, np.ndarray]:
        """Every robot's front foot as ``(x, y)`` arrays."""
        cells = np.array([int(g.feet[p, 0]) for g, p in zip(self.world.graphs, s.poses)], dtype=np.int64)
        return cells % self.width, cells // self.width

    def _manhattan(self, s: LoopState, i: int, j: int) -> int:
        w = self.width
        ci, cj = (int(self.world.graphs[k].feet[s.poses[k], 0]) for k in (i, j))
        return abs(ci % w - cj % w) + abs(ci // w - cj // w)

    def _reach(self, s: LoopState, i: int, carrying: bool, cell: int, pose: int | None = None,
               around: int | None = None) -> tuple[int, int]:
        """``(cost, pose)``: P (or D when ``carrying``) of the paper for robot ``i`` from
        ``pose`` (default: its pose now) to the cell: steps to the nearest pose facing it, plus
        one for the pick or place, walking around robot ``around`` where it stands now; and that
        pose. ``UNREACHABLE`` when there is none."""
        tiles = s.state.tiles
        if around is not None:
            tiles = tiles.copy()
            tiles[list(s.cells_now(around))] = False
        pose = s.poses[i] if pose is None else pose
        found = nearest(walk_for(self.world.graphs[i], tiles, carrying), pose, cell)
        if found[0] >= UNREACHABLE and around is not None:
            # the partner is in the way: it must back off before this robot gets past
            free = nearest(s.walk(i, carrying), pose, cell)
            if free[0] < UNREACHABLE:
                return free[0] + PASSING * self._manhattan(s, i, around), free[1]
        return found

    def transfer_cells(self, s: LoopState, i: int) -> list[int]:
        """Candidate transfer cells for robot ``i``: empty cells that touch the structure, within
        Manhattan distance ``d_tr`` of its front foot, that no pending job or leg names, not
        next to a tile still to be picked (a relay tile hanging on it would hold that pick up),
        and not under any robot."""
        w, h = self.width, self.height
        tiles = s.state.tiles
        fx, fy = self.world.graphs[i].feet_xy(s.poses[i])[0]
        busy = s.pending_cells() | s.occupied()
        picks = s.pending_picks()
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

    # ---- the decision -----------------------------------------------------------------------

    def decide(self, s: LoopState) -> list[Transfer]:
        """The load transfers to make now: every pair of robots within Manhattan distance
        ``d_tr`` is checked.

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
        steps per cell between the two. Robots in the middle of a relay are left alone, and so
        are transfers of the tabu list. When several transfers share a robot, the one that saves
        most is taken (ties: the lower robot ids), then the next that shares none with it, and
        so on. Counts the pairs considered (``pairs_considered``).
        """
        found: list[Transfer] = []
        carrying = s.state.carrying
        x, y = self._fronts(s)
        near = np.abs(x[:, None] - x[None, :]) + np.abs(y[:, None] - y[None, :]) <= self.d_tr
        np.fill_diagonal(near, False)
        for i, j in zip(*(k.tolist() for k in np.nonzero(near))):  # row by row, as i then j
            li, lj = s.legs[i], s.legs[j]
            if not li or not lj or li[0].relay or lj[0].relay:
                continue
            if i < j:
                self.stats["pairs_considered"] += 1
            if carrying[i] and carrying[j] and i < j and len(li) == 1 and len(lj) == 1:
                x1, x2 = li[0].cell, lj[0].cell
                old = self._reach(s, i, True, x1, around=j)[0] + self._reach(s, j, True, x2, around=i)[0]
                new = self._reach(s, i, True, x2, around=j)[0] + self._reach(s, j, True, x1, around=i)[0]
                if new < old:
                    found.append(Transfer("swap", i, j, old - new))
            elif carrying[i] and not carrying[j] and len(li) == 1 and len(lj) == 2 and lj[0].kind == Kind.PICK:
                best = self._relay(s, i, j)
                if best is not None:
                    found.append(best)
        found = [t for t in found if self.key(s, t) not in self.tabu]
        found.sort(key=lambda t: (-t.saving, t.giver, t.taker))
        chosen, used = [], set()
        for t in found:
            if t.giver in used or t.taker in used:
                continue
            chosen.append(t)
            used |= {t.giver, t.taker}
        return chosen

    @staticmethod
    def key(s: LoopState, t: Transfer) -> tuple:
        """A transfer as the jobs it moves: the same exchange of the same loads, at any step."""
        return (t.kind, s.legs[t.giver][0].job, s.legs[t.taker][0].job, t.cell)

    def _relay(self, s: LoopState, i: int, j: int) -> Transfer | None:
        x1, x2 = s.legs[i][0].cell, s.legs[j][0].cell
        old = self._reach(s, i, True, x1, around=j)[0] + self._reach(s, j, False, x2, around=i)[0]
        best = None
        for x3 in self.transfer_cells(s, i):
            d_i_x3, s_i = self._reach(s, i, True, x3, around=j)
            p_j_x3, s_j = self._reach(s, j, False, x3, around=i)
            if d_i_x3 >= UNREACHABLE or p_j_x3 >= UNREACHABLE:
                continue
            p_i_x2 = self._reach(s, i, False, x2, s_i, around=j)[0]
            d_j_x1 = self._reach(s, j, True, x1, s_j, around=i)[0]
            new = d_i_x3 + p_i_x2 + p_j_x3 + d_j_x1
            if new < old and (best is None or (new, d_i_x3, x3) < best[0]):
                best = ((new, d_i_x3, x3), x3)
        if best is None:
            return None
        return Transfer("relay", i, j, min(old, UNREACHABLE) - best[0][0], best[1])

    # ---- backtracking -----------------------------------------------------------------------

    def remember(self, before: LoopState, seen: set, counts: dict, chosen: list[Transfer]) -> None:
        """Keep the state ``before`` a step's transfers ``chosen`` (with the loop states seen and
        the counts to restore), to come back to if they lead into a deadlock."""
        self._checkpoints.append((before.snapshot(), set(seen), dict(counts), {self.key(before, t) for t in chosen}))

    def can_backtrack(self, max_backtracks: int = MAX_BACKTRACKS) -> bool:
        return bool(self._checkpoints) and self.stats["backtracks"] < max_backtracks

    def backtrack(self) -> tuple[LoopState, set, dict]:
        """Undo the latest step that made load transfers, and never make those transfers again:
        ``(the state before it, the loop states seen then, the counts then)``. Called when the
        robots are going round in circles after a transfer: a relay can lead a robot into a crowd
        it cannot get through (the cost comparison of equation 2 knows distances, not
        congestion)."""
        before, seen, counts, chosen = self._checkpoints.pop()
        self.tabu |= chosen
        self.stats["backtracks"] += 1
        return before, seen, counts
