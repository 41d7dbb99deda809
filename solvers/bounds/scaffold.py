"""A lower bound on the makespan that prices scaffold: the routing bound per scaffold scenario
(a part of :mod:`.static`, "scaffold scenarios (LP)").

The routing bound (:mod:`.routing`) lets robots walk anywhere, over empty cells too: a schedule
can only do so on tiles it set down there first (rule 4), and each such tile costs a place (and a
pick to take it away again, which the program's tile balance already asks). On maps whose
platforms are joined by thin bridges, which cells may ever hold such a tile decides how much a
schedule can shortcut; this part splits every schedule by that, and takes the least bound.

**Setting.** ``A`` is the set of cells with a tile at the start or in the goal. A *corridor line*
is a column holding one or two start tiles (and, separately, a row: see below). A schedule's
*scenario* ``Z`` is the set of corridor columns in which some cell outside ``A`` holds a tile after
some step. Its *ground* is ``A``, every cell of the columns that are not corridor columns, and every
cell of the columns of ``Z``.

**Theorem.** Let a valid schedule have scenario ``Z``. (i) At every step, every tile lies on its
ground: a tile outside ``A`` in a corridor column puts that column in ``Z``. So (rule 4) every pose
of the schedule has its feet on the ground, and every pick and place targets it (a pick's target
holds a tile before it, a place's after). (ii) For every column ``j`` of ``Z`` some place targets a
cell of column ``j`` outside ``A``: such a cell holds no tile at the start, so its tile was placed
there. Hence the schedule's carries and walks are a solution of the routing program on that
ground (:class:`.ground.Ground`; the routing proof holds for the schedules that keep to the
ground given) with, for each ``j`` of ``Z``, the row "places on the cells of column ``j`` outside
``A`` >= 1": the program's value bounds the schedule's makespan.

**Families.** For corridor columns ``Z_in`` (in the scenario) and ``U`` (not decided), every scenario
``Z`` with ``Z_in <= Z <= Z_in | U`` has a ground inside the ground of ``Z_in | U`` and the rows of
``Z_in`` among its own, so the program on the ground of ``Z_in | U`` with the rows of ``Z_in`` is a
relaxation of each of theirs: its value is a lower bound for every schedule whose scenario is in
the family. The search splits the family of least value on its next undecided column (in, out)
until that family is one scenario: a family's value is at least its parent's (its scenarios are
among the parent's), the families not split cover every scenario, so at any moment the least
value among them is a lower bound on every schedule; when the budget runs out, that is the part.
A family whose program is not solved (no time left, too many cells, or an infeasible program,
which is not used as a proof here) keeps its parent's value.

Rows instead of columns give a bound by the same proof (for maps whose bridges run north-south);
the part is the larger of the two. On the paper's maps the least family is the one with scaffold
in every corridor column, and the rows of its places raise the routing bound by one to three
(docs/anytime.md). Checked against the brute-force search on tiny instances, through the bounds'
soundness tests, and on tiny bridge maps (tests/test_classes.py).
"""
from __future__ import annotations

import heapq

import numpy as np

from bille.instances import Instance
from bille.instances.run import Budget

from .ground import Ground
from .routing import routing_bound

SECONDS = 10.0  # at most, of the static bound's time: 2-8 s on lt-1..lt-5 (lt-8 needs 18 s)


def scaffold_search(instance: Instance, budget: Budget | None = None, floor: int = 0) -> Scenarios:
    """The search of the module docstring (columns and rows), as it stands when ``budget`` (at
    most :data:`SECONDS`) ran out: its ``value`` is the part, the larger of the two kinds of line,
    and :meth:`Scenarios.advance` takes it further. The value is None where no line is a
    corridor line, no program is solved, or it cannot exceed ``floor`` (the other parts' best):
    the scenario with scaffold in every corridor line, whose value the part never exceeds, is
    tried first."""
    budget = (budget or Budget()).child(SECONDS)
    search = Scenarios([_Lines(instance, line, corridor) for line, corridor in corridor_lines(instance)])
    for lines in search.lines:
        lines.begin(budget, floor)
    search.advance(budget)
    return search


class Scenarios:
    """The best-first search of the module docstring over the families of scenarios, one per kind
    of line (columns, rows), resumable: ``value`` is the larger of their bounds so far (None
    where neither has one), ``finished`` whether more time can raise it no further.

    :meth:`advance` with ``split`` also solves the per-robot integer program of
    :mod:`.routing` (its last section) for a single scenario once it has the least value: that
    program's bound is a bound for the schedules of that scenario too, and the scenario goes back
    among the families with it (the program is solved once per scenario, whether in time or
    not)."""

    def __init__(self, lines: list[_Lines]) -> None:
        self.lines = lines

    @property
    def value(self) -> int | None:
        found = [lines.value for lines in self.lines if lines.value is not None]
        return max(found) if found else None

    @property
    def finished(self) -> bool:
        return all(lines.finished for lines in self.lines)

    def advance(self, budget: Budget, split: bool = False, on_value=None) -> int | None:
        """Search on until ``budget`` expires or nothing is left to do; the value then.
        ``on_value`` hears of every rise of the value, as it happens."""
        held = [self.value]

        def changed() -> None:
            if on_value is not None and self.value is not None and (held[0] is None or self.value > held[0]):
                held[0] = self.value
                on_value(self.value)

        for lines in self.lines:
            lines.advance(budget, split, changed)
        return self.value


class _Lines:
    """The search over the scenarios of one kind of line (:class:`Scenarios`)."""

    def __init__(self, instance: Instance, line: np.ndarray, corridor: tuple) -> None:
        self.instance, self.line, self.corridor = instance, line, corridor
        self.heap: list = []  # (value, lines in, lines undecided, split): the families not split
        self.finished = False

    @property
    def value(self) -> int | None:
        return self.heap[0][0] if self.heap else None

    def _value(self, budget: Budget, inside: tuple, allowed: tuple, split: bool = False) -> int | None:
        if budget.expired():
            return None
        return scenario_value(self.instance, self.line, self.corridor, inside, allowed, budget, split)

    def begin(self, budget: Budget, floor: int) -> None:
        """The root family, unless the scenario with every line cannot exceed ``floor``."""
        every = self._value(budget, self.corridor, self.corridor)
        root = None if every is None or every <= floor else self._value(budget, (), self.corridor)
        if root is None:
            self.finished = True
        else:
            self.heap = [(root, (), self.corridor, False)]

    def advance(self, budget: Budget, split: bool, changed=lambda: None) -> None:
        heap = self.heap
        while heap and not self.finished and not budget.expired():
            lower, inside, undecided, done = heap[0]
            if not undecided:  # a single scenario has the least value
                if done:
                    self.finished = True  # nothing lower can be proved
                    break
                if not split:
                    break
                got = self._value(budget, inside, inside, split=True)
                heapq.heapreplace(heap, (lower if got is None else max(lower, got), inside, (), True))
                changed()
                continue
            heapq.heappop(heap)
            j, rest = undecided[0], undecided[1:]
            for child in (inside + (j,), inside):
                got = self._value(budget, child, child + rest)
                heapq.heappush(heap, (lower if got is None else max(lower, got), child, rest, False))
            changed()


def corridor_lines(instance: Instance) -> list[tuple[np.ndarray, tuple[int, ...]]]:
    """For columns, then rows: the line of every cell and the corridor lines (one or two start
    tiles), where there are any."""
    start = instance.start.tiles
    cells = np.arange(instance.width * instance.height)
    out = []
    for line, count in ((cells % instance.width, instance.width), (cells // instance.width, instance.height)):
        starts = np.bincount(line[start], minlength=count)
        corridor = tuple(j for j in range(count) if 1 <= starts[j] <= 2)
        if corridor:
            out.append((line, corridor))
    return out


def scenario_value(instance: Instance, line: np.ndarray, corridor: tuple, inside: tuple, allowed: tuple,
                   budget: Budget | None = None, split: bool = False) -> int | None:
    """The program of the family of scenarios ``inside <= Z <= allowed`` (module docstring):
    the routing bound on the ground of ``allowed`` with a place forced in each line of
    ``inside`` (with ``split``, the per-robot integer program of :mod:`.routing`); None where it
    is not solved."""
    both = instance.start.tiles | instance.goal_tiles
    ground = both | ~np.isin(line, corridor) | np.isin(line, allowed)
    groups = [np.flatnonzero((line == j) & ~both) for j in inside]
    return routing_bound(instance, Ground(feet=ground, picks=ground, places=ground), budget, places=groups,
                         split=split)


def scenario_of(instance: Instance, line: np.ndarray, corridor: tuple, tiles) -> tuple:
    """A schedule's scenario: the corridor lines in which a cell outside start and goal holds a
    tile after some step (``tiles``: the tiles after each step)."""
    both = instance.start.tiles | instance.goal_tiles
    ever = np.logical_or.reduce([t & ~both for t in tiles])
    return tuple(j for j in corridor if ever[line == j].any())
