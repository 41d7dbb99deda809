"""Anytime certified solving: the method (:mod:`.method`), the bracket of best schedule and proved
bound (:mod:`.bracket`), the bound search (:mod:`.rise`) and the neighbourhood search
(:mod:`.windows`)."""
from .method import AnytimeOptions, plan

__all__ = ["AnytimeOptions", "plan"]
