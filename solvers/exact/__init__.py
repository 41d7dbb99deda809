"""Optimal makespan by the time-expanded encodings: the methods ``cpsat`` and ``sat``
(:mod:`.method`), the state of one search (:mod:`.search`), horizons one at a time
(:mod:`.horizons`) or side by side (:mod:`.lanes`)."""
from .method import CpsatOptions, SatOptions, plan_cpsat, plan_sat

__all__ = ["CpsatOptions", "SatOptions", "plan_cpsat", "plan_sat"]
