"""Lower bounds on the makespan: the static bound of every schedule (:mod:`.static`: robots'
goals, manipulations, carrying, :mod:`.crossings`, the routing program :mod:`.routing` and its
scaffold scenarios :mod:`.scaffold`, over the relaxed graphs of :mod:`.ground`), and the bounds
of the classes of schedules (:mod:`.classes`)."""
from .static import Bounds, lower_bound

__all__ = ["Bounds", "lower_bound"]
