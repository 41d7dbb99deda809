"""Certified gaps of anytime solving, and where each end of the gap came from (``bille bench gaps``).

One ``anytime`` run per instance. A row gives the static lower bound and its strongest part, the
bound at the end and what proved it (``static``: the bound parts alone; ``rise``: the exact search
from below, one horizon after another; ``ahead``: a horizon decided above the rising search's,
:class:`bille.solvers.anytime.rise.Ahead`; ``window``: the whole schedule's window), the best schedule
and its first schedule's method and makespan, how many windows of each neighbourhood search
(free, kept) shortened it, the certified gap ``(makespan - LB) / LB`` and the seconds at which
each end reached its final value. Beside them, on an instance that moves tiles, the bound of each
class of schedules (:mod:`bille.solvers.classes`: ``no-scaffold``, ``keep-structure``,
``single-carry``), the classes the schedule belongs to (``N``, ``K``, ``S``: read from it), and its
gap within the narrowest of them: never a certified gap, since a schedule outside the class may
be shorter.
"""
from __future__ import annotations

from bille.solvers import solve
from bille.solvers.classes import CLASSES

from ..common import instance_arg, solved
from ..tables import text_table


def row(arg: str, time_limit: float) -> dict:
    """The measured row of one instance (a file or a bundled name)."""
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
                classes=stats.get("classes"))


def _proved_by(stats: dict, lower, static: int) -> str:
    if lower is None or lower <= static:
        return "static"
    if stats.get("windows", {}).get("proved_bound") == lower:
        return "window"
    if any(h + 1 == lower and answer == "unsat" for h, answer, _ in stats.get("ahead", [])):
        return "ahead"
    return "rise"


def _when(timeline, value):
    """The seconds at which a ``[[seconds, value], ...]`` timeline first reached ``value``."""
    return next((s for s, v in timeline or [] if v == value), None)


def table(rows: list[dict]) -> list[str]:
    short = {c.key: c.key[0].upper() for c in CLASSES}
    columns = ["instance", "static (part)", "LB", "by", "at s", "makespan", "at s", "first", "free", "kept",
               "gap"] + [f"LB {short[c.key]}" for c in CLASSES] + ["in", "class gap", "status"]
    body = []
    for r in rows:
        first = f"{r['first'].get('makespan')} {r['first'].get('method', '')}".strip() if r["first"] else None
        bounds = r.get("class_bounds") or {}
        inside = [c.key for c in CLASSES if c.key in (r.get("classes") or ()) and bounds.get(c.key) is not None]
        within = _gap(r["makespan"], bounds[inside[-1]]) if inside else None
        shown = None if r.get("classes") is None else "".join(short[k] for k in r["classes"]) or "-"
        body.append([r["instance"], f"{r['static']} ({r['static_part']})", r["lower"], r["lower_by"], r["lower_s"],
                     r["makespan"], r["best_s"], first, r["free"], r["kept"], _gap(r["makespan"], r["lower"])]
                    + [bounds.get(c.key) for c in CLASSES] + [shown, within, r["status"]])
    legend = ", ".join(f"{short[c.key]} {c.name}" for c in CLASSES)
    return text_table(columns, body, right={"LB", "at s", "makespan", "free", "kept", "gap", "class gap"}
                      | {f"LB {short[c.key]}" for c in CLASSES}) + [
        f"classes of schedules: {legend}; 'in': those the schedule belongs to; 'class gap': within the narrowest "
        "of them (not a certified gap)"]


def _gap(makespan, lower) -> str | None:
    if makespan is None or not lower:
        return None
    return f"{100.0 * (makespan - lower) / lower:.1f}%"
