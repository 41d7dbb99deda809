"""LaCAM*: complete on a fixed structure, anytime, and the loop's motion layer (every schedule
goes through the validator; solvability and optima are checked against brute force)."""
from functools import lru_cache
from random import Random

import pytest

from bille.instances import InstanceError, load_instance
from bille.instances.bundled import bundled_path
from bille.instances.claim import Claim
from bille.instances.failure import Failure
from bille.heuristics.lacam import states as lacam_states
from bille.instances.generators.random import crowded
from bille.instances.run import Run
from bille.solvers import solve, validate
from helpers import diagonal_moveset, make
from refsearch import walking_makespan
from tinyworlds import tiny_instances

STEPS = ((0, -1), (1, 0), (0, 1), (-1, 0))


def tiny_path_planning(seed: int):
    """A random path-planning instance small enough for brute force: 2-3 robots on a few tiles,
    goals anywhere (some instances have no walking schedule); point robots under either
    collision rule."""
    rnd = Random(seed)
    w, h = rnd.choice([(3, 2), (4, 2), (3, 3), (5, 2), (4, 3)])
    cells = [(x, y) for y in range(h) for x in range(w)]
    tiles = set(cells) - set(rnd.sample(cells, rnd.randint(0, 2)))
    moveset = rnd.choice(["point", "point", "S5", "S7"])
    robots, used, goals = [], set(), []
    for _ in range(rnd.randint(2, 3 if moveset == "point" and w * h <= 9 else 2)):  # keeps the brute force fast
        for _try in range(20):
            x, y = rnd.choice(sorted(tiles))
            if moveset == "point":
                feet, robot = [(x, y)], {"at": [x, y]}
            else:
                dx, dy = rnd.choice(STEPS)
                feet, robot = [(x, y), (x - dx, y - dy)], {"front": [x, y], "back": [x - dx, y - dy]}
            if all(f in tiles for f in feet) and used.isdisjoint(feet):
                used.update(feet)
                robots.append(robot)
                goals.append(list(rnd.choice(sorted(tiles))) if rnd.random() < 0.8 else None)
                break
    grid = "\n".join("".join("T" if (x, y) in tiles else "." for x in range(w)) for y in range(h))
    collisions = "classic" if moveset == "point" and rnd.random() < 0.5 else None
    try:
        return make(grid, robots, moveset=moveset, robot_goals=goals, name=f"tiny-path-{seed}", collisions=collisions)
    except InstanceError:
        return None


TINY = [inst for inst in map(tiny_path_planning, range(60)) if inst is not None]


@lru_cache(maxsize=None)
def reference(name: str) -> int | None:
    return walking_makespan(next(inst for inst in TINY if inst.name == name))


def checked(inst, **options):
    result = solve(inst, "lacam", **options)
    if result.schedule is not None:
        assert result.status in ("feasible", "optimal") and validate(inst, result.schedule).valid, result.stats
    return result


@pytest.mark.parametrize("inst", TINY, ids=lambda inst: inst.name)
def test_complete_and_eventually_optimal_on_tiny_instances(inst):
    best = reference(inst.name)
    first = checked(inst, improve=0.0)
    if best is None:  # the whole walking space is searched before it says so
        assert first.status == "unsolved" and "no walking schedule" in first.failure.text
        return
    assert first.schedule is not None and first.metrics.makespan >= best
    final = checked(inst, improve=1.0)
    assert final.metrics.makespan <= first.metrics.makespan
    if final.status == "optimal":  # the search closed: its claim is checked
        CLOSED.append(inst.name)
        assert final.metrics.makespan == best


CLOSED: list[str] = []


def test_the_tiny_instances_include_both_answers_and_closed_searches():
    answers = {reference(inst.name) is None for inst in TINY}
    assert answers == {True, False} and len(TINY) >= 40
    solvable = sum(reference(inst.name) is not None for inst in TINY)
    assert len(CLOSED) >= solvable // 2  # (runs after the test above, in file order)


@pytest.mark.parametrize("name", ["point-4", "compare-2", "compare-3", "compare-4", "compare-5", "compare-6",
                                  "crowded-2", "crowded-3"])
def test_solves_every_bundled_path_planning_instance(name):
    inst = load_instance(bundled_path(name))
    result = checked(inst, improve=0.0)
    assert result.status in ("feasible", "optimal")
    assert result.stats["nodes"] < 10_000  # a first schedule, quickly (at most 78 nodes on these)


def test_where_the_paper_planner_deadlocks():
    # two S7 robots swap the ends of a fully tiled 5x2 block
    swap = make("TTTTT\nTTTTT", [{"front": [1, 0], "back": [0, 0]}, {"front": [3, 1], "back": [4, 1]}],
                robot_goals=[[4, 1], [0, 0]])
    # four robots cross a plus-shaped 8x8 structure to the opposite arms
    plus = make("""
        ...TT...
        ...TT...
        ...TT...
        TTTTTTTT
        TTTTTTTT
        ...TT...
        ...TT...
        ...TT...""", [{"front": [3, 1], "back": [3, 0]}, {"front": [6, 3], "back": [7, 3]},
                      {"front": [4, 6], "back": [4, 7]}, {"front": [1, 4], "back": [0, 4]}],
                robot_goals=[[3, 7], [0, 3], [4, 0], [7, 4]])
    for inst in (swap, plus):
        result = checked(inst, improve=0.0)
        assert result.status in ("feasible", "optimal"), result.stats


@pytest.mark.parametrize("seed", range(100))
def test_crowded_random_instances_are_solved(seed):
    robots = 2 + seed % 7
    w, h = (6, 5) if robots <= 4 else (8, 6)
    inst = crowded(w, h, robots, seed=seed, moveset=["S7", "S5", "point"][seed % 3])
    result = checked(inst, improve=0.0)
    assert result.status in ("feasible", "optimal"), result.stats


def test_anytime_improvement_never_makes_it_worse():
    inst = load_instance(bundled_path("compare-4"))
    first = checked(inst, improve=0.0)
    later = checked(inst, improve=2.0)
    costs = [c for _, c in later.stats["improvements"]]
    assert costs == sorted(costs, reverse=True) and costs[0] == first.metrics.makespan
    assert later.metrics.makespan <= first.metrics.makespan


def test_sum_of_loss_objective():
    inst = load_instance(bundled_path("compare-3"))
    result = checked(inst, objective="sum-of-loss", improve=0.0)
    assert result.claim == Claim("sum-of-loss", walking_only=True)


TINY_RECONFIGURATION = tiny_instances(36)


@lru_cache(maxsize=None)
def brute_force(name: str):
    inst = next(i for i in TINY_RECONFIGURATION if i.name == name)
    return solve(inst, "bfs", time_limit=60)


@lru_cache(maxsize=None)
def with_lacam(name: str):
    # the loop first; where it gives up, LaCAM* over whole states, which is complete
    inst = next(i for i in TINY_RECONFIGURATION if i.name == name)
    return solve(inst, "lacam", time_limit=60, load_transfer=True, improve=0.0)


@pytest.mark.parametrize("inst", TINY_RECONFIGURATION, ids=lambda inst: inst.name)
def test_lacam_solves_every_tiny_reconfiguration_that_brute_force_solves(inst):
    result = with_lacam(inst.name)
    best = brute_force(inst.name)
    assert best.status in ("optimal", "infeasible")
    if best.status == "optimal":
        assert result.status == "feasible", result.stats
        assert validate(inst, result.schedule).valid
        assert result.metrics.makespan >= best.metrics.makespan
    else:  # the whole-state search exhausts its space: a proof, as the brute force's
        assert result.status == "infeasible" and result.schedule is None, result.stats


def test_the_tiny_reconfigurations_include_both_answers_and_loop_failures():
    answers = {brute_force(inst.name).status for inst in TINY_RECONFIGURATION}
    assert answers == {"optimal", "infeasible"}
    rescued = [inst.name for inst in TINY_RECONFIGURATION if brute_force(inst.name).status == "optimal"
               and "loop" in with_lacam(inst.name).stats]
    assert rescued  # instances where the loop gave up and the whole-state search found a schedule


@pytest.mark.parametrize("inst", [i for i in TINY_RECONFIGURATION[:24]], ids=lambda inst: inst.name)
def test_whole_state_search_improves_to_the_brute_force_optimum(inst):
    result = lacam_states.plan(inst, run=Run.limited(60), improve=30.0)
    best = brute_force(inst.name)
    if best.status == "infeasible":
        assert result.status == "infeasible"
        return
    steps = validate(inst, result.schedule)
    assert steps.valid and steps.metrics.makespan >= best.metrics.makespan
    gains = [cost for _, cost in result.stats["improvements"]]
    assert gains == sorted(gains, reverse=True)  # anytime: never worse
    if result.status == "optimal":  # the space was exhausted: the claim is a proof
        assert steps.metrics.makespan == best.metrics.makespan == result.lower_bound
        assert result.claim.unconditional


def test_a_loop_out_of_its_share_of_the_time_hands_over_to_the_complete_search(monkeypatch):
    """The loop gets part of the time limit; when it runs out of it (its motion layer finds no
    joint plan), the whole-state search still gets the rest and finds the schedule."""
    from bille.heuristics.loop import reconfigure
    from bille.instances.result import Result
    from bille.heuristics.lacam import method as lacam_method

    given = []

    def stuck(instance, options, run, **kw):
        given.append(run.budget.seconds())
        return Result("lacam", "timeout", failure=Failure("stuck", "LaCAM* found no joint plan (timeout)"))

    monkeypatch.setattr(reconfigure, "plan", stuck)
    name = next(i.name for i in TINY_RECONFIGURATION if brute_force(i.name).status == "optimal")
    inst = next(i for i in TINY_RECONFIGURATION if i.name == name)
    result = solve(inst, "lacam", time_limit=20, improve=0.0)
    assert given == [pytest.approx(lacam_method.LOOP_SHARE * 20, abs=0.01)] and lacam_method.LOOP_SHARE < 1
    assert result.status == "feasible" and validate(inst, result.schedule).valid
    assert result.metrics.makespan >= brute_force(name).metrics.makespan
    assert result.stats["loop"]["status"] == "timeout"


def _suo(inst, margin=10):
    from random import Random as R

    from bille.heuristics.joint import JointProblem
    from bille.heuristics.lacam.pibt import Classic
    from bille.heuristics.lacam.scatter import CollisionTable, scatter

    problem = JointProblem.of(inst, "lacam")
    nbrs = Classic(problem, R(0)).nbrs
    goals = [int(w.goal_poses(c)[0]) for w, c in zip(problem.walks, problem.goals)]
    nxt = scatter(nbrs, problem.dist_lists, list(problem.start), goals, margin=margin)
    paths = []
    for i, (s, g) in enumerate(zip(problem.start, goals)):
        path = [s]
        while path[-1] != g:
            assert path[-1] in nxt[i] and nxt[i][path[-1]] in nbrs[path[-1]]
            path.append(nxt[i][path[-1]])
        assert len(path) - 1 <= problem.dist_lists[i][s] + margin
        paths.append(path)
    table = CollisionTable(nbrs)
    for i, p in enumerate(paths):
        table.enroll(i, p)
    return problem, paths, table.count


def test_suo_paths_walk_to_the_goal_within_the_margin_and_avoid_each_other():
    # two robots cross a two-lane corridor head-on on the same lane: the shortest paths collide,
    # the SUO paths take one lane each (one step longer for one of them)
    inst = make("TTTTTTTT\nTTTTTTTT", [{"at": [0, 0]}, {"at": [7, 0]}], moveset="point",
                robot_goals=[[7, 0], [0, 0]], collisions="classic")
    assert _suo(inst, margin=0)[2] > 0  # the shortest paths: head-on on one lane
    _, paths, collisions = _suo(inst, margin=2)
    assert collisions == 0 and {p[len(p) // 2] // 8 for p in paths} == {0, 1}
    alone = make("TTTT\nTTTT", [{"at": [0, 0]}], moveset="point", robot_goals=[[3, 1]], collisions="classic")
    _, (path,), _ = _suo(alone)
    assert len(path) - 1 == 4  # one robot: a shortest path


@pytest.mark.parametrize("agents, seed", [(60, 0), (150, 3)])
def test_the_compiled_suo_table_gives_the_python_tables_paths(agents, seed):
    # the same algorithm twice (heuristics/scatter_compiled.py compiles it): the same paths, on a
    # benchmark map crowded enough that the rounds move many robots off their shortest paths
    from bille.heuristics.joint import JointProblem
    from bille.heuristics.lacam.pibt import Classic
    from bille.heuristics.lacam.scatter import scatter
    from bille.instances.generators.movingai import from_movingai
    from bille.tools.bench.maps import shipped_maps

    folder = shipped_maps()
    inst = from_movingai(folder / "room-32-32-4.map", folder / "room-32-32-4-random-1.scen", agents=agents)
    problem = JointProblem.of(inst, "lacam")
    nbrs = Classic(problem, Random(0)).nbrs
    goals = [int(w.goal_poses(c)[0]) for w, c in zip(problem.walks, problem.goals)]
    runs = {compiled: scatter(nbrs, problem.dist_lists, list(problem.start), goals, seed=seed, compiled=compiled,
                              arrays=problem.dists if compiled else None)
            for compiled in (False, True)}
    assert runs[True] == runs[False]
    assert sum(len(nxt) for nxt in runs[True]) > 0
    assert sum(len(nxt) - problem.dist_lists[i][s] for i, (nxt, s) in enumerate(zip(runs[True], problem.start))) > 0


@pytest.mark.parametrize("name, agents", [("room-32-32-4", 150), ("random-32-32-10", 200)])
def test_the_compiled_generator_gives_the_python_generators_configurations(name, agents):
    # the same PIBT twice (heuristics/lacam/pibt_compiled.py compiles it): from the same random
    # state, the same configurations (or the same refusal) under the same constraints, the random
    # state left alike, and the same moves left open by forced ones; along a run of configurations
    from bille.heuristics.joint import JointProblem
    from bille.heuristics.lacam.pibt import Classic
    from bille.heuristics.lacam.pibt_compiled import CompiledClassic
    from bille.heuristics.lacam.scatter import scatter
    from bille.instances.generators.movingai import from_movingai
    from bille.tools.bench.maps import shipped_maps

    folder = shipped_maps()
    inst = from_movingai(folder / f"{name}.map", folder / f"{name}-random-1.scen", agents=agents)
    problem = JointProblem.of(inst, "lacam")
    python, compiled = Classic(problem, Random(1)), CompiledClassic(problem, Random(1))
    goals = [int(w.goal_poses(c)[0]) for w, c in zip(problem.walks, problem.goals)]
    python.prefer = compiled.prefer = scatter(python.nbrs, problem.dist_lists, list(problem.start), goals,
                                              arrays=problem.dists)
    config, rng, refused = tuple(problem.start), Random(5), 0
    for step in range(40):
        order = list(range(agents))
        rng.shuffle(order)
        forced = ()
        if step % 3 == 0:  # a constraint: one robot's move fixed, as the search's tree sets them
            i = rng.randrange(agents)
            forced = ((i, rng.randrange(len(problem.moves(i, config[i])))),)
            j = rng.randrange(agents)
            assert python.compatible(config, forced, j) == compiled.compatible(config, forced, j)
        got = python.generate(config, order, forced, {})
        assert compiled.generate(config, order, forced, {}) == got, step
        assert python.rng.getstate() == compiled.rng.getstate()
        refused += got is None
        if got is not None and not forced:
            config = got[1]
    assert config != tuple(problem.start) and refused < 40


def test_suo_makes_lacam_spread_robots_on_a_benchmark_map():
    from bille.heuristics.lacam import search as lacam
    from bille.instances.generators.movingai import from_movingai
    from bille.tools.bench.maps import shipped_maps
    from bille.tools.bench.mapf import sum_of_costs

    folder = shipped_maps()
    inst = from_movingai(folder / "random-32-32-10.map", folder / "random-32-32-10-random-1.scen", agents=60)
    _, _, collisions = _suo(inst)
    with_suo = checked(inst, objective="sum-of-loss", improve=0.0)
    assert "scatter_s" in with_suo.stats and collisions < 60
    saved = lacam.SCATTER_SHARE
    try:
        lacam.SCATTER_SHARE = 0.0  # the SUO paths get no time: plain PIBT
        plain = checked(inst, objective="sum-of-loss", improve=0.0, time_limit=30)
    finally:
        lacam.SCATTER_SHARE = saved
    assert sum_of_costs(inst, with_suo.schedule) <= sum_of_costs(inst, plain.schedule)


def test_refinement_keeps_schedules_valid_and_never_costlier():
    from random import Random as R

    from bille.heuristics.lacam.refine import Paths, refine_once
    from bille.instances.generators.movingai import from_movingai
    from bille.tools.bench.maps import shipped_maps
    from bille.tools.bench.mapf import sum_of_costs

    folder = shipped_maps()
    inst = from_movingai(folder / "room-32-32-4.map", folder / "room-32-32-4-random-1.scen", agents=40)
    result = checked(inst, objective="sum-of-loss", improve=1.0)
    gains = [cost for _, cost in result.stats["improvements"]]
    assert gains == sorted(gains, reverse=True) and result.stats.get("refined", 0) >= 0
    # the refinement alone, forty neighbourhoods on the first schedule: paths stay conflict-free
    from bille.heuristics.joint import JointProblem
    from bille.heuristics.lacam.pibt import Classic

    first = checked(inst, objective="sum-of-loss", improve=0.0)
    problem = JointProblem.of(inst, "lacam")
    nbrs = Classic(problem, R(0)).nbrs
    goals = [int(w.goal_poses(c)[0]) for w, c in zip(problem.walks, problem.goals)]
    configs, poses = [tuple(problem.start)], list(problem.start)
    from bille.instances.schedule import bind

    ids = bind(inst, first.schedule)
    for t in range(ids.shape[1]):
        poses = [int(problem.walks[i].succ[p, ids[i, t]]) for i, p in enumerate(poses)]
        configs.append(tuple(poses))
    paths = []
    for i, g in enumerate(goals):
        end = len(configs) - 1
        while end > 0 and configs[end - 1][i] == g:
            end -= 1
        paths.append([c[i] for c in configs[:end + 1]])
    table = Paths(paths, len(nbrs))
    before = sum(len(p) - 1 for p in table.paths)
    assert before == sum_of_costs(inst, first.schedule)
    rng = R(1)
    saved = sum(refine_once(table, nbrs, problem.dist_lists, goals, rng, None) for _ in range(40))
    after = sum(len(p) - 1 for p in table.paths)
    assert saved == before - after >= 0
    steps = []
    for t in range(max(map(len, table.paths))):
        a = tuple(p[min(t, len(p) - 1)] for p in table.paths)
        b = tuple(p[min(t + 1, len(p) - 1)] for p in table.paths)
        steps.append(tuple(next(act for act, q, _ in problem.moves(i, x) if q == y) for i, (x, y) in enumerate(zip(a, b))))
    from bille.heuristics.joint import to_result

    refined = to_result(inst, "lacam", "feasible", steps, stats={})
    assert validate(inst, refined.schedule).valid and sum_of_costs(inst, refined.schedule) == after


def test_robots_with_different_point_movesets_get_a_valid_schedule(tmp_path):
    # one robot may also step diagonally: the SUO paths on the other robots' neighbours would
    # send it where its own moves do not go (a RuntimeError from a StopIteration before)
    inst = make("\n".join(["TTTTTT"] * 6), [{"at": [0, 3], "moveset": diagonal_moveset(tmp_path)}, {"at": [2, 4]}, {"at": [2, 2]},
                                            {"at": [4, 4]}, {"at": [0, 0]}],
                moveset="point", collisions="classic", robot_goals=[[2, 4], [4, 2], [3, 2], [2, 2], [0, 0]])
    result = solve(inst, "lacam", time_limit=10)
    assert result.status in ("feasible", "optimal") and validate(inst, result.schedule).valid


def test_an_unreachable_goal_is_said_before_any_path_is_spread():
    # the SUO step reserved a table as long as the unreachable distance: MemoryError before
    inst = make("TT.TT\nTT.TT", [{"at": [0, 0]}, {"at": [4, 1]}], moveset="point", collisions="classic",
                robot_goals=[[4, 0], [3, 1]])
    result = solve(inst, "lacam", time_limit=10)
    assert result.status == "unsolved" and result.failure.text == "unreachable"


@pytest.mark.parametrize("collisions", ["classic", "bille"])
def test_no_robots_under_either_rule_is_solved_in_no_steps(collisions):
    # with Numba loaded (the compiled generator's condition), an empty fleet is done at once
    import numba  # noqa: F401 - loaded, as in a process that has compiled something

    inst = make("TTT\nT.T", [], moveset="point", collisions=collisions)
    found = solve(inst, "lacam")
    assert found.status in ("optimal", "feasible") and found.metrics.makespan == 0
    assert validate(inst, found.schedule).valid
