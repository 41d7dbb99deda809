"""Certified gaps of anytime solving, and where each end of the gap came from (``bille bench gaps``).

One ``anytime`` run per instance. A row gives the static lower bound and its strongest part, the
bound at the end and what proved it (``static``: the bound parts alone; ``rise``: the exact search
from below, one horizon after another; ``ahead``: a horizon decided above the rising search's,
:class:`bille.solvers.anytime.rise.Ahead`; ``scaffold``: the static bound's scaffold scenarios
taken further, :class:`bille.solvers.anytime.rise.Scaffold`; ``window``: the whole schedule's
window), the best schedule
and its first schedule's method and makespan, how many windows of each neighbourhood search
(free, kept) shortened it, the certified gap ``(makespan - LB) / LB`` and the seconds at which
each end reached its final value. Beside them, on an instance that moves tiles, the bound of each
class of schedules (:mod:`bille.solvers.bounds.classes`: ``no-scaffold``, ``keep-structure``,
``single-carry``), the classes the schedule belongs to (``N``, ``K``, ``S``: read from it), and its
gap within the narrowest of them: never a certified gap, since a schedule outside the class may
be shorter.

With ``class_exact`` seconds, the exact joint search of the schedules without scaffold
(``bfs -O cells=no-scaffold``, guided by its abstraction where it fits) runs after anytime, below
anytime's schedule when that schedule is one of the class: it finds a shorter schedule of the
class, or proves that none is shorter (anytime's is then optimal within the class), or raises
the class bound as far as it got. The row gets the class bound it proved (``N exact``), the makespan of the best
schedule of the class either search found (``N best``) and the gap between the two (``N gap``):
which side of the class gap is open, measured.
"""
from __future__ import annotations

from bille.solvers import solve
from bille.solvers.bounds.classes import CLASSES

from ..common import instance_arg, solved
from ..tables import text_table


def row(arg: str, time_limit: float, class_exact: float | None = None) -> dict:
    """The measured row of one instance (a file or a bundled name); with ``class_exact``, the
    restricted exact search's columns too (module docstring)."""
    inst = instance_arg(arg)
    result = solved(solve(inst, "anytime", time_limit=time_limit))
    stats = result.stats
    parts = {k: v for k, v in stats.get("bound_parts", {}).items() if v is not None}
    static = max(parts.values(), default=0)
    lower = result.lower_bound
    makespan = result.metrics.makespan if result.metrics else None
    return dict(instance=inst.name, status=result.status, static=static,
                static_part=max(parts, key=parts.get) if parts else None, lower=lower,
                lower_by=_proved_by(stats, lower, static), lower_s=_when(stats.get("lower_bounds"), lower),
                makespan=makespan, best_s=_when(stats.get("improvements"), makespan),
                first=stats.get("first", {}), free=stats.get("windows", {}).get("shortened", 0),
                kept=stats.get("kept_windows", {}).get("shortened", 0), time_s=round(result.time_s, 1),
                class_bounds={k: v.get("lower_bound") for k, v in stats.get("class_bounds", {}).items()},
                classes=stats.get("classes"), exact=_class_exact(inst, result, class_exact) if class_exact else None,
                keep_optimum=stats.get("class_optima", {}).get("keep-structure"),
                free_optimum=stats.get("class_optima", {}).get("no-scaffold"))


def _class_exact(inst, anytime, seconds: float) -> dict | None:
    """The restricted exact search after ``anytime`` (module docstring): ``lower``, the bound it
    proved for the schedules without scaffold (at least the class's static bound), ``best``, the
    shortest schedule of the class found by either search, and ``optimal``: whether they meet.
    None where the instance moves no tiles or the class has no schedule."""
    bound = anytime.stats.get("class_bounds", {}).get("no-scaffold", {}).get("lower_bound")
    if bound is None:
        return None
    own = anytime.metrics.makespan if anytime.schedule is not None and "no-scaffold" in anytime.stats.get(
        "classes", ()) else None
    if own is not None and own <= bound:
        return {"lower": bound, "best": own, "optimal": True, "time_s": 0.0}
    incumbent = anytime.schedule if own is not None else None
    exact = solved(solve(inst, "bfs", cells="no-scaffold", incumbent=incumbent, time_limit=seconds))
    lower = max(bound, exact.stats["class"]["lower_bound"] or 0)
    found = [m for m in (own, exact.metrics.makespan if exact.schedule is not None else None) if m is not None]
    best = min(found, default=None)
    return {"lower": lower, "best": best, "optimal": best is not None and best <= lower,
            "time_s": round(exact.time_s, 1)}


def _proved_by(stats: dict, lower, static: int) -> str:
    if lower is None or lower <= static:
        return "static"
    if stats.get("windows", {}).get("proved_bound") == lower:
        return "window"
    if any(h + 1 == lower and answer == "unsat" for h, answer, _ in stats.get("ahead", [])):
        return "ahead"
    if any(value == lower for _, value in stats.get("scaffold", [])):
        return "scaffold"
    return "rise"


def _when(timeline, value):
    """The seconds at which a ``[[seconds, value], ...]`` timeline first reached ``value``."""
    return next((s for s, v in timeline or [] if v == value), None)


def table(rows: list[dict]) -> list[str]:
    short = {c.key: c.key[0].upper() for c in CLASSES}
    exact = any(r.get("exact") is not None for r in rows)
    columns = ["instance", "static (part)", "LB", "by", "at s", "makespan", "at s", "first", "free", "kept",
               "gap"] + [f"LB {short[c.key]}" for c in CLASSES] + ["K opt", "N opt", "in", "class gap", "status"] + (
        ["N exact", "N best", "N gap", "exact s"] if exact else [])
    body = []
    for r in rows:
        first = f"{r['first'].get('makespan')} {r['first'].get('method', '')}".strip() if r["first"] else None
        bounds = r.get("class_bounds") or {}
        inside = [c.key for c in CLASSES if c.key in (r.get("classes") or ()) and bounds.get(c.key) is not None]
        within = _gap(r["makespan"], bounds[inside[-1]]) if inside else None
        shown = None if r.get("classes") is None else "".join(short[k] for k in r["classes"]) or "-"
        body.append([r["instance"], f"{r['static']} ({r['static_part']})", r["lower"], r["lower_by"], r["lower_s"],
                     r["makespan"], r["best_s"], first, r["free"], r["kept"], _gap(r["makespan"], r["lower"])]
                    + [bounds.get(c.key) for c in CLASSES] + [r.get("keep_optimum"), r.get("free_optimum"), shown, within,
                                                                 r["status"]]
                    + (_exact_cells(r.get("exact")) if exact else []))
    legend = ", ".join(f"{short[c.key]} {c.name}" for c in CLASSES)
    notes = [f"classes of schedules: {legend}; 'in': those the schedule belongs to; 'class gap': within the "
             "narrowest of them (not a certified gap); 'K opt': the optimum of the schedules that keep the "
             "structure, decided by anytime's joint search (bille solve -m bfs -O cells=keep); 'N opt': the optimum of "
             "the schedules without scaffold, decided by its ladder's top (bille solve -m bfs -O cells=no-scaffold)"]
    if exact:
        notes.append("'N exact': the bound for schedules without scaffold with the exact search restricted to them; "
                     "'N best': the shortest such schedule found; 'N gap': between the two ('optimal' where they meet)")
    return text_table(columns, body, right={"LB", "at s", "makespan", "free", "kept", "gap", "class gap", "K opt", "N opt", "N exact",
                                            "N best", "N gap", "exact s"}
                      | {f"LB {short[c.key]}" for c in CLASSES}) + notes


def _exact_cells(exact: dict | None) -> list:
    if exact is None:
        return [None] * 4
    gap = "optimal" if exact["optimal"] else _gap(exact["best"], exact["lower"])
    return [exact["lower"], exact["best"], gap, exact["time_s"]]


def _gap(makespan, lower) -> str | None:
    if makespan is None or not lower:
        return None
    return f"{100.0 * (makespan - lower) / lower:.1f}%"
