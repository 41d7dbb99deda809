"""The method registry: method name -> ``plan(instance, **options) -> Result``.

Methods live in several packages (``bille.solvers`` for the exact ones, ``bille.heuristics``
for the planners), and those import the ``Result`` and ``Schedule`` types from here; the
registry is therefore filled on first use, which keeps imports one-way at load time.
"""
from __future__ import annotations

from collections.abc import Mapping
from importlib import import_module
from typing import Callable, Iterator

# name -> "module:function"; the order is the order shown to users
_ENTRIES = {
    "astar": "bille.heuristics.astar:plan",
    "mstar": "bille.heuristics.mstar:plan",
    "temporal-astar": "bille.heuristics.temporal_astar:plan",
    "cpsat": "bille.solvers.exact:plan_cpsat",
    "sat": "bille.solvers.exact:plan_sat",
    "bfs": "bille.solvers.bfs:plan",
}


class _Registry(Mapping):
    def __init__(self, entries: dict[str, str]) -> None:
        self._entries = entries
        self._loaded: dict[str, Callable] = {}

    def __getitem__(self, name: str) -> Callable:
        if name not in self._loaded:
            module, func = self._entries[name].split(":")
            self._loaded[name] = getattr(import_module(module), func)
        return self._loaded[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)


METHODS: Mapping[str, Callable] = _Registry(_ENTRIES)
