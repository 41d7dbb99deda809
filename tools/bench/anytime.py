"""How far anytime certified solving improves the paper's method (``bille bench anytime``).

Per instance: the paper's method (the reconfiguration loop with Temporal A*, H = 5, on the
instance's task sequence; Temporal A* alone on path planning), then ``anytime`` for the same time
limit twice: started from the paper's schedule (``--incumbent``) and from its own first schedule.
Each row gives the makespans, the lower bound proved in the run, and the certified gaps
``(makespan - LB) / LB``; the ratio column is the anytime makespan over the paper's, the baseline
of the same run.
"""
from __future__ import annotations

from bille.solvers import solve

from ..common import instance_arg, solved
from ..tables import text_table


def _gap(makespan, lower):
    return None if makespan is None or not lower else f"{100.0 * (makespan - lower) / lower:.1f}%"


def row(arg: str, time_limit: float) -> dict:
    """The measured row of one map (an instance file or a bundled name)."""
    inst = instance_arg(arg)
    paper = solved(solve(inst, "temporal-astar", time_limit=time_limit))
    from_paper = None
    if paper.schedule is not None:
        from_paper = solved(solve(inst, "anytime", time_limit=time_limit, incumbent=paper.schedule))
    own = solved(solve(inst, "anytime", time_limit=time_limit))
    runs = [r for r in (paper, from_paper, own) if r is not None]
    lower = max(r.lower_bound for r in runs if r.lower_bound is not None)
    span = {key: (r.metrics.makespan if r is not None and r.metrics else None)
            for key, r in (("paper", paper), ("from_paper", from_paper), ("own", own))}
    return dict(instance=inst.name, paper_status=paper.status, lower_bound=lower, **span, own_status=own.status,
                own_first=own.stats.get("first", {}).get("makespan"))


def table(rows: list[dict]) -> list[str]:
    columns = ["instance", "paper", "anytime from paper", "ratio", "anytime", "its first", "LB", "paper gap",
               "anytime gap"]
    body = []
    for r in rows:
        best = min((v for v in (r["from_paper"], r["own"]) if v is not None), default=None)
        ratio = f"{r['from_paper'] / r['paper']:.2f}" if r["paper"] and r["from_paper"] else None
        body.append([r["instance"], r["paper"] if r["paper"] is not None else r["paper_status"], r["from_paper"], ratio,
                     r["own"], r["own_first"], r["lower_bound"], _gap(r["paper"], r["lower_bound"]),
                     _gap(best, r["lower_bound"])])
    return text_table(columns, body, right=set(columns[1:]))
