"""Where the MovingAI maps shipped with bille are: a module of its own, light to import, for the
commands that name them (``bille list --maps``, ``bille gen movingai NAME``) and the benchmarks."""
from __future__ import annotations

from importlib import resources
from pathlib import Path

SCENARIO = "-random-1.scen"  # NAME.map is read with NAME-random-1.scen


def shipped_maps() -> Path:
    """The folder of the MovingAI maps and scenarios shipped with bille (see its README for their
    source and licence)."""
    return Path(str(resources.files("bille.tools.bench").joinpath("movingai")))
