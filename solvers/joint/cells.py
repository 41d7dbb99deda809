"""Classes of schedules named by the cells allowed to change (docs/exact.md, "Classes of schedules").

A cell *changes* in a schedule when it holds a tile at one step and not at another. A class is a
set ``C`` of cells; its schedules change no cell outside ``C``. Writing ``S`` and ``G`` for the
cells with a tile at the start and in the goal:

``keep``
    ``C = S ^ G``: only the cells where the start and the goal differ; the rest of the
    structure is kept (the schedules that keep the structure).
``no-scaffold``
    ``C = S | G``: no tile is ever set down where neither the start nor the goal has one.
``all``
    every cell that is not an obstacle: every schedule (the unconditional optimum).

Each may be widened by listed cells (``add_cells``). They nest: ``keep`` within ``no-scaffold``
within ``all``, and a class within the same class widened. Every schedule changes the cells of
``S ^ G`` (they differ between the first and the last step), so every class here contains them,
and a schedule of a class leaves every other cell as it is at the start, which is as in the goal.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bille.instances import Instance, OptionError

KINDS = ("keep", "no-scaffold", "all")
# the names of the classes in a sentence, and the keys of solvers.classes for the same sets
NAMES = {"keep": "the schedules that keep the structure", "no-scaffold": "the schedules without scaffold",
         "all": "all schedules"}
CLASS_KEYS = {"keep": "keep-structure", "no-scaffold": "no-scaffold"}


@dataclass(frozen=True)
class Cells:
    """One class of schedules on one instance: its ``kind``, the cells added to it (``(x, y)``,
    in the order given, without repeats and without those the kind has already), and ``mask``,
    the flat mask of the cells allowed to change."""

    kind: str
    added: tuple[tuple[int, int], ...]
    mask: np.ndarray

    @property
    def unconditional(self) -> bool:
        """Whether the class holds every schedule (its optimum is the instance's)."""
        return self.kind == "all"

    @property
    def key(self) -> str:
        """The option's spelling: ``keep``, or ``keep+(8,2)(8,5)`` when widened."""
        return self.kind + ("+" + "".join(f"({x},{y})" for x, y in self.added) if self.added else "")

    @property
    def name(self) -> str:
        """The class in a sentence: "the schedules that keep the structure, and may change (8, 2)"."""
        cells = ", ".join(f"({x}, {y})" for x, y in self.added)
        return NAMES[self.kind] + (f" and may change {cells}" if self.added else "")

    @property
    def class_key(self) -> str | None:
        """The key of the same set in :mod:`bille.solvers.bounds.classes` (None when widened or ``all``)."""
        return None if self.added else CLASS_KEYS.get(self.kind)

    def to_json(self) -> dict:
        return {"cells": self.kind, "add_cells": [list(c) for c in self.added], "size": int(self.mask.sum())}


def cells_of(instance: Instance, kind: str = "all", add: list | tuple = ()) -> Cells:
    """The class ``kind`` (:data:`KINDS`) on ``instance``, widened by the cells ``add`` (``[x, y]``
    pairs); raises :class:`OptionError` naming a cell outside the grid or on an obstacle."""
    if kind not in KINDS:
        raise OptionError(f"unknown cells {kind!r} (expected one of: {', '.join(KINDS)})")
    start, goal = instance.start.tiles, instance.goal_tiles
    free = ~instance.start.obstacles
    mask = {"keep": start ^ goal, "no-scaffold": start | goal, "all": free}[kind].copy()
    added = []
    for xy in add:
        if not (isinstance(xy, (list, tuple)) and len(xy) == 2 and all(isinstance(v, int) and not isinstance(v, bool)
                                                                      for v in xy)):
            raise OptionError(f"add_cells: expected [x, y] pairs of whole numbers, got {xy!r}")
        x, y = xy
        if not (0 <= x < instance.width and 0 <= y < instance.height):
            raise OptionError(f"add_cells: ({x}, {y}) is outside the {instance.width}x{instance.height} grid")
        cell = y * instance.width + x
        if not free[cell]:
            raise OptionError(f"add_cells: ({x}, {y}) is an obstacle")
        if not mask[cell]:
            mask[cell] = True
            added.append((x, y))
    mask.flags.writeable = False
    return Cells(kind, tuple(added), mask)
