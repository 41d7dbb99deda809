"""Instances shipped with bille (``instances/bundled/``), each with a known valid schedule.

Commands take a file path or, where no such file exists, a bundled name: ``corridor-2`` is the
instance ``bundled/corridor-2.yaml`` and ``corridor-2.schedule`` its schedule.
"""
from __future__ import annotations

from importlib import resources
from pathlib import Path

from .errors import BilleError

SCHEDULE_SUFFIX = ".schedule"


def _folder() -> Path:
    return Path(str(resources.files(__package__).joinpath("bundled")))


def bundled_names() -> list[str]:
    """Names of the bundled instances, sorted."""
    return sorted(p.stem for p in _folder().glob("*.yaml") if not p.stem.endswith(SCHEDULE_SUFFIX))


def bundled_path(name: str) -> Path:
    """Path of a bundled instance (``name``) or schedule (``name.schedule``)."""
    path = _folder() / f"{name}.yaml"
    if not path.is_file():
        raise BilleError(f"no bundled instance or schedule named '{name}' (bundled: {', '.join(bundled_names())})")
    return path


def resolve(arg: str, error: type[BilleError] = BilleError) -> Path:
    """A user's argument as a path: the file if it exists, else the bundled file of that name."""
    path = Path(arg)
    if path.exists():
        return path
    name = arg[:-5] if arg.endswith(".yaml") else arg
    if "/" not in name and (_folder() / f"{name}.yaml").is_file():
        return _folder() / f"{name}.yaml"
    import difflib

    names = bundled_names()
    close = difflib.get_close_matches(name, names, n=1, cutoff=0.6) if "/" not in name else []
    hint = f"; did you mean '{close[0]}'?" if close else ""
    raise error(f"{arg}: no such file or bundled name{hint} (bundled: {', '.join(names)})")
