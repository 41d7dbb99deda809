"""The counts a method keeps that tools read, as typed fields of its result
(:attr:`bille.instances.result.Result.counters`; docs/decisions.md, "Claims").

A method keeps its counts in its ``stats`` (they go out with the JSON as they are); these are
the ones the tools compare across runs and methods, read through one typed record instead of by
their keys, so a count of the wrong type is a bug found where it is read, not a blank column.
Each is None where the method keeps no such count.
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass, fields


@dataclass(frozen=True)
class Counters:
    # the searches
    expanded: int | None = None  # states expanded (A*, M*, CBS's constraint tree, the loop's plans)
    nodes: int | None = None  # LaCAM*'s search nodes (configurations)
    states: int | None = None  # joint states stored (bfs)
    cuts: int | None = None  # constraints added lazily (the exact models' lazy connectivity)
    sum_of_costs: int | None = None  # the sum of costs the search reached (A*, M*, CBS, ...)
    first_s: float | None = None  # seconds to LaCAM*'s first schedule
    scatter_s: float | None = None  # seconds of LaCAM*'s SUO paths
    # the reconfiguration loop (docs/load-transfer.md)
    jobs: int | None = None  # jobs handed to the robots
    steps: int | None = None  # steps planned
    priority_shifts: int | None = None
    relays: int | None = None  # load transfers: a tile handed over
    swaps: int | None = None  # load transfers: two robots' jobs exchanged
    pairs_considered: int | None = None  # robot pairs within d_tr considered for a transfer
    plan_ms_mean: float | None = None  # milliseconds to plan a step, mean and largest
    plan_ms_max: float | None = None

    @classmethod
    def of(cls, stats: dict) -> Counters:
        """The counts of ``stats``; raises TypeError naming a count of the wrong type."""
        found = {}
        for f in fields(cls):
            value = stats.get(f.name)
            if value is None:
                continue
            real = "float" in f.type  # NumPy's numbers count as numbers (numbers.Integral, numbers.Real)
            if isinstance(value, bool) or not isinstance(value, numbers.Real if real else numbers.Integral):
                raise TypeError(f"stats[{f.name!r}] = {value!r}: expected {'a number' if real else 'a whole number'}")
            if not real:
                found[f.name] = int(value)
            else:
                found[f.name] = value if isinstance(value, (int, float)) else float(value)
        return cls(**found)


KEYS = tuple(f.name for f in fields(Counters))
