"""First schedules from the heuristics, for the exact solvers and the anytime method to start from.

A schedule found here is an *upper* bound: it caps the makespan search and is what a solver
returns when its time runs out. Each candidate is checked by the validator before it is used, so
a heuristic's mistake can never become a claimed makespan.
"""
from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass

import numpy as np

from bille.heuristics import lacam, temporal_astar
from bille.heuristics.lacam import states as lacam_states

from bille.heuristics.loop import reconfigure
from bille.heuristics.loop.loop_options import LoopOptions
from bille.instances import Instance, OptionError
from bille.instances.metrics import makespan as ids_makespan
from bille.instances.run import Budget, Run
from bille.instances.schedule import Schedule, bind

from .compact import compact
from .validate import validate

# the heuristics tried for a first schedule, in order: path planning, each method with a share
# of the budget; reconfiguration, the loop with each motion layer, without and with load
# transfer, on the instance's tasks and then on a derived sequence (often much shorter than the
# paper's tasks: docs/decisions.md)
PATH_PLANNING = (("lacam", 0.5), ("temporal-astar", 0.5))
RECONFIGURATION = tuple((motion, transfer, sequence) for sequence in ("given", "derived")
                        for motion in ("temporal-astar", "lacam", "mstar") for transfer in (False, True))
RUN_SHARE = 0.25  # of the budget, at most, for one run of the loop
# with fewer robots taking jobs (:func:`fewer_robots`): the motion layers in the order they were
# measured to succeed there (Temporal A* also fails fastest)
FEWER = (("temporal-astar", True), ("temporal-astar", False), ("lacam", True), ("lacam", False),
         ("mstar", False), ("mstar", True))
EXHAUSTED = "the complete planner exhausted the reachable states"  # stats.reason of that proof


@dataclass
class Incumbent:
    """A validated schedule as action ids ``int64[m, makespan]`` (trailing waits trimmed)."""

    ids: np.ndarray
    makespan: int
    method: str


def from_schedule(instance: Instance, schedule: Schedule, method: str) -> Incumbent | None:
    """The schedule as an incumbent if it is valid for ``instance``, else None."""
    report = validate(instance, schedule)
    if not report.valid:
        return None
    makespan = report.metrics.makespan
    return Incumbent(bind(instance, schedule)[:, :makespan], makespan, method)


def first_schedule(instance: Instance, budget: Budget, improve: bool = True,
                   cut: list | None = None) -> Incumbent | None:
    """The shortest valid schedule the heuristics find within ``budget`` seconds, or None.

    Path planning: LaCAM* (complete on a fixed structure), improving for up to a quarter of the
    budget (at most 1 s) if ``improve``, then Temporal A*. Reconfiguration: the loop with each
    motion layer (Temporal A*, LaCAM*, M*), without and with load transfer, on the instance's
    tasks and on a derived sequence (:data:`RECONFIGURATION`), each run within a quarter of the
    budget. Each schedule is compacted (:mod:`.compact`) before they are compared (bridge-3:
    LaCAM*'s loop 70 steps, compacted 50). The runs that their share cut short (see
    :func:`retry`) are appended to ``cut``, if given, for :func:`retry`.
    """
    if instance.is_reconfiguration:
        runs = [(f"{m}{'+transfer' if t else ''}{'' if s == 'given' else '+derived'}", (m, t, s, None), RUN_SHARE)
                for m, t, s in RECONFIGURATION if s == "given" or instance.tasks is not None]
    else:
        runs = [(m, m, share) for m, share in PATH_PLANNING]
    return _portfolio(instance, runs, budget, improve, cut=cut)


def retry(instance: Instance, cut: list, budget: Budget) -> Incumbent | None:
    """The first valid schedule of the runs that :func:`first_schedule` cut short (``cut``: name,
    what to run, seconds it had), each given twice its last time in turn (rounds over the runs
    still cut, until one finds a schedule or ``budget`` ends), or None. A run is *cut short* when
    its time ran out between the loop's steps (``failure.kind`` ``time-limit``: it was still
    getting on); one that ends otherwise (a deadlock, no joint plan for one step within its time)
    is not tried again: more time rarely gives it a schedule and takes the complete planner's
    (docs/decisions.md). Example: on ``bille gen random --width 40 --height 40 --tiles 600
    --robots 6 --moved 30 --seed 1`` the loop with LaCAM* needs more than its share of the first
    schedule's budget, and nothing else finds a schedule."""
    pending, total = list(cut), budget.seconds()
    while pending and not budget.expired():
        name, how, had = pending.pop(0)
        left = budget.left()
        limit = min(left, 2 * had)
        found = _run(instance, how, budget.child(max(0.01, limit)), improve=False)
        if found is not None and found.schedule is not None:
            candidate = _compacted_result(instance, found, name, budget.child(_compact_s(total)))
            if candidate is not None:
                return candidate
        elif _cut_short(found) and limit < left:
            pending.append((name, how, limit))
    return None


def fewer_robots(instance: Instance, budget: Budget | None) -> Incumbent | None:
    """The first valid schedule the reconfiguration loop finds within ``budget`` seconds with
    fewer robots taking jobs (the loop's ``active``; the others only keep out of the way), or
    None: for when the loop with every robot finds none. On crowded maps the robots with jobs
    block one another where fewer get through (``bille gen random --robots 4 --moved 10 --seed
    6``: every run with all four robots deadlocks or finds no joint plan, three of them finish). Sets
    of ``m - 1`` robots first, then smaller; per size, each motion layer of :data:`FEWER` on
    every set before the next layer, each run within a quarter of the budget. The first schedule
    found is returned, compacted as in :func:`first_schedule`: runs that fail mostly take their
    whole share (a joint plan not found in time), so looking on for a shorter one costs the time
    in which the windows shorten the first. ``budget`` None (or one without a time limit): each run ends at the
    loop's own bounds (steps, priority shifts, the motion layers' expansions) and compaction at
    its fixed point, so the answer does not depend on the machine's speed."""
    m = instance.num_robots
    if not instance.is_reconfiguration or instance.collisions == "classic" or m < 2:
        return None
    runs = ((f"{motion}{'+transfer' if transfer else ''}+robots{','.join(map(str, active))}",
             (motion, transfer, "given", list(active)), RUN_SHARE)
            for k in range(m - 1, 0, -1) for motion, transfer in FEWER
            for active in itertools.combinations(range(m), k))
    return _portfolio(instance, runs, budget or Budget(), improve=False, first=True)


def compacted(instance: Instance, found: Incumbent, budget: Budget | None) -> Incumbent:
    """``found`` with its actions as early as they go (:mod:`.compact`, within ``budget``), if that
    is shorter and valid."""
    ids = compact(instance, found.ids, budget)
    if ids.shape[1] >= found.makespan:
        return found
    return from_schedule(instance, Schedule.from_ids(instance, ids), found.method) or found


def to_cap(instance: Instance, given: Schedule | None, budget: Budget,
           method: str) -> tuple[Incumbent | None, bool]:
    """The exact solvers' first schedule, a cap on their horizons and a fallback: the one
    ``given`` (which must be valid), else the heuristics' in a twentieth of the time left (at
    most 1 s: refuting an infeasible instance need not wait for heuristics that cannot succeed),
    else the loop's with fewer robots (:func:`fewer_robots`) in as long, else the complete
    planner's in a tenth. Also whether the complete planner proved that no
    schedule exists (see :func:`complete_search`)."""
    if given is not None:
        found = from_schedule(instance, given, "given")
        if found is None:
            raise OptionError(f"{method}: the incumbent schedule is not valid for instance "
                              f"'{instance.name}' (bille check says why)")
        return found, False
    limited = budget.seconds() is not None
    seconds = max(0.01, min(1.0, 0.05 * budget.left()))  # 1 s without a limit
    found = first_schedule(instance, budget.child(seconds), improve=False)  # a cap: the proof follows
    found = found or fewer_robots(instance, budget.child(seconds))
    if found is not None or not limited:
        return found, False
    return complete_search(instance, budget.child(max(0.01, 0.1 * budget.left())))


def complete_search(instance: Instance, budget: Budget) -> tuple[Incumbent | None, bool]:
    """A first schedule from the complete planner, for when the heuristics found none: LaCAM*
    over whole states (:mod:`bille.heuristics.lacam.states`), after LaCAM* on the fixed
    structure on path planning (a walking schedule, found faster where one exists). Returns the
    validated schedule or None, and whether the search proved that no schedule exists (it
    exhausted the space of whole states; a walking search that fails proves nothing, since
    robots may move tiles aside).
    """
    compact_s = max(0.05, min(2.0, 0.1 * budget.left()))  # its schedules are mostly waits
    if not instance.is_reconfiguration:
        found = lacam.plan(instance, lacam.Options(improve=0.0), Run(budget))
        if found.schedule is not None:
            return _compacted_result(instance, found, "lacam", budget.child(compact_s)), False
    if instance.collisions == "classic" or budget.expired():
        return None, False
    found = lacam_states.plan(instance, run=Run(budget))
    if found.schedule is not None:
        return _compacted_result(instance, found, "lacam-states", budget.child(compact_s)), False
    return None, found.status == "infeasible"


def _compacted_result(instance: Instance, found, method: str, budget: Budget) -> Incumbent | None:
    """A planner's result as a compacted incumbent (:func:`compacted`, within ``budget``), or None
    if its schedule is not valid."""
    candidate = from_schedule(instance, found.schedule, method)
    return candidate and compacted(instance, candidate, budget)


def _portfolio(instance: Instance, runs, budget: Budget, improve: bool, first: bool = False,
               cut: list | None = None) -> Incumbent | None:
    """The shortest valid schedule (the first one, if ``first``) of the ``runs`` (name, what to
    run for :func:`_run`, share of the budget) within ``budget``, each compacted; the runs that ran
    out of their time go to ``cut`` (name, what to run, seconds), if given."""
    total = budget.seconds()  # None: the runs' own bounds end them (see fewer_robots)
    best = None
    for name, how, share in runs:
        if budget.expired():
            break
        limit = None if total is None else max(0.01, min(budget.left(), share * total))
        found = _run(instance, how, budget.child(limit), improve)
        if found is None:
            continue
        if found.schedule is None:
            if cut is not None and _cut_short(found):
                cut.append((name, how, limit))
            continue
        candidate = _compacted_result(instance, found, name, budget.child(_compact_s(total)))
        if candidate is not None and (best is None or candidate.makespan < best.makespan):
            best = candidate
            if first:
                break
    return best


def _cut_short(found) -> bool:
    """Whether a run without a schedule ended because its time ran out between the loop's steps
    (see :func:`retry`)."""
    return found is not None and found.failure is not None and found.failure.kind == "time-limit"


def _compact_s(budget: float | None) -> float | None:
    """Seconds to compact one schedule found within ``budget`` (None: to the fixed point)."""
    return None if budget is None else max(0.01, min(0.5, 0.1 * budget))


def _run(instance: Instance, how, budget: Budget, improve: bool):
    if instance.is_reconfiguration:
        if instance.collisions == "classic":
            return None
        motion, transfer, sequence, active = how
        if sequence == "derived":
            instance = dataclasses.replace(instance, tasks=None)
        return reconfigure.plan(instance, LoopOptions(load_transfer=transfer, active=active), Run(budget),
                                motion=motion)
    if how == "lacam":
        return lacam.plan(instance, lacam.Options(improve=min(1.0, budget.left() / 2) if improve else 0.0), Run(budget))
    if instance.collisions == "classic":
        return None
    return temporal_astar.plan(instance, run=Run(budget))


def makespan_of(instance: Instance, ids: np.ndarray) -> int:
    """The makespan of an action-id matrix (its last step in which some robot does not wait)."""
    return ids_makespan(instance, ids)
