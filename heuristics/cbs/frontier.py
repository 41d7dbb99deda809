"""Which constraint-tree node is expanded next.

- :class:`BestFirst` (optimal search): the open node of least ``f``; ties to fewer conflicts,
  then deeper.
- :class:`Focal` (``w > 1``, the default): among the open nodes of ``g <= w * LB`` (``LB`` the
  least ``f`` of all open nodes, a lower bound on the optimum), the one with the fewest
  conflicts (ECBS's high level, Barer et al. 2014).
- :class:`Explicit` (``w > 1``, ``focal=ees``): explicit estimation search, EECBS's high level (Li, Ruml, Koenig,
  AAAI 2021, after Thayer and Ruml's EES). Three orders over the open nodes: CLEANUP by ``f``
  (admissible: its least is the lower bound ``LB``); OPEN by ``f^ = g + h^``, an estimate of the
  best schedule below the node that need not be admissible; FOCAL, the nodes of OPEN with
  ``f^`` at most ``w`` times OPEN's least, by their number of conflicts. It takes FOCAL's first if
  its ``g <= w * LB``, else OPEN's first if its ``g <= w * LB``, else CLEANUP's first. Every node
  taken from FOCAL or OPEN has ``g <= w * LB``; one taken from CLEANUP has ``f = LB`` and
  ``g <= f``. A conflict-free node taken is a schedule of sum of costs ``g <= w * LB <= w *
  optimum``.

``h^`` is learned online as in EES: after each expansion, the best child (least ``f``) tells how
far ``f`` rose in one step (``e_f = f(child) - f(parent)``) and how far the conflicts fell short of
one fewer (``e_d = d(child) - d(parent) + 1``); with their running means, a node with ``d``
conflicts gets ``h^ = h + d * mean(e_f) / (1 - mean(e_d))`` (``d`` steps still to go, each
costing ``mean(e_f)``, each removing ``1 - mean(e_d)`` conflicts), fixed when it is generated.
"""
from __future__ import annotations

import heapq
import itertools
from typing import Callable


class BestFirst:
    """The open nodes by ``f``; closed or re-valued entries are skipped when met."""

    def __init__(self) -> None:
        self.heap: list = []
        self.counter = itertools.count()

    def push(self, node) -> None:
        heapq.heappush(self.heap, (node.f, len(node.conflicts), -node.depth, next(self.counter), node))

    def lower(self) -> int | None:
        """The least ``f`` of the open nodes, None if there is none."""
        heap = self.heap
        while heap and (heap[0][4].closed or heap[0][0] != heap[0][4].f):
            heapq.heappop(heap)
        return heap[0][0] if heap else None

    def select(self, lower: int):
        return heapq.heappop(self.heap)[4]

    def learn(self, parent, children: list) -> None:
        pass


class Focal:
    """Fewest conflicts among the open nodes of ``g <= w * LB`` (module docstring)."""

    def __init__(self, w: float) -> None:
        self.w = w
        self.cleanup = BestFirst()
        self.waiting: list = []  # (g, n, node): open, not yet in FOCAL
        self.focal: list = []  # (conflicts, f, n, node)
        self.counter = itertools.count()

    def push(self, node) -> None:
        self.cleanup.push(node)
        heapq.heappush(self.waiting, (node.g, next(self.counter), node))

    def lower(self) -> int | None:
        return self.cleanup.lower()

    def select(self, lower: int):
        limit = self.w * lower
        while self.waiting and self.waiting[0][0] <= limit:
            g, n, node = heapq.heappop(self.waiting)
            if not node.closed:
                heapq.heappush(self.focal, (len(node.conflicts), node.f, n, node))
        while self.focal and self.focal[0][3].closed:
            heapq.heappop(self.focal)
        return heapq.heappop(self.focal)[3] if self.focal else self.cleanup.heap[0][4]

    def learn(self, parent, children: list) -> None:
        pass


class Explicit:
    """Explicit estimation search (module docstring). ``settle(node)`` gives a node its own
    estimate ``h`` when it is pushed (False: its subtree is empty and it is dropped): ``f``, the
    lower bound, is then as high as the estimate makes it for every open node."""

    def __init__(self, w: float, settle: Callable) -> None:
        self.w, self.settle = w, settle
        self.cleanup = BestFirst()
        self.open: list = []  # (f^, conflicts, n, node)
        self.waiting: list = []  # (f^, n, node): in OPEN, not yet in FOCAL
        self.focal: list = []  # (conflicts, f^, n, node)
        self.counter = itertools.count()
        self.error_f = self.error_d = 0.0
        self.learned = 0

    def push(self, node) -> None:
        if not node.estimated and not self.settle(node):
            node.closed = True
            return
        d = len(node.conflicts)
        mean_f = self.error_f / self.learned if self.learned else 0.0
        mean_d = self.error_d / self.learned if self.learned else 0.0
        node.fhat = node.f + (d * mean_f / (1 - mean_d) if mean_d < 1 else float("inf") if d else 0.0)
        self.cleanup.push(node)
        n = next(self.counter)
        heapq.heappush(self.open, (node.fhat, d, n, node))
        heapq.heappush(self.waiting, (node.fhat, n, node))

    def lower(self) -> int | None:
        return self.cleanup.lower()

    def select(self, lower: int):
        bound = self.w * lower
        best = _top(self.open, 0, 3)
        limit = self.w * best[0]
        while self.waiting and self.waiting[0][0] <= limit:
            fhat, n, node = heapq.heappop(self.waiting)
            if not node.closed and fhat == node.fhat:
                heapq.heappush(self.focal, (len(node.conflicts), fhat, n, node))
        first = _top(self.focal, 1, 3)
        if first is not None and first[3].g <= bound:
            return first[3]
        if best[3].g <= bound:
            return best[3]
        return self.cleanup.heap[0][4]

    def learn(self, parent, children: list) -> None:
        if not children:
            return
        child = min(children, key=lambda c: (c.f, len(c.conflicts)))
        self.error_f += max(0, child.f - parent.f)
        self.error_d += max(0, len(child.conflicts) - len(parent.conflicts) + 1)
        self.learned += 1


def _top(heap: list, value: int, at: int):
    """The first entry of ``heap`` whose node (``entry[at]``) is open and has the ``f^`` of the
    entry (``entry[value]``), dropping the others."""
    while heap and (heap[0][at].closed or heap[0][value] != heap[0][at].fhat):
        heapq.heappop(heap)
    return heap[0] if heap else None
