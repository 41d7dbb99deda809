"""Each motion of S5, S7 and point, in each heading, against the rule book's local-frame table."""
import numpy as np
import pytest

import refmodel
from bille.instances import compile_posegraph, load_moveset

W = H = 9
CENTRE = (4, 4)


def graph(name):
    return compile_posegraph(load_moveset(name), W, H, np.zeros(W * H, bool))


def cellset(g, cells):
    return {(int(c) % W, int(c) // W) for c in cells if c >= 0}


@pytest.mark.parametrize("moveset", ["S5", "S7"])
@pytest.mark.parametrize("heading", list(refmodel.HEADING))
@pytest.mark.parametrize("action", list(refmodel.BIPED))
def test_biped_motion_matches_table(moveset, heading, action):
    if action not in refmodel.MOVESETS[moveset]:
        assert action not in load_moveset(moveset).index
        return
    g = graph(moveset)
    h = refmodel.HEADING[heading]
    front, back = CENTRE, (CENTRE[0] - h[0], CENTRE[1] - h[1])
    robot = {"front": front, "back": back, "carrying": False}
    nf, nb, coll, carried, target = refmodel.motion(robot, action)

    p = g.pose_of(front, back)
    a = g.moveset.index[action]
    assert g.feet_xy(p) == (front, back)
    assert g.feet_xy(int(g.succ[p, a])) == (nf, nb)
    assert cellset(g, g.coll[p, a]) == coll
    assert cellset(g, g.carry[p, a]) == carried
    assert cellset(g, g.need[p, a]) == {nf, nb}
    assert cellset(g, [g.target[p, a]]) == ({target} if target else set())
    parts = g.world_cells(p, a, carrying=True)
    assert set(parts["collision"]) == coll and set(parts["carried"]) == carried


@pytest.mark.parametrize("action", refmodel.MOVESETS["point"])
def test_point_action_matches_table(action):
    g = graph("point")
    robot = {"front": CENTRE, "back": None, "carrying": True}
    nf, _, coll, carried, target = refmodel.motion(robot, action)
    p = g.pose_of(CENTRE)
    a = g.moveset.index[action]
    assert g.feet_xy(int(g.succ[p, a])) == (nf,)
    assert cellset(g, g.coll[p, a]) == coll
    assert cellset(g, g.carry[p, a]) == set()  # a carried tile rides on the robot
    assert cellset(g, [g.target[p, a]]) == ({target} if target else set())


def test_shipped_carried_cells_follow_the_box_rule():
    from bille.instances.moveset import box_rule

    for name in ("S5", "S7"):
        for act in load_moveset(name).actions:
            if act.target is None:
                assert sorted(act.carried) == sorted(box_rule(act.front, act.back)), (name, act.name)


def test_motions_leaving_the_grid_have_no_successor():
    g = graph("S7")
    p = g.pose_of((4, 0), (4, 1))  # heading N at the top edge
    assert g.succ[p, g.moveset.index["fwd"]] == -1
    assert g.succ[p, g.moveset.index["back"]] >= 0
    assert not g.carry_ok[p, g.moveset.index["wait"]]  # a carried tile would hover off the grid


def test_obstacles_block_feet_and_swept_cells():
    obstacles = np.zeros(W * H, bool)
    obstacles[5 * W + 5] = True  # (5, 5): the cell fwd-right sweeps for a robot at (4,4) heading N
    g = compile_posegraph(load_moveset("S7"), W, H, obstacles)
    p = g.pose_of((4, 4), (4, 5))
    assert g.succ[p, g.moveset.index["fwd-right"]] == -1
    assert g.succ[p, g.moveset.index["fwd-left"]] >= 0
    assert g.pose_of((5, 5), (5, 6)) == -1  # a foot on an obstacle is no pose


@pytest.mark.parametrize("name", ["crowded-2", "lt-1", "compare-4", "point-4"])
def test_the_python_and_the_compiled_search_walk_the_same_distances(name, monkeypatch):
    # below SMALL_GRAPH poses the distances come from a Python breadth-first search, above from
    # the compiled one: both, and scipy's Dijkstra, on every bundled structure tried, to every
    # cell and from many poses
    from scipy.sparse.csgraph import dijkstra

    from bille.instances import load_instance, walking
    from bille.instances.bundled import bundled_path

    inst = load_instance(bundled_path(name))
    graph = inst.world.graphs[0]
    tiles = np.asarray(inst.start.tiles)
    for carrying in (False, True):
        tables = []
        for small, large in ((10**9, 10**9), (0, 0), (0, 10**9)):  # Python, compiled, scipy (numba unloaded)
            monkeypatch.setattr(walking, "SMALL_GRAPH", small)
            monkeypatch.setattr(walking, "LARGE_GRAPH", large)
            monkeypatch.setattr(walking.Walk, "_compiled", lambda self: self.succ.shape[0] >= walking.LARGE_GRAPH)
            walk = walking.Walk(graph, tiles, carrying)
            poses = range(0, walk.succ.shape[0], max(1, walk.succ.shape[0] // 40))
            tables.append([walk.distances(c) for c in range(tiles.size)] + [walk.from_pose(p) for p in poses])
        assert all(np.array_equal(a, b) for a, b in zip(tables[0], tables[1]))
        assert all(np.array_equal(a, b) for a, b in zip(tables[0], tables[2]))
        scipy = [dijkstra(walk._reverse_graph(), indices=walk.goal_poses(c), unweighted=True, min_only=True)
                 if len(walk.goal_poses(c)) else np.full(walk.succ.shape[0], np.inf) for c in range(tiles.size)]
        assert all(np.array_equal(np.where(np.isfinite(s), s, walking.UNREACHABLE), t)
                   for s, t in zip(scipy, tables[0]))
