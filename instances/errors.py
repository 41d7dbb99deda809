"""The project's error taxonomy.

Every error a user can cause is a :class:`BilleError`; its message names the source (file, line,
field) and what was expected. The command line prints the message as one line and exits 2.
"""
from __future__ import annotations


class BilleError(Exception):
    """Base class of every error caused by bad input to bille. Its text is one line: a line
    break in a value it quotes is shown as ``\\n``, so the message is always one line.

    >>> str(BilleError("unknown moveset 'S7\\nTTT'"))
    "unknown moveset 'S7\\\\nTTT'"
    """

    def __str__(self) -> str:
        text = super().__str__()
        return text.replace("\r", "\\r").replace("\n", "\\n") if "\n" in text or "\r" in text else text


class MovesetError(BilleError):
    """A moveset file or name is malformed or unknown."""


class InstanceError(BilleError):
    """An instance file is malformed, or the instance breaks an instance validity rule."""


class ScheduleError(BilleError):
    """A schedule file is malformed or does not fit its instance."""


class OptionError(BilleError):
    """A solver or command option has a value that cannot work."""


def where(source: str | None, line: int | None = None, field: str | None = None) -> str:
    """Format an error location: ``file:line: field: ``, leaving out what is unknown.

    >>> where("a.yaml", 3, "robots[0].front")
    'a.yaml:3: robots[0].front: '
    >>> where(None, None, "grid")
    'grid: '
    """
    head = ""
    if source:
        head = source if line is None else f"{source}:{line}"
    elif line is not None:
        head = f"line {line}"
    parts = [p for p in (head, field) if p]
    return "".join(p + ": " for p in parts)
