"""``bfs``: the exhaustive joint search, optimal with proof within a class of schedules.

Breadth-first over joint states (every robot's pose and load, the tiles on the cells the class
allows to change), compiled (:mod:`.joint.search`): the first goal state found gives the class's
optimal makespan; a search that stops early has proved the class's optimum above the depth it
finished. ``cells`` names the class (:mod:`.joint.cells`): ``all`` (the default) searches every
schedule, so its optimum and its bound are the instance's; ``keep`` and ``no-scaffold`` search
far fewer states and prove the optimum *of that class*, which the result names (``stats.class``
and the result's ``claim``) and never gives as the instance's ``lower_bound``. ``add_cells`` widens
a class by listed cells.

With ``incumbent`` (a schedule known, ``bille solve --incumbent``), only schedules shorter than it
are searched, with an admissible bound cutting states that cannot lead to one (:mod:`.joint.search`):
an exhausted search proves the incumbent optimal (within the class, when it belongs to it).

``engine=python`` runs the pure-Python twin (:mod:`.bfs_python`, every schedule only), the
reference the compiled search is tested against.

>>> from bille.instances import instance_from_text
>>> inst = instance_from_text("grid: |\\n  TTT\\nmoveset: point\\nrobots: [{at: [0, 0]}]\\nrobot_goals: [[2, 0]]")
>>> found = plan(inst)
>>> found.status, found.lower_bound, found.schedule.actions
('optimal', 2, (('east', 'east'),))
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from bille.instances import Instance, OptionError
from bille.instances.claim import EVERY, Claim
from bille.instances.failure import cap, no_schedule
from bille.instances.limits import address_room, human, memory_budget
from bille.instances.options import MethodOptions, option
from bille.instances.result import Result
from bille.instances.run import INTERRUPTED, TIME_LIMIT, Run
from bille.instances.schedule import Schedule, bind

from .joint.cells import CLASS_KEYS, KINDS, Cells, cells_of


# estimated joint states up to which engine=auto runs the Python twin: crowded-2 (1.8 x 10^4,
# 133 states stored) takes it 0.004 s, the compiled search 0.5 s with its loading
PYTHON_SMALL = 50_000
# with deepen, the plain search's time before it deepens: this share of the time limit, and at
# least PLAIN_MIN seconds (up to half of the limit), where the classes whose bound is far below
# their optimum are decided (lt-1's keep class: 1.4-2.2 s)
PLAIN_SHARE, PLAIN_MIN = 0.05, 5.0
# the abstraction's share of the time left at most: where it is not built in time, the search goes
# on unguided with the rest (lt-5's keep class: 66 s to build, then decided in 11 s)
BUILD_SHARE = 0.5


@dataclass(frozen=True)
class Options(MethodOptions):
    """``cells``: the class of schedules searched (``keep``: only the cells where the start and
    the goal differ change; ``no-scaffold``: only cells where either has a tile; ``all``: every
    schedule). ``add_cells``: ``[[x, y], ...]`` cells added to the class. ``incumbent``: a schedule
    to search below. ``max_steps``: depth cap (none: until the goal, the time limit or the state
    cap). ``max_states``: states stored at most (none: as many as fit in the memory allowed,
    ``BILLE_MEMORY_GIB``). ``engine``: ``compiled``, ``python`` for the reference twin (every
    schedule only, no incumbent), or ``auto``: the twin where it searches every schedule of a
    joint state space estimated at most :data:`PYTHON_SMALL` (:func:`.auto.joint_states`; loading
    the compiled code takes about 0.4 s, more than the twin needs there), compiled otherwise.
    ``direction``: ``forward`` from the start, ``both`` from the start and back from the goal
    states (:mod:`.joint.bidirectional`), ``auto`` both where the goal states can be listed and no
    incumbent is given (its pruning works forward). ``deepen``: where no incumbent is given and the
    search has not decided in a share of the time limit (:data:`PLAIN_SHARE`), search below a
    rising bound with the rest (:func:`.joint.search.deepen`): that decides classes whose bound is
    close to their optimum (short schedules of several robots) and slows the others down.
    ``abstraction``: for ``keep`` and ``no-scaffold`` (widened or not), the exact distances of a
    coarser world where each group of cells keeps only its count of tiles
    (:mod:`.joint.abstraction`), built once where it fits and within half the time left
    (:data:`BUILD_SHARE`; else the search goes on without them); the search then deepens from
    their bound at the start, below the incumbent if one is given (the direction ``both``,
    asked for, goes without them)."""

    METHOD = "bfs"
    cells: str = option("all", choices=KINDS,
                        help="the class searched: keep (cells where start and goal differ), no-scaffold (where either "
                             "has a tile), all")
    add_cells: list[list[int]] | None = option(None, help="[[x, y], ...]: cells added to the class")
    incumbent: Schedule | None = option(None, help="a schedule to search below (--incumbent FILE)")
    max_steps: int | None = option(None, at_least=0,
                                   help="depth cap (none: until the goal, the time limit or the state cap)")
    max_states: int | None = option(None, at_least=1,
                                    help="states stored at most (none: what fits in the memory allowed, "
                                         "BILLE_MEMORY_GIB)")
    engine: str = option("auto", choices=("auto", "compiled", "python"),
                         help="compiled, python (the reference twin: every schedule only) or auto (the twin on tiny "
                              "spaces)")
    direction: str = option("auto", choices=("auto", "forward", "both"),
                            help="forward, both (also back from the goal states) or auto (both where they can be "
                                 "listed)")
    abstraction: bool = option(True, help="keep and no-scaffold classes: guide the search by an abstraction's exact "
                                          "distances (robots exact, tiles counted per group of cells), where it fits")
    deepen: bool = option(False, help="without an incumbent, when the plain search has not decided in 5 % of the time "
                                      "limit (at least 5 s): search below a rising bound with the rest")

    @property
    def plain(self) -> bool:
        """Whether the options ask for nothing but the Python twin's search: every schedule from scratch."""
        return self.cells == "all" and not self.add_cells and self.incumbent is None

    def check(self) -> None:
        if self.engine == "python" and not self.plain:
            raise OptionError("bfs: engine python searches every schedule from scratch; cells, add_cells and "
                              "incumbent need engine compiled")


def plan(instance: Instance, options: Options | None = None, run: Run | None = None) -> Result:
    """The optimum of the class ``options.cells`` with its proof (module docstring), or what was
    proved when the run's budget, the state cap or the depth cap stopped the search.

    Statuses: ``optimal`` (of the class: the result's ``claim`` names it unless the class is
    ``all``); ``infeasible`` (``all`` exhausted: no schedule exists); ``feasible`` (the incumbent,
    outside the class, and no shorter schedule in it); ``unsolved`` (a class without schedules
    below the incumbent or at all, or a cap reached); ``timeout``; ``interrupted``. The bound a
    stopped search proved is the result's ``lower_bound`` for ``all``, and ``stats.class.lower_bound``
    for a class (and the claim's ``lower``)."""
    options = options or Options()
    run = run or Run()
    if options.engine == "python" or (options.engine == "auto" and options.plain and _tiny(instance)):
        from . import bfs_python

        return bfs_python.plan(instance, options, run)
    from .joint.search import bytes_per_state, search
    from .joint.tables import compile_tables

    budget = run.budget.child()
    cells = cells_of(instance, options.cells, options.add_cells or ())
    upper, incumbent = None, None
    if options.incumbent is not None:
        incumbent = bind(instance, options.incumbent)
        from .validate import validate

        report = validate(instance, options.incumbent)
        if not report.valid:
            raise OptionError(f"bfs: the incumbent is no valid schedule: {report.violation}")
        upper = report.metrics.makespan
    direction = _direction(options, upper)
    # the abstraction guides a forward search of a class below an incumbent, or deepening from its bound
    guided = options.abstraction and options.max_steps is None and (upper is not None or options.direction != "both")
    tables = compile_tables(instance, cells, distances=upper is not None or guided)  # the bounds serve the pruning
    per = bytes_per_state(tables)
    room = min(memory_budget(), address_room())
    built = None
    if guided:
        from .joint.abstraction import attach

        tables, built = attach(instance, cells, tables, budget.share(BUILD_SHARE), room)
        room -= 0 if built is None else built["states"]
    cap = int(room // per)
    max_states = options.max_states or cap
    if max_states > cap:
        raise OptionError(f"bfs: max_states {max_states:,} needs about {human(max_states * per)}, more than the "
                          f"{human(room)} this machine allows (BILLE_MEMORY_GIB sets it)")
    deepening = options.deepen and upper is None and options.max_steps is None
    if built is not None and built["none"]:  # no abstract goal reached: the class has no schedule
        from .joint.store import Outcome

        out = Outcome("exhausted", math.inf if upper is None else upper, states=1)
    elif built is not None:  # no schedule of the class is shorter than its bound: deepen from there
        from .joint.search import deepen

        out = deepen(instance, cells, budget, proved=int(built["start"]), max_states=max_states, events=run.events,
                     tables=tables, upper=upper)
    else:
        out = search(instance, cells, _plain_share(budget) if deepening else budget, U=upper, max_states=max_states,
                     max_steps=options.max_steps, events=run.events, tables=tables, direction=direction)
        if deepening and out.stop == "time" and not budget.expired():  # its share spent, not the whole limit
            from .joint.search import deepen

            out = deepen(instance, cells, budget, proved=int(out.proved), max_states=max_states, events=run.events,
                         tables=compile_tables(instance, cells, distances=True))  # keeps the better proof
    result = _result(instance, cells, out, upper, incumbent, options, budget, built)
    if result.schedule is not None:
        run.events.schedule(result.schedule)
    return result


def _tiny(instance: Instance) -> bool:
    from .estimate import joint_states

    return joint_states(instance) <= PYTHON_SMALL


def _plain_share(budget):
    left = budget.seconds()
    return budget if left is None else budget.child(max(PLAIN_SHARE * left, min(PLAIN_MIN, left / 2)))


def _direction(options: Options, upper: int | None) -> str:
    if options.direction != "auto":
        return options.direction
    return "forward" if upper is not None else "both"


def _result(instance: Instance, cells: Cells, out, upper, incumbent, options: Options, budget, built) -> Result:
    """The search's outcome as a result whose claim names its class (module docstring)."""
    stats = {**out.stats(), "class": {**cells.to_json(), "lower_bound": None}}
    if built is not None:
        stats["abstraction"] = built
    whole = cells.unconditional
    schedule, status, proved, failure = None, None, out.proved, None
    if out.stop == "goal":
        schedule = Schedule.from_ids(instance, out.ids, meta={"method": "bfs"})
        status = "optimal"
    elif out.stop == "exhausted" and upper is not None:  # nothing shorter than the incumbent
        schedule = Schedule.from_ids(instance, incumbent, meta={"method": "bfs"})
        member = whole or _member(instance, cells, incumbent)
        status = "optimal" if member else "feasible"
        if not member:
            failure = no_schedule(f"no schedule among {cells.name} is shorter than the incumbent's {upper} steps")
    elif out.stop == "exhausted":
        status = "infeasible" if whole else "unsolved"
        if not whole:
            failure = no_schedule(f"no schedule among {cells.name} exists")
            proved = None
    else:
        failure = {"time": TIME_LIMIT, "cancelled": INTERRUPTED, "states": cap(f"state cap ({out.states:,} states)"),
                   "steps": cap("step bound")}[out.stop]
        status = {"time": "timeout", "cancelled": "interrupted"}.get(out.stop, "unsolved")
        if upper is not None:
            schedule = Schedule.from_ids(instance, incumbent, meta={"method": "bfs"})
            status = "interrupted" if out.stop == "cancelled" else "feasible"
        which = "every schedule" if whole else cells.name
        stats["stopped"] = f"stopped at {out.states:,} states at depth {out.depth}: makespan >= {proved} among {which}"
    if status == "infeasible":
        proved = None
    stats["class"]["lower_bound"] = proved
    lower = proved if whole else None
    if whole and status == "optimal" and schedule is not None and upper is not None and out.stop == "exhausted":
        lower = upper
    return Result("bfs", status, schedule, lower_bound=lower, stats=stats, time_s=budget.elapsed(),
                  claim=claim_of(cells, None if whole else proved), failure=failure)


def claim_of(cells: Cells, lower: int | None) -> Claim:
    """The claim of a search of ``cells`` with the class bound ``lower``. Widened, a class holds
    the kind it widens, so its bound is one of that kind's too (a least makespan over more
    schedules is at most the least over fewer)."""
    if cells.unconditional:
        return EVERY
    return Claim(among=cells.name, spelled=f"cells={cells.key}", bounds=CLASS_KEYS.get(cells.kind), lower=lower)


def _member(instance: Instance, cells: Cells, ids) -> bool:
    """Whether a valid schedule changes no cell outside the class."""
    from .bounds.classes import tiles_over_time

    tiles = tiles_over_time(instance, ids)
    start = instance.start.tiles
    return all(not ((t != start) & ~cells.mask).any() for t in tiles)
