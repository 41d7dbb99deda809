"""Edge-weighted vertex covers: the admissible heuristics of CBSH (Felner et al. 2018; Li et al. 2019).

Robots are vertices; an edge ``(i, j, w)`` says that in every schedule of the node's subtree
``i`` and ``j`` together pay at least ``w`` more than their present costs. Any assignment of
extra costs ``x`` must then have ``x_i + x_j >= w`` on every edge, so the least ``sum(x)`` (an
edge-weighted vertex cover) is a lower bound on the extra sum of costs. With every ``w = 1`` it is
the minimum vertex cover (the CG and DG heuristics); with ``w`` from solving the pair alone, WDG.

Solved exactly per connected component by branch and bound up to :data:`EXACT` robots; a larger
component gets the weight of a greedy matching (the edges of a matching share no vertex, so their
weights add up to at most ``sum(x)``): smaller, still a lower bound.
"""
from __future__ import annotations

EXACT = 14


def cover(edges: dict[tuple[int, int], int]) -> int:
    """The least ``sum(x)`` over non-negative integers with ``x_i + x_j >= w`` on every edge."""
    adjacent: dict[int, dict[int, int]] = {}
    for (i, j), w in edges.items():
        if w > 0:
            adjacent.setdefault(i, {})[j] = max(w, adjacent.get(i, {}).get(j, 0))
            adjacent.setdefault(j, {})[i] = max(w, adjacent.get(j, {}).get(i, 0))
    total, seen = 0, set()
    for v in adjacent:
        if v in seen:
            continue
        part, todo = [], [v]
        seen.add(v)
        while todo:
            u = todo.pop()
            part.append(u)
            for n in adjacent[u]:
                if n not in seen:
                    seen.add(n)
                    todo.append(n)
        total += _exact(part, adjacent) if len(part) <= EXACT else _matching(part, adjacent)
    return total


def _matching(part: list[int], adjacent: dict[int, dict[int, int]]) -> int:
    used, total = set(), 0
    for w, i, j in sorted(((w, i, j) for i in part for j, w in adjacent[i].items() if i < j), reverse=True):
        if i not in used and j not in used:
            used.update((i, j))
            total += w
    return total


def _exact(part: list[int], adjacent: dict[int, dict[int, int]]) -> int:
    order = sorted(part, key=lambda v: -len(adjacent[v]))
    rank = {v: k for k, v in enumerate(order)}
    best = [_matching_upper(order, adjacent)]
    x: dict[int, int] = {}

    def bound(k: int) -> int:
        """A lower bound on what the vertices from ``k`` on must still pay: for each edge to an
        assigned vertex, what it leaves uncovered; the largest such need per vertex."""
        need = 0
        for v in order[k:]:
            need += max((w - x[n] for n, w in adjacent[v].items() if n in x), default=0)
        return need

    def go(k: int, paid: int) -> None:
        if paid + bound(k) >= best[0]:
            return
        if k == len(order):
            best[0] = paid
            return
        v = order[k]
        low = max((w - x[n] for n, w in adjacent[v].items() if n in x), default=0)
        high = max((w for n, w in adjacent[v].items() if rank[n] > k), default=0)
        for value in range(max(low, 0), max(low, high, 0) + 1):
            x[v] = value
            go(k + 1, paid + value)
            del x[v]

    go(0, 0)
    return best[0]


def _matching_upper(order: list[int], adjacent: dict[int, dict[int, int]]) -> int:
    """A feasible cover's cost (every vertex pays its heaviest edge) plus one: the first bound
    to beat."""
    return sum(max(adjacent[v].values()) for v in order) + 1
