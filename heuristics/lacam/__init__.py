"""LaCAM*, complete and anytime (Okumura, AAAI 2023, IJCAI 2023; the engineering of lacam3,
AAMAS 2024): the search over configurations (:mod:`.search`, the method's entry :func:`plan` and
its :class:`Options`), its space on a fixed structure (:mod:`.space`) and over whole states
with tiles (:mod:`.states`), the configuration generator PIBT (:mod:`.pibt`), the SUO paths
(:mod:`.scatter`, compiled in :mod:`.scatter_compiled`) and the refinement of a schedule while
improving (:mod:`.refine`)."""
from .search import OBJECTIVES, Options, joint_plan, plan

__all__ = ["OBJECTIVES", "Options", "joint_plan", "plan"]
