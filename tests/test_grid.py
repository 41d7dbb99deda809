"""Connectivity, articulation points and the connectivity rule on random structures."""
import networkx as nx
import numpy as np
from hypothesis import event, given, strategies as st

import refmodel
from bille.instances import Violation, apply, articulation_points, is_connected, may_pick
from bille.instances.grid import detached_cells
from helpers import make


@st.composite
def structures(draw, min_tiles=2):
    W, H = draw(st.integers(2, 8)), draw(st.integers(1, 8))
    mask = draw(st.lists(st.booleans(), min_size=W * H, max_size=W * H))
    tiles = np.array(mask, dtype=bool)
    return W, H, tiles


@st.composite
def polyominoes(draw):
    """A connected tile set grown cell by cell from a random seed."""
    W, H = draw(st.integers(2, 8)), draw(st.integers(1, 8))
    rnd = draw(st.randoms(use_true_random=False))
    tiles = np.zeros(W * H, bool)
    tiles[rnd.randrange(W * H)] = True
    for _ in range(draw(st.integers(1, W * H))):
        grow = [y * W + x for c in np.flatnonzero(tiles) for x, y in
                [(c % W + 1, c // W), (c % W - 1, c // W), (c % W, c // W + 1), (c % W, c // W - 1)]
                if 0 <= x < W and 0 <= y < H and not tiles[y * W + x]]
        if grow:
            tiles[rnd.choice(grow)] = True
    return W, H, tiles


def tile_graph(W, H, tiles):
    g = nx.grid_2d_graph(W, H)
    return g.subgraph([(x, y) for x, y in g.nodes if tiles[y * W + x]])


@given(st.one_of(structures(), polyominoes()))
def test_articulation_points_agree_with_networkx(s):
    W, H, tiles = s
    expected = set(nx.articulation_points(tile_graph(W, H, tiles)))
    got = {(c % W, c // W) for c in np.flatnonzero(articulation_points(tiles, W, H))}
    assert got == expected


@st.composite
def larger(draw):
    """A random tile mask on a grid of more than TINY_GRID cells (up to 12 x 12)."""
    W, H = draw(st.integers(9, 12)), draw(st.integers(8, 12))
    return W, H, np.array(draw(st.lists(st.booleans(), min_size=W * H, max_size=W * H)), dtype=bool)


@given(st.one_of(structures(), larger(), polyominoes()), st.sampled_from([0, 10**9]))
def test_connectivity_agrees_with_networkx(s, searched):
    # both ways of telling it: the search here (nothing searched yet) and scipy's labelling
    from bille.instances import grid

    W, H, tiles = s
    g = tile_graph(W, H, tiles)
    saved, grid._searched = grid._searched, searched
    try:
        assert is_connected(tiles, W, H) == (g.number_of_nodes() > 0 and nx.is_connected(g))
    finally:
        grid._searched = saved


@given(structures(), st.integers(0, 63))
def test_may_pick_is_removal_keeps_connectivity(s, k):
    W, H, tiles = s
    cell = k % (W * H)
    rest = {(c % W, c // W) for c in np.flatnonzero(tiles) if c != cell}
    expected = bool(tiles[cell]) and refmodel.connected(rest)
    assert may_pick(tiles, W, H, cell) == expected


@given(polyominoes(), st.integers(0, 10**6), st.integers(0, 3))
def test_pick_rule_agrees_with_the_reference(s, k, d):
    W, H, tiles = s
    cells = [(int(c % W), int(c // W)) for c in np.flatnonzero(tiles)]
    at = cells[k % len(cells)]
    name = ["north", "east", "south", "west"][d]
    grid = "\n".join("".join("T" if tiles[y * W + x] else "." for x in range(W)) for y in range(H))
    inst = make(grid, [{"at": list(at)}], moveset="point")
    got = apply(inst.world, inst.start_state, [inst.movesets[0].index[f"pick-{name}"]])
    robot = {"front": at, "back": None, "carrying": False}
    expected = refmodel.step(W, H, set(), set(cells), [robot], [f"pick-{name}"])
    event(f"pick: {expected[0] if expected[0] == 'ok' else expected[1]}")
    if expected[0] == "ok":
        assert not isinstance(got, Violation)
        assert {(c % W, c // W) for c in np.flatnonzero(got.tiles)} == expected[1]
    else:
        assert isinstance(got, Violation)
        assert (got.rule, got.robot, got.cells) == expected[1:]


def test_detached_cells_keep_the_largest_component():
    tiles = np.array([1, 1, 0, 1, 1, 1], bool)
    assert detached_cells(tiles, 6, 1) == [0, 1]
