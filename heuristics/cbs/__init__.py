"""Conflict-based search: optimal path planning for classic and Bill-E robots.

CBS (Sharon, Stern, Felner, Sturtevant, AIJ 2015) with the improvements of CBSH2-RTC (Li, Harabor,
Stuckey, Koenig, AIJ 2021): conflicts prioritized by multi-valued decision diagrams (cardinal
first), bypassing, the WDG admissible heuristic, target reasoning, and, for point robots under
classic collisions, rectangle and corridor reasoning; and bounded-suboptimal focal search in the
manner of ECBS, or of EECBS's explicit estimation (Li, Ruml, Koenig, AAAI 2021), with its proved
lower bound.

Modules: :mod:`.constraints` (what a branch forbids), :mod:`.lowlevel` (space-time A* and MDDs),
:mod:`.conflicts` (the two collision rules as conflicts and branches), :mod:`.rectangle` and
:mod:`.corridor` (the symmetry splits, with their proofs), :mod:`.cover` (vertex covers for the
admissible heuristics), :mod:`.frontier` (which node comes next), :mod:`.search` (the constraint
tree), :mod:`.classic` (numpy tables for many point robots), :mod:`.method` (options, proofs, the
result).
"""
from .method import plan

__all__ = ["plan"]
