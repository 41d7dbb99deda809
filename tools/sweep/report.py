"""``bille sweep report RESULTS``: per method configuration, success rate, certified gaps and
times; why runs failed (each kind of error once, with its count and its first run); and the
plots people expect (PNG): success rate against the number of robots, a cactus plot of solve
times, the distribution of certified gaps.

A run that does not apply (its method cannot plan that instance: ``n/a``) is counted apart and
left out of the success rate; a run that ``failed`` (crashed, killed, out of memory, an
exception) or ended in ``error`` (its schedule or proofs contradicted) is a failure."""
from __future__ import annotations

import statistics
from pathlib import Path

from ..tables import text_table


FAILED = ("failed", "error")


def solved(row: dict) -> bool:
    return row.get("makespan") is not None and row.get("status") not in FAILED


def summary(rows: list[dict]) -> list[str]:
    """The table per method configuration, then why runs failed and any contradiction."""
    from .results import contradictions

    body = [_summary_row(label, [r for r in rows if r["label"] == label])
            for label in dict.fromkeys(r["label"] for r in rows)]
    right = {"runs", "n/a", "success", "failed", "no schedule", "median certified gap", "worst certified gap",
             "median time [s]"}
    out = text_table(["method", "runs", "n/a", "success", "failed", "no schedule", "median certified gap",
                      "worst certified gap", "median time [s]"],
                     body, right=right)
    reasons = why(rows)
    if reasons:
        out += ["", "why runs failed or did not apply (each kind of error once, with its count and its first run):"]
        out += [f"  {n} x {_short(first['error'] or 'status ' + first['status'])} (first: {first['label']} on "
                f"{first['instance']})" for n, first in reasons.values()]
    unsolved: dict[str, tuple[int, dict]] = {}
    for r in rows:
        if r["status"] not in FAILED and r["status"] != "n/a" and not solved(r):
            kind = r["status"] + (f" ({r['error']})" if r.get("error") else "")
            n, first = unsolved.get(kind, (0, r))
            unsolved[kind] = (n + 1, first)
    if unsolved:
        out += ["", "runs that ended without a schedule (by how they ended, with their count and their first run):"]
        out += [f"  {n} x {_short(kind)} (first: {first['label']} on {first['instance']})"
                for kind, (n, first) in unsolved.items()]
    out += [f"contradiction: {line}" for line in contradictions(rows)]
    return out


def _summary_row(label: str, mine: list[dict]) -> list:
    """One configuration's line of :func:`summary`: runs, not applicable, success, failures,
    runs without a schedule, certified gaps and the median time."""
    applies = [r for r in mine if r["status"] != "n/a"]
    ok = [r for r in applies if solved(r)]
    gaps = [100.0 * r["certified_gap"] for r in ok if r.get("certified_gap") is not None]
    times = [r["time_s"] for r in ok if r.get("time_s") is not None]
    failed = sum(r["status"] in FAILED for r in mine)
    return [label, len(mine), len(mine) - len(applies), f"{100.0 * len(ok) / len(applies):.0f}%" if applies else None,
            failed, len(applies) - len(ok) - failed, f"{statistics.median(gaps):.1f}%" if gaps else None,
            f"{max(gaps):.1f}%" if gaps else None, f"{statistics.median(times):.3f}" if times else None]


def _short(text: str) -> str:
    return text if len(text) <= 160 else text[:157] + "..."


def kind_of(row: dict) -> str:
    """An error's kind: ``error: ValueError``, ``crashed (signal 9)``, ``memory limit``, ``n/a``..."""
    if row["status"] == "n/a":
        return "n/a"
    text = row.get("error") or f"status {row['status']}"
    if row["status"] == "error":
        return "status error"
    head, _, rest = text.partition(": ")
    if head in ("error", "worker lost") and rest:
        return f"{head}: {rest.partition(':')[0]}"
    return head


def why(rows: list[dict]) -> dict[str, tuple[int, dict]]:
    """Failed and inapplicable runs by kind of error: how many, and the first of them."""
    out: dict[str, tuple[int, dict]] = {}
    for r in rows:
        if r["status"] in FAILED or r["status"] == "n/a":
            kind = kind_of(r)
            n, first = out.get(kind, (0, r))
            out[kind] = (n + 1, first)
    return out


def plots(rows: list[dict], folder: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    labels = list(dict.fromkeys(r["label"] for r in rows))
    out = []
    fig, ax = plt.subplots(figsize=(7, 4))
    for label in labels:
        by = {}
        for r in rows:
            if r["label"] == label and r["status"] != "n/a":
                by.setdefault(r["robots"], []).append(solved(r))
        xs = sorted(by)
        ax.plot(xs, [100.0 * sum(by[x]) / len(by[x]) for x in xs], marker="o", label=label)
    ax.set(xlabel="robots", ylabel="success [%]", ylim=(-5, 105), title="success rate against robots")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))  # robots come whole
    ax.legend(fontsize=7)
    out.append(_save(fig, folder / "success.png"))
    fig, ax = plt.subplots(figsize=(7, 4))
    for label in labels:
        times = sorted(r["time_s"] for r in rows if r["label"] == label and solved(r) and r.get("time_s") is not None)
        ax.plot(range(1, len(times) + 1), [max(t, 1e-4) for t in times], marker=".", label=label)
    ax.set(xlabel="instances solved", ylabel="time [s]", yscale="log", title="cactus plot")
    ax.legend(fontsize=7)
    out.append(_save(fig, folder / "cactus.png"))
    fig, ax = plt.subplots(figsize=(7, 4))
    data = [[100.0 * r["certified_gap"] for r in rows if r["label"] == label and r.get("certified_gap") is not None]
            for label in labels]
    ax.boxplot([d or [float("nan")] for d in data])
    ax.set_xticks(range(1, len(labels) + 1), labels, rotation=20, fontsize=7, ha="right")
    ax.set(ylabel="certified gap [%]", title="(makespan - lower bound) / lower bound")
    out.append(_save(fig, folder / "gaps.png"))
    return out


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
