"""Breadth-first distances over a walk's pose graph, compiled with Numba for large graphs
(:mod:`.walking` uses them above :data:`.walking.SMALL_GRAPH` poses; below, its pure-Python
search answers before Numba would load). The same distances as that search and as SciPy's
unweighted Dijkstra: tests/test_walking.py compares them."""
from __future__ import annotations

import numpy as np

from .jit import jit


@jit
def breadth_first(indptr, indices, sources, unreachable, blocked):  # pragma: no cover - compiled
    """``int32[n]``: fewest edges from any of ``sources`` to each node along the CSR graph
    (``indptr``, ``indices``), never entering a node where ``blocked`` is True (an empty array:
    none); ``unreachable`` where none leads."""
    n = indptr.shape[0] - 1
    dist = np.full(n, unreachable, dtype=np.int32)
    queue = np.empty(n, dtype=np.int64)
    head, tail = 0, 0
    for s in sources:
        if dist[s] == unreachable:
            dist[s] = 0
            queue[tail] = s
            tail += 1
    while head < tail:
        u = queue[head]
        head += 1
        d = dist[u] + 1
        for k in range(indptr[u], indptr[u + 1]):
            v = indices[k]
            if dist[v] == unreachable and not (blocked.shape[0] > 0 and blocked[v]):
                dist[v] = d
                queue[tail] = v
                tail += 1
    return dist


def csr(origin: np.ndarray, target: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The edges ``origin[k] -> target[k]`` of an ``n``-node graph as CSR arrays."""
    order = np.argsort(origin, kind="stable")
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(origin, minlength=n), out=indptr[1:])
    return indptr, target[order].astype(np.int64)
