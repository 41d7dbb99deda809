"""How large an instance this machine can hold: checked before anything large is allocated.

The pose tables (``posegraph``) grow with cells x headings x actions x collision cells; a grid
of a few million cells asks for gigabytes. The budget is half of what this process may use: the
smaller of the physical memory and an address-space limit (``ulimit -v``), or
``BILLE_MEMORY_GIB`` (GiB) when set. A grid over it is refused with one line that names the
sizes, before any table is built.
"""
from __future__ import annotations

import os
import resource
from typing import Callable

from .errors import BilleError, InstanceError
from .moveset import Moveset

GIB = 1 << 30
# joint actions tried between two looks at the clock in the searches over all robots at once:
# one state of m robots has up to (actions per robot)**m of them, millions from ten robots on
CHECK_EVERY = 4096


def mapped() -> int:
    """This process's address space in bytes (0 where /proc is missing)."""
    try:
        with open("/proc/self/status") as f:
            line = next(line for line in f if line.startswith("VmSize:"))
        return int(line.split()[1]) * 1024
    except (OSError, StopIteration):
        return 0


def address_room() -> float:
    """Bytes of address space this process may still map under its limit (``ulimit -v``, or the
    sweep's ``memory_limit``); infinite without a limit."""
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft in (resource.RLIM_INFINITY, -1):
        return float("inf")
    return soft - mapped()


def human(size: float) -> str:
    """Bytes as GiB, or MiB below one GiB."""
    return f"{size / GIB:.1f} GiB" if size >= GIB else f"{size / (1 << 20):.1f} MiB"


def memory_budget() -> int:
    """Bytes that one instance's tables may take (module docstring)."""
    env = os.environ.get("BILLE_MEMORY_GIB")
    if env:
        try:
            value = float(env)
        except ValueError:
            raise BilleError(f"BILLE_MEMORY_GIB: expected a number of GiB, got {env!r}") from None
        if not value > 0:
            raise BilleError(f"BILLE_MEMORY_GIB: expected a positive number of GiB, got {env!r}")
        return int(value * GIB)
    total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft not in (resource.RLIM_INFINITY, -1):
        total = min(total, soft)
    return total // 2


def table_bytes(moveset: Moveset, width: int, height: int) -> int:
    """An upper estimate of the bytes the pose tables of ``moveset`` on the grid take while
    they are built (int64 intermediates included)."""
    headings = 4 if moveset.footprint == "biped" else 1
    actions = len(moveset.actions)
    per = 0
    for a in moveset.actions:
        per = max(per, 6 + len(a.swept) + len(a.carried))
    return width * height * headings * actions * (per + 6) * 8


def check_budget(need: int, says: Callable[[str], str], error: type[BilleError] = InstanceError) -> None:
    """Raise ``error`` if ``need`` bytes exceed the budget: ``says(size)`` tells what needs that
    size, and the budget and how to set it follow."""
    budget = memory_budget()
    if need > budget:
        raise error(f"{says(human(need))}, more than the {human(budget)} this machine allows (BILLE_MEMORY_GIB sets it)")


def check_size(movesets, width: int, height: int, what: str = "the instance",
               error: type[BilleError] = InstanceError) -> None:
    """Raise ``error`` if the tables of the grid with these movesets exceed the budget."""
    need = sum(table_bytes(ms, width, height) for ms in {m.name: m for m in movesets}.values())
    check_budget(need, lambda size: f"{what}: a {width}x{height} grid needs about {size} for its pose tables", error)
