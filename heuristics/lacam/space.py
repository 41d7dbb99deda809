"""LaCAM*'s search space on a fixed structure: the configurations of a :class:`JointProblem` (one
pose per robot), their generator (:mod:`.pibt`), the step cost and admissible estimate of the
objective, and under classic collisions the SUO paths (:mod:`.scatter`) and their refinement
(:mod:`.refine`). The search itself is :func:`.search.search`."""
from __future__ import annotations

import random

import numpy as np

from bille.instances.jit import loaded
from bille.instances.run import Budget

from ..joint import JointProblem
from .pibt import Bille, Classic
from .refine import Paths, refine_once
from .scatter import COMPILED_FROM, scatter

SCATTER_MARGIN = 10  # steps an SUO path may take beyond the shortest (lacam3's default)
Poses = tuple[int, ...]


class PoseSpace:
    """The configurations of :class:`JointProblem` (one pose per robot) as LaCAM*'s search space:
    its generator (:mod:`.pibt`), its objective's step cost and admissible estimate."""

    def __init__(self, problem: JointProblem, objective: str, rng: random.Random, pinned: dict) -> None:
        self.problem, self.pinned = problem, pinned
        self.m = len(problem.walks)
        self.makespan = objective == "makespan"
        self.classic = problem.instance.collisions == "classic"
        self.refining = False  # no refinement (:meth:`refine`) until the SUO paths are set
        # the SUO paths and their refinement walk on one set of neighbours, so only where every
        # robot walks alike (one moveset, one load): another robot's moves may not be among them
        self.alike = len({id(w) for w in problem.walks}) <= 1
        large = self.m > 0 and self.m * problem.walks[0].succ.shape[0] >= COMPILED_FROM
        # the same configurations compiled, where Numba is worth loading (0.3 s) or loaded
        self.compiled = self.classic and self.alike and self.m > 0 and (large or loaded())
        if self.compiled:
            from .pibt_compiled import CompiledClassic

            self.generator = CompiledClassic(problem, rng)
            self._rows = np.arange(self.m)
        else:
            self.generator = (Classic if self.classic else Bille)(problem, rng)

    def spread(self, budget: Budget, seed: int) -> None:
        """Classic collisions: the generator prefers each robot's next cell on its SUO path
        (:mod:`.scatter`), planned within ``budget``; and the search may
        refine its schedules (:meth:`refine`)."""
        problem = self.problem
        self.goal_poses = [int(w.goal_poses(c)[0]) for w, c in zip(problem.walks, problem.goals)]
        if self.compiled:  # Numba loaded, the distances stacked: the compiled table reads their rows
            dists, arrays, compiled = problem.dist_table, None, True
        else:
            dists, arrays, compiled = problem.dist_lists, problem.dists, None
        self.generator.prefer = scatter(self.generator.nbrs, dists, list(problem.start), self.goal_poses,
                                        margin=SCATTER_MARGIN, budget=budget, seed=seed, arrays=arrays,
                                        compiled=compiled)
        self.refining = None

    def refine(self, configs: list[Poses] | None, rng: random.Random, budget: Budget) -> list[Poses] | None:
        """One neighbourhood of :mod:`.refine` on the best schedule (``configs``, given when it
        changed since the last call): the improved configurations, or None."""
        goals = self.goal_poses
        if configs is not None:
            paths = []
            for i, goal in enumerate(goals):
                end = len(configs) - 1
                while end > 0 and configs[end - 1][i] == goal:
                    end -= 1
                paths.append([c[i] for c in configs[:end + 1]])
            self.refining = Paths(paths, len(self.generator.nbrs))
        if not refine_once(self.refining, self.generator.nbrs, self.problem.dist_lists, goals, rng, budget):
            return None
        paths = self.refining.paths
        return [tuple(p[min(t, len(p) - 1)] for p in paths) for t in range(max(map(len, paths)))]

    def actions(self, a: Poses, b: Poses) -> tuple[int, ...]:
        """The joint action from configuration ``a`` to ``b``."""
        moves = self.problem.moves
        return tuple(next(act for act, q, _ in moves(i, p) if q == r) for i, (p, r) in enumerate(zip(a, b)))

    def start(self) -> Poses:
        return tuple(self.problem.start)

    def unreachable(self) -> list[int]:
        return self.problem.unreachable()

    def branches(self, config: Poses, forced: tuple, i: int) -> list[int]:
        """Robot ``i``'s moves that a constraint may add to ``forced`` (the others cannot be
        completed to a configuration, nor can any constraint that extends them)."""
        return self.generator.compatible(config, forced, i)

    def generate(self, config: Poses, order: list[int], forced: tuple, first: bool):
        return self.generator.generate(config, order, forced, self.pinned if first else {})

    # with the compiled generator, the same values read from the stacked tables (no lists made)
    def is_goal(self, config: Poses) -> bool:
        if self.compiled:
            return bool(self.problem.home_table[self._rows, config].all())
        return self.problem.is_goal(config)

    def resting_all(self, config: Poses) -> list[bool]:
        if self.compiled:
            return self.problem.home_table[self._rows, config].tolist()
        return [home[p] for home, p in zip(self.problem.home_lists, config)]

    def first_priorities(self, config: Poses) -> list[float]:
        if self.compiled:
            return (self.problem.dist_table[self._rows, config] / 10_000).tolist()
        return [d[p] / 10_000 for d, p in zip(self.problem.dist_lists, config)]

    def h(self, config: Poses) -> int:
        if self.compiled:
            ds = self.problem.dist_table[self._rows, config]
            return int(ds.max()) if self.makespan else int(ds.sum())
        ds = [d[p] for d, p in zip(self.problem.dist_lists, config)]
        return max(ds, default=0) if self.makespan else sum(ds)

    def cost(self, a: Poses, b: Poses) -> int:
        if self.makespan:
            return 1
        if self.compiled:
            a, b = np.asarray(a), np.asarray(b)
            return int(((a != b) | ~self.problem.home_table[self._rows, b]).sum())
        return sum(1 for home, p, q in zip(self.problem.home_lists, a, b) if not (p == q and home[q]))


__all__ = ["PoseSpace", "SCATTER_MARGIN"]
