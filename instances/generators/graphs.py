"""Grid graphs, the source problem of the paper's reductions (Computational Complexity section).

A *grid graph* is a finite set of integer points with an edge between every two points at
distance 1 (an induced subgraph of the infinite grid). Files describe one in either of two forms:

- a drawing: ``o`` a vertex, ``.`` or a space no vertex, one text row per grid row (``y`` grows
  downward);
- a vertex list: one ``x y`` pair per line;
- an edge list: one ``x1 y1 x2 y2`` per line, two points at distance 1 (the vertices are their
  ends); since a grid graph joins *every* two points at distance 1, an edge list that leaves
  such a pair out is refused, naming the pair.

In the Python API any networkx graph whose vertices are ``(x, y)`` integer points is accepted if it
is a grid graph (:func:`check_grid_graph` names what is not).

Lines starting with ``#`` are comments in both. Hamiltonian paths (Itai, Papadimitriou and
Szwarcfiter 1982: NP-complete in grid graphs) are decided exactly by backtracking, which is fast
for the few dozen vertices the reductions are used with.
"""
from __future__ import annotations

import random
import re
from pathlib import Path

import networkx as nx

from ..errors import InstanceError

XY = tuple[int, int]
# the reductions and the exact Hamiltonian path search are for small graphs: a bound on the
# vertices (a 40x40 grid graph), and on the backtracking's work (steps x vertices, each step
# looks at every vertex), answers within seconds what would run for hours
MAX_VERTICES = 1600
MAX_WORK = 5_000_000
_PAIR = re.compile(r"^\s*(-?\d+)\s+(-?\d+)\s*$")
_EDGE = re.compile(r"^\s*(-?\d+)\s+(-?\d+)\s+(-?\d+)\s+(-?\d+)\s*$")


def grid_graph(vertices) -> nx.Graph:
    """The grid graph on ``(x, y)`` points: edges between points at distance 1.

    >>> sorted(grid_graph([(0, 0), (1, 0), (1, 1), (3, 3)]).edges)
    [((0, 0), (1, 0)), ((1, 0), (1, 1))]
    """
    g = nx.Graph()
    points = {(int(x), int(y)) for x, y in vertices}
    g.add_nodes_from(sorted(points))
    g.add_edges_from(((x, y), (x + 1, y)) for x, y in points if (x + 1, y) in points)
    g.add_edges_from(((x, y), (x, y + 1)) for x, y in points if (x, y + 1) in points)
    return g


def parse_graph(text: str, name: str = "<graph>") -> nx.Graph:
    """A grid graph from a drawing or a vertex list (see the module docstring).

    Raises :class:`InstanceError` naming the line and column of an unknown character, or when
    the graph is empty.
    """
    lines = [(k + 1, line.rstrip("\n")) for k, line in enumerate(text.splitlines())]
    body = [(k, line) for k, line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not body:
        raise InstanceError(f"{name}: no vertices (expected a drawing with 'o' or lines 'x y')")
    if len(body) > MAX_VERTICES * 2:  # a vertex or edge per line: too many lines is too many vertices
        _check_vertices(len(body) // 2, name)
    if all(_PAIR.match(line) for _, line in body):
        return grid_graph(tuple(map(int, _PAIR.match(line).groups())) for _, line in body)
    if all(_EDGE.match(line) for _, line in body):
        g = nx.Graph()
        for k, line in body:
            x1, y1, x2, y2 = map(int, _EDGE.match(line).groups())
            if abs(x1 - x2) + abs(y1 - y2) != 1:
                raise InstanceError(f"{name}:{k}: the edge ({x1}, {y1})-({x2}, {y2}) joins points at distance "
                                    f"{abs(x1 - x2) + abs(y1 - y2)}, not 1")
            g.add_edge((x1, y1), (x2, y2))
        check_grid_graph(g, name)
        return grid_graph(g.nodes)
    _check_vertices(sum(line.count("o") for _, line in body), name)
    points = []
    top = body[0][0]
    for k, line in lines[top - 1:]:
        if line.lstrip().startswith("#"):
            continue
        for col, ch in enumerate(line):
            if ch == "o":
                points.append((col, k - top))
            elif ch not in ". \t":
                raise InstanceError(f"{name}:{k}: column {col + 1}: unexpected {ch!r} "
                                    f"(a drawing has 'o' for a vertex and '.' or ' ' for none; "
                                    f"a vertex list has lines 'x y')")
    if not points:
        raise InstanceError(f"{name}: no vertices (expected a drawing with 'o' or lines 'x y')")
    return grid_graph(points)


def check_grid_graph(g, name: str = "the graph") -> None:
    """Raise :class:`InstanceError` unless ``g`` is a grid graph: a networkx graph whose vertices
    are ``(x, y)`` integer points and whose edges join exactly the pairs at distance 1."""
    if not isinstance(g, nx.Graph):
        raise InstanceError(f"{name}: expected a networkx graph, got {type(g).__name__}")
    _check_vertices(g.number_of_nodes(), name)
    for v in g.nodes:
        if not (isinstance(v, tuple) and len(v) == 2 and all(isinstance(c, int) and not isinstance(c, bool) for c in v)):
            raise InstanceError(f"{name}: vertex {v!r} is not an (x, y) integer point (a grid graph's vertices are "
                                f"points of the grid, e.g. networkx.grid_2d_graph(3, 2))")
    for a, b in g.edges:
        if abs(a[0] - b[0]) + abs(a[1] - b[1]) != 1:
            raise InstanceError(f"{name}: the edge {a}-{b} joins points at distance {abs(a[0] - b[0]) + abs(a[1] - b[1])}, "
                                f"not 1")
    for x, y in g.nodes:
        for n in ((x + 1, y), (x, y + 1)):
            if n in g and not g.has_edge((x, y), n):
                raise InstanceError(f"{name}: the points {(x, y)} and {n} are at distance 1 but not joined; a grid "
                                    f"graph joins every such pair (the reductions build all of them)")


def load_graph(path: str | Path) -> nx.Graph:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InstanceError(f"{path}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError:
        raise InstanceError(f"{path}: not a text file") from None
    return parse_graph(text, str(path))


def random_grid_graph(vertices: int, seed: int = 0) -> nx.Graph:
    """A connected grid graph of ``vertices`` points grown from ``(0, 0)`` by adding a random
    free neighbour of the points so far, shifted so that the smallest ``x`` and ``y`` are 0."""
    if vertices < 1:
        raise InstanceError(f"a graph needs at least 1 vertex, got {vertices}")
    _check_vertices(vertices)
    rnd = random.Random(seed)
    points = [(0, 0)]
    taken = {(0, 0)}
    while len(points) < vertices:
        x, y = rnd.choice(points)
        dx, dy = rnd.choice(((1, 0), (-1, 0), (0, 1), (0, -1)))
        if (x + dx, y + dy) not in taken:
            taken.add((x + dx, y + dy))
            points.append((x + dx, y + dy))
    mx, my = min(x for x, _ in points), min(y for _, y in points)
    return grid_graph((x - mx, y - my) for x, y in points)


def _check_vertices(n: int, name: str = "the graph") -> None:
    if n > MAX_VERTICES:
        raise InstanceError(f"{name}: {n} vertices, more than the {MAX_VERTICES} the reductions and the exact "
                            "Hamiltonian path search are made for")


def draw_graph(g: nx.Graph) -> str:
    """The drawing form of a grid graph (origin at its smallest ``x`` and ``y``)."""
    xs, ys = [x for x, _ in g.nodes], [y for _, y in g.nodes]
    return "\n".join("".join("o" if (x, y) in g else "." for x in range(min(xs), max(xs) + 1))
                     for y in range(min(ys), max(ys) + 1)) + "\n"


def hamiltonian_path(g: nx.Graph, start: XY | None = None, end: XY | None = None) -> list[XY] | None:
    """A Hamiltonian path of ``g`` (starting at ``start`` and ending at ``end`` if given), or None
    if there is none.

    Backtracking from each possible first vertex (a vertex of degree 1 if there is one: it must
    be an end), extending along unvisited neighbours, fewest onward choices first (Warnsdorff's
    order), and cutting a branch when the unvisited vertices are no longer connected to the
    path's end or more than one of them has become a dead end.

    >>> hamiltonian_path(grid_graph([(0, 0), (1, 0), (2, 0), (1, 1)])) is None   # a T
    True
    >>> hamiltonian_path(grid_graph([(0, 0), (1, 0), (1, 1)]))
    [(0, 0), (1, 0), (1, 1)]
    >>> hamiltonian_path(grid_graph([(0, 0), (1, 0), (1, 1)]), end=(0, 0))
    [(1, 1), (1, 0), (0, 0)]

    A fixed end is a fixed start with one more vertex: a leaf hung on ``end``, which every
    Hamiltonian path of the larger graph has at its other end.
    """
    n = g.number_of_nodes()
    if n == 0 or not nx.is_connected(g):
        return None
    for name, v in (("start", start), ("end", end)):
        if v is not None and v not in g:
            raise InstanceError(f"the {name} vertex {v} is not a vertex of the graph")
    if end is not None:
        if end == start:
            return [end] if n == 1 else None
        leaf = ("end", end)
        path = hamiltonian_path(nx.Graph([*g.edges, (end, leaf)]) if n > 1 else nx.Graph([(end, leaf)]), start)
        if path is not None and path[0] == leaf:
            path.reverse()
        return None if path is None else path[:-1]
    leaves = [v for v in g if g.degree(v) == 1]
    if len(leaves) > 2 or (start is not None and leaves and start not in leaves and len(leaves) == 2):
        return None
    firsts = [start] if start is not None else (leaves[:1] if leaves else sorted(g.nodes))
    _check_vertices(n)
    adj = {v: set(g[v]) for v in g}
    budget = [max(1, MAX_WORK // n)]
    for first in firsts:
        path = [first]
        if _extend(adj, path, {first}, n, budget):
            return path
    return None


def _options(adj: dict, end, seen: set) -> list:
    """The unvisited neighbours of ``end``, fewest onward choices first (Warnsdorff's order)."""
    options = [v for v in adj[end] if v not in seen]
    options.sort(key=lambda v: sum(1 for u in adj[v] if u not in seen))
    return options


def _extend(adj: dict, path: list, seen: set, n: int, budget: list) -> bool:
    """Extend ``path`` to all ``n`` vertices, depth first; ``frames[k]`` holds the options of
    ``path[k]`` not yet tried (a loop, not recursion: paths are longer than Python's stack)."""
    frames = [_options(adj, path[-1], seen)]
    while frames:
        if len(path) == n:
            return True
        if not frames[-1]:
            frames.pop()
            if frames:
                seen.discard(path.pop())
            continue
        budget[0] -= 1
        if budget[0] < 0:
            raise InstanceError(f"the graph's Hamiltonian path is undecided after {MAX_WORK // n} steps of the "
                                f"exact search ({n} vertices: a smaller graph, please)")
        v = frames[-1].pop(0)
        path.append(v)
        seen.add(v)
        if _promising(adj, seen, v, n):
            frames.append(_options(adj, v, seen))
        else:
            path.pop()
            seen.discard(v)
    return False


def _promising(adj: dict, seen: set, end, n: int) -> bool:
    """The rest can still be one path from ``end``: connected to it, at most one dead end."""
    rest = n - len(seen)
    if rest == 0:
        return True
    dead = sum(1 for v in adj if v not in seen and sum(1 for u in adj[v] if u not in seen or u == end) <= 1)
    if dead > 1:
        return False
    stack = [u for u in adj[end] if u not in seen]
    if not stack:
        return False
    reached = set(stack)
    while stack:
        for u in adj[stack.pop()]:
            if u not in seen and u not in reached:
                reached.add(u)
                stack.append(u)
    return len(reached) == rest
