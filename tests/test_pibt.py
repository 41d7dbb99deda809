"""LaCAM*'s configuration generators (PIBT under the Bill-E rule and under classic collisions):
what a push achieves, and which constraints the search may skip."""
from random import Random

import pytest

from bille.heuristics.joint import JointProblem
from bille.heuristics.lacam.pibt import Bille, Classic, next_configuration, next_priorities
from helpers import make
from test_lacam import TINY


def test_a_pushed_biped_with_both_feet_in_the_way_leaves_in_two_steps():
    # robot 0 heads east against a wall and must turn right (south), a turn that sweeps both feet
    # of robot 1 (heading west): every move of a biped keeps one foot down, so robot 1 needs two
    # steps to clear the way, and it does them although they take it no closer to its own goal
    inst = make("""
        TTTTTT
        TTT.TT
        TTTTTT
        TTTTTT
        TTTTTT""", [{"front": [2, 1], "back": [1, 1]}, {"front": [1, 2], "back": [2, 2]}],
                robot_goals=[[2, 4], [1, 0]])
    problem = JointProblem.of(inst, "lacam")
    config, priority = tuple(problem.start), [2.0, 1.0]
    for step in range(8):
        order = sorted(range(2), key=lambda i: -priority[i])
        _, config = next_configuration(problem.walks, problem.dist_lists, config, order, {}, Random(0))
        priority = next_priorities(priority, [problem.at_goal(i, p) for i, p in enumerate(config)])
        if problem.is_goal(config):
            break
    assert problem.is_goal(config), f"robots still {[problem.dist_lists[i][p] for i, p in enumerate(config)]} away"
    assert step + 1 <= 6


@pytest.mark.parametrize("inst", TINY[:30], ids=lambda inst: inst.name)
def test_constraints_skipped_by_the_search_can_never_be_completed(inst):
    # the search adds to a constraint only the moves that compatible() keeps; every other move
    # must make the generator fail, whatever else is forced (else completeness would be lost)
    problem = JointProblem.of(inst, "lacam")
    make_generator = Classic if inst.collisions == "classic" else Bille
    generator = make_generator(problem, Random(0))
    config = tuple(problem.start)
    order = list(range(inst.num_robots))
    for first in range(len(problem.moves(0, config[0]))):
        forced = ((0, first),)
        if generator.generate(config, order, forced, {}) is None:
            continue
        for i in order[1:]:
            keep = set(generator.compatible(config, forced, i))
            for k in range(len(problem.moves(i, config[i]))):
                if k not in keep:
                    assert generator.generate(config, order, forced + ((i, k),), {}) is None
