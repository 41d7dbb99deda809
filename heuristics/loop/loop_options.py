"""The options of the reconfiguration loop (:mod:`.reconfigure`), shared by the methods that run
it on an instance that moves tiles (``temporal-astar``, ``mstar``, ``lacam``)."""
from __future__ import annotations

from dataclasses import dataclass

from bille.instances import OptionError
from bille.instances.options import MethodOptions, option


@dataclass(frozen=True)
class LoopOptions(MethodOptions):
    """``load_transfer`` and ``d_tr``: equations (1)-(3) of the paper (robots hand loads over
    within Manhattan distance ``d_tr``); ``max_steps``: the loop's step bound (default: ten
    times the summed Manhattan carries plus ``W + H`` per job, at least 200); ``active``: the
    robots that take jobs (default: all; the others only keep out of the way). For path
    planning ``max_steps`` is Temporal A*'s step bound, the others are not used, and ``active``
    is refused (:meth:`loop_only`)."""

    load_transfer: bool = option(False)
    d_tr: int = option(5, at_least=0)
    max_steps: int | None = option(None, at_least=0)
    active: list[int] | None = option(None)

    def loop_only(self) -> None:
        """Raise OptionError if ``active`` is given for path planning (it names robots that take
        jobs: there are none)."""
        if self.active is not None:
            raise OptionError(f"{self.METHOD}: active is for instances that move tiles (the reconfiguration loop)")


__all__ = ["LoopOptions"]
