"""Where the MovingAI maps shipped with bille are: a module of its own, light to import, for the
commands that name them (``bille list --maps``, ``bille gen movingai NAME``) and the benchmarks."""
from __future__ import annotations

from importlib import resources
from pathlib import Path

SCENARIO = "-random-1.scen"  # NAME.map is read with NAME-random-1.scen, or its one other scenario


def scenario_of(folder: Path, name: str) -> Path:
    """The scenario read with ``folder/name.map``: ``name-random-1.scen``, else the first
    ``name-*.scen`` by name (den312d ships with another one, see the README), else the
    ``random-1`` path (missing: the caller says so)."""
    first = folder / f"{name}{SCENARIO}"
    if first.is_file():
        return first
    others = sorted(folder.glob(f"{name}-*.scen"))
    return others[0] if others else first


def shipped_maps() -> Path:
    """The folder of the MovingAI maps and scenarios shipped with bille (see its README for their
    source and licence)."""
    return Path(str(resources.files("bille.tools.bench").joinpath("movingai")))
