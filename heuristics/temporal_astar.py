"""Temporal A*: prioritized planning in a receding time window (paper, Methods, "Temporal A*").

Symbols of the paper: ``H`` the time horizon (steps planned ahead), ``Q`` the priority queue
(robot ids, highest priority first), ``epsilon`` the heuristic weight.

Every step, the robots plan their next ``H`` moves one after another in the order of ``Q``
(:func:`~.spacetime.window`). A robot avoids the cells that higher-priority robots have planned
for each of the ``H`` steps; it sees lower-priority robots only at the first step (their current
feet), assuming that later they move out of the way. All robots then make the first move of
their plan, and the window recedes by one step.

One driver. Temporal A* is the reconfiguration loop (:mod:`.loop.reconfigure`) with this
planner as its motion layer (:class:`.loop.motion.TemporalAStar`); path planning is the loop
with no jobs. There it keeps the paper's rules when the robots are stuck: if a robot finds no
walk at all (not even waiting), it moves up one place in ``Q`` and the step is planned again; if
the robots come back to a joint state they were in before with the same ``Q``, they are going
round in circles, and the lowest-priority robot not at its goal moves up one place. Both count
against a budget of priority shifts; when it is spent, or the step bound is reached, the planner
gives up with status ``unsolved`` and the reason in the result's ``failure`` (``timeout`` when the
time limit ended it). Temporal A* is not complete: giving up is not a proof that no schedule
exists.
"""
from __future__ import annotations

from dataclasses import dataclass

from bille.instances import Instance, OptionError
from bille.instances.options import option, refuse
from bille.instances.run import Run

from .loop.loop_options import LoopOptions


# the longest window: with -H 10,000 compare-2 takes 1.5 s; -H 100,000 took 20 s for a 5 s limit
# and -H 1,000,000 ran past 120 s at 2.2 GB (one reservation set per step of the window, every step)
MAX_HORIZON = 10_000


@dataclass(frozen=True)
class Options(LoopOptions):
    """``epsilon``: heuristic weight of each robot's window search; ``horizon``: ``H``, the
    number of steps each robot plans ahead; ``max_shifts``: budget of priority shifts (default:
    4 m^2 for m robots; in the loop ``4 m^2 + 4 jobs``); ``shift_priorities``: False keeps ``Q``
    fixed (for comparison): a blocked robot then ends the run (path planning only);
    ``priorities``: the initial ``Q`` (default: robot ids in order). On a fixed structure
    ``max_steps`` defaults to 4 x the robots' summed distances to their goals, at least 100."""

    METHOD = "temporal-astar"
    epsilon: float = option(1.0, at_least=1,
                            help="weight of the heuristic in each robot's window search", aliases=("eps",))
    horizon: int = option(5, at_least=1, help="steps each robot plans ahead", aliases=("H",))
    max_shifts: int | None = option(None, at_least=0,
                                    help="priority shifts allowed (default: 4 m^2, in the loop 4 m^2 + 4 jobs)")
    shift_priorities: bool = option(True,
                                    help="false keeps the priorities fixed (for comparison): a blocked robot ends the "
                                         "run")
    priorities: list[int] | None = option(None, help="the initial priority order, robot ids (default: in order)")

    def check_instance(self, instance) -> None:
        """The loop's (:class:`LoopOptions`); ``priorities`` orders the instance's robots, and
        ``shift_priorities=false`` is for path planning only."""
        super().check_instance(instance)
        m = instance.num_robots
        if self.priorities is not None and sorted(self.priorities) != list(range(m)):
            raise OptionError(f"temporal-astar: priorities must order the robot ids 0..{m - 1}, got {self.priorities}")
        if instance.is_reconfiguration:
            refuse(self, ("shift_priorities",), "is for path planning only (the loop shifts priorities to get out of "
                                                "a circle)")

    def check(self) -> None:
        super().check()
        if self.horizon > MAX_HORIZON:
            raise OptionError(f"temporal-astar: horizon {self.horizon:,} is more than {MAX_HORIZON:,} steps: each step "
                              "plans a window that long for every robot (its memory and time grow with it; the "
                              "paper's windows are a few steps)")


def plan(instance: Instance, options: Options | None = None, run: Run | None = None):
    """Temporal A* (:class:`Options`, checked for the instance by ``solve()`` or the caller) on
    any instance: the reconfiguration loop with Temporal A* as its motion layer (module
    docstring). When the run's budget expires, status ``timeout`` (no run: no limit)."""
    from .loop import reconfigure

    return reconfigure.plan(instance, options or Options(), run, motion="temporal-astar", method="temporal-astar")
