"""Every method on generated instances of each family (classic and Bill-E, mixed movesets,
unreachable goals, one to a thousand robots) with a 2 s limit: an answer or one clear error,
never a crash; a schedule, when there is one, valid."""
from __future__ import annotations

import pytest

from bille.instances import BilleError
from bille.instances.result import STATUSES
from bille.solvers import METHODS, solve, validate
from helpers import diagonal_moveset, make
from tinyworlds import tiny_instances


def families(tmp_path) -> dict:
    many = [{"at": [x, y]} for y in range(0, 64, 2) for x in range(0, 64, 2)][:1000]
    return {
        "classic, unreachable goal": make("TT.TT\nTT.TT", [{"at": [0, 0]}, {"at": [4, 1]}], moveset="point",
                                          collisions="classic", robot_goals=[[4, 0], [3, 1]]),
        "classic, mixed movesets": make("\n".join(["TTTTTT"] * 6), [{"at": [0, 3], "moveset": diagonal_moveset(tmp_path)},
                                                                   {"at": [2, 4]}, {"at": [4, 4]}],
                                        moveset="point", collisions="classic",
                                        robot_goals=[[2, 4], [4, 2], [2, 2]]),
        "bille, tiny reconfiguration": tiny_instances(1, first_seed=7)[0],
        "bille, a goal beyond the tiles": make("TTT\n...", [{"at": [0, 0]}], moveset="point", goal="...\nTTT",
                                               robot_goals=[[2, 1]]),
        "classic, a thousand robots": make("\n".join(["T" * 64] * 64), many, moveset="point", collisions="classic",
                                           robot_goals=[[r["at"][0] + 1, r["at"][1]] for r in many]),
    }


@pytest.mark.slow
def test_every_method_answers_every_family(tmp_path):
    for name, inst in families(tmp_path).items():
        for method in METHODS:
            try:
                result = solve(inst, method, time_limit=2)
            except BilleError as error:  # one clear line: the method does not apply, and says why
                assert str(error) and "\n" not in str(error), (name, method)
                continue
            assert result.status in STATUSES and result.status != "error", (name, method, result.stats)
            if result.schedule is not None:
                assert validate(inst, result.schedule).valid, (name, method)
