"""The options of the reconfiguration loop (:mod:`.reconfigure`), shared by the methods that run
it on an instance that moves tiles (``temporal-astar``, ``mstar``, ``lacam``)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from bille.instances.errors import OptionError
from bille.instances.options import MethodOptions, option, refuse


@dataclass(frozen=True)
class LoopOptions(MethodOptions):
    """``load_transfer`` and ``d_tr``: equations (1)-(3) of the paper (robots hand loads over
    within Manhattan distance ``d_tr``); ``max_steps``: the loop's step bound (default: ten
    times the summed Manhattan carries plus ``W + H`` per job, at least 200); ``active``: the
    robots that take jobs (default: all; the others only keep out of the way). For path
    planning ``max_steps`` is Temporal A*'s step bound, the others are not used, and ``active``
    is refused (:meth:`check_instance`).

    The loop also reads ``epsilon``, ``horizon``, ``max_shifts``, ``priorities`` and
    ``shift_priorities``: options of the methods that have them (Temporal A*, M*), the defaults
    below for the others."""

    epsilon: ClassVar[float] = 1.0
    horizon: ClassVar[int] = 5
    max_shifts: ClassVar[int | None] = None  # default: 4 m^2 + 4 jobs
    priorities: ClassVar[list[int] | None] = None  # default: robot ids in order
    shift_priorities: ClassVar[bool] = True

    load_transfer: bool = option(False,
                                 help="robots hand loads over to one another (paper, equations 1-3); instances that "
                                      "move tiles")
    d_tr: int = option(5, at_least=0,
                       help="Manhattan distance within which two robots consider a hand-over (with load_transfer)")
    max_steps: int | None = option(None, at_least=0,
                                   help="the loop's step bound (default: 10x the summed carries plus W+H per job, at "
                                        "least 200)")
    active: list[int] | None = option(None,
                                      help="the robots that take jobs (default: all; the others keep out of the way); "
                                           "instances that move tiles")

    def check_instance(self, instance) -> None:
        """``load_transfer``, ``d_tr`` and ``active`` are the reconfiguration loop's: refused on
        an instance that moves no tiles; ``active`` names robots the instance has."""
        if not instance.is_reconfiguration:
            refuse(self, ("load_transfer", "d_tr", "active"),
                   f"works in the reconfiguration loop only, and {instance.name or 'the instance'} moves no tiles")
        m = instance.num_robots
        if self.active is not None and (not self.active or not all(0 <= i < m for i in self.active)):
            raise OptionError(f"{self.METHOD}: active must name some of the robot ids 0..{m - 1}, got {self.active!r}")


__all__ = ["LoopOptions"]
