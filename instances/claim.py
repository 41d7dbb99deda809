"""What a result proves (docs/decisions.md, "Claims").

A result's status says whether it has a proof; its :class:`Claim` says of what: the objective
minimized, then over which schedules (every one, the walking-only ones, or a named class), and
the lower bound proved over them. One function renders a claim for each output: :meth:`Claim.text`
for the text, :meth:`Claim.to_json` for the JSON, :func:`status_key` for files (gap.csv, sweep
results) and :func:`shown_status` for the status a person reads. A file never says ``optimal`` for
an optimum of fewer schedules or of another objective than the makespan.
"""
from __future__ import annotations

from dataclasses import dataclass

OBJECTIVES = ("makespan", "sum-of-costs", "sum-of-loss")
WALKING = "walking only (no pick or place)"


@dataclass(frozen=True)
class Claim:
    """The objective and the schedules a result's proofs are about.

    ``objective``: one of :data:`OBJECTIVES`; ``then``: what is minimized next among its optima
    (``makespan``), or None. ``walking_only``: over the schedules that never pick or place.
    ``among``: a class of schedules in words ("the schedules that keep the structure"), with
    ``spelled``, how the options name it (``cells=keep``, ``keep_structure``); None for every
    schedule. ``bounds``: the class-bound key (:mod:`bille.solvers.bounds.classes`) that
    ``lower`` also bounds: the claim's class or one held by it. ``lower``: the objective's lower
    bound proved over these schedules, None where none was (the makespan over every schedule is
    the result's ``lower_bound``, never here).
    """

    objective: str = "makespan"
    then: str | None = None
    walking_only: bool = False
    among: str | None = None
    spelled: str | None = None
    bounds: str | None = None
    lower: int | None = None

    def __post_init__(self) -> None:
        if self.objective not in OBJECTIVES:
            raise ValueError(f"unknown objective {self.objective!r} (expected one of {OBJECTIVES})")

    @property
    def unconditional(self) -> bool:
        """The makespan over every schedule: what ``optimal`` means without a word more."""
        return self.objective == "makespan" and not self.walking_only and self.among is None

    @property
    def restricted(self) -> bool:
        """The makespan over fewer schedules than every one (walking only or a class)."""
        return self.objective == "makespan" and not self.unconditional

    def name(self) -> str:
        """The objective and its set, short: ``sum of costs over walking-only schedules``,
        ``makespan among the schedules that keep the structure``."""
        text = self.objective.replace("-", " ")
        if self.among is not None:
            text += f" among {self.among}"
        return text + (" over walking-only schedules" if self.walking_only else "")

    def text(self) -> str:
        """The whole claim in words, as ``bille solve`` prints it after ``objective:``."""
        text = self.objective.replace("-", " ") if self.objective != "sum-of-loss" else self.objective
        if self.then:
            text += f", then {self.then}"
        if self.walking_only:
            text += f", {WALKING}"
        if self.among is not None:
            text += f" among {self.among}" + (f" ({self.spelled})" if self.spelled else "")
        return text

    def to_json(self) -> dict:
        return {"objective": self.objective, "then": self.then, "walking_only": self.walking_only,
                "among": self.among, "spelled": self.spelled, "bounds": self.bounds, "lower": self.lower,
                "unconditional": self.unconditional, "text": self.text()}

    @classmethod
    def from_json(cls, data: dict | None) -> Claim:
        if not data:
            return cls()
        return cls(**{k: data.get(k) for k in ("objective", "then", "among", "spelled", "bounds", "lower")
                      if data.get(k) is not None}, walking_only=bool(data.get("walking_only")))


EVERY = Claim()


def status_key(status: str, claim: Claim | None) -> str:
    """The status as one word for files (gap.csv, sweep results): ``optimal`` only for the
    makespan over every schedule; another optimum says of what (``optimal-sum-of-costs-walking-only``,
    ``optimal-in-class``, ``optimal-walking-only``)."""
    if status != "optimal" or claim is None or claim.unconditional:
        return status
    parts = ["optimal"]
    if claim.among is not None:
        parts.append("in-class")
    elif claim.objective != "makespan":
        parts.append(claim.objective)
    if claim.walking_only:
        parts.append("walking-only")
    return "-".join(parts)


def base_status(key: str) -> str:
    """The status of a :func:`status_key` (``optimal-in-class`` → ``optimal``)."""
    return key.split("-", 1)[0]


def shown_status(status: str, claim: Claim | None) -> str:
    """The status as a person reads it: ``optimal`` names its claim where it is not the makespan
    over every schedule (``optimal (sum of costs over walking-only schedules)``)."""
    if status == "optimal" and claim is not None and not claim.unconditional:
        return f"optimal ({claim.name()})"
    return status
