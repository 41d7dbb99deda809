"""One least-recently-used cache for the compiled tables and distance tables.

``functools.lru_cache`` keys on the call's arguments; these caches key on what the arguments
mean (a tile set's bytes, a goal's name) and compute the value only on a miss.
"""
from __future__ import annotations

from collections import OrderedDict
from typing import Callable, Generic, Hashable, TypeVar

V = TypeVar("V")


class LRU(Generic[V]):
    """At most ``size`` values; the least recently used goes first.

    >>> cache = LRU(2)
    >>> [cache.get("a", lambda: 1), cache.get("b", lambda: 2), cache.get("a", lambda: 9)]
    [1, 2, 1]
    >>> cache.get("c", lambda: 3); "b" in cache
    3
    False
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: OrderedDict = OrderedDict()

    def clear(self) -> None:
        self._items.clear()

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def get(self, key: Hashable, make: Callable[[], V], valid: Callable[[V], bool] | None = None) -> V:
        """The value of ``key``, made by ``make()`` on a miss (or when ``valid(value)`` fails)."""
        value = self._items.get(key)
        if value is None or (valid is not None and not valid(value)):
            value = make()
            self._items[key] = value
            while len(self._items) > self.size:
                self._items.popitem(last=False)
        else:
            self._items.move_to_end(key)
        return value
