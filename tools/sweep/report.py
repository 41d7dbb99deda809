"""``bille sweep report RESULTS``: per method configuration, success rate, certified gaps and
times, and the plots people expect (PNG): success rate against the number of robots, a cactus
plot of solve times, the distribution of certified gaps."""
from __future__ import annotations

import statistics
from pathlib import Path

from ..tables import text_table


def solved(row: dict) -> bool:
    return row.get("makespan") is not None


def summary(rows: list[dict]) -> list[str]:
    body = []
    for label in dict.fromkeys(r["label"] for r in rows):
        mine = [r for r in rows if r["label"] == label]
        ok = [r for r in mine if solved(r)]
        gaps = [100.0 * r["certified_gap"] for r in ok if r.get("certified_gap") is not None]
        times = [r["time_s"] for r in ok if r.get("time_s") is not None]
        failed = sum(r["status"] == "failed" for r in mine)
        body.append([label, len(mine), f"{100.0 * len(ok) / len(mine):.0f}%", failed,
                     f"{statistics.median(gaps):.1f}%" if gaps else None, f"{max(gaps):.1f}%" if gaps else None,
                     f"{statistics.median(times):.3f}" if times else None])
    return text_table(["method", "runs", "success", "failed", "median gap", "worst gap", "median time [s]"], body,
                      right={"runs", "success", "failed", "median gap", "worst gap", "median time [s]"})


def plots(rows: list[dict], folder: Path) -> list[Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(dict.fromkeys(r["label"] for r in rows))
    out = []
    fig, ax = plt.subplots(figsize=(7, 4))
    for label in labels:
        by = {}
        for r in rows:
            if r["label"] == label:
                by.setdefault(r["robots"], []).append(solved(r))
        xs = sorted(by)
        ax.plot(xs, [100.0 * sum(by[x]) / len(by[x]) for x in xs], marker="o", label=label)
    ax.set(xlabel="robots", ylabel="success [%]", ylim=(-5, 105), title="success rate against robots")
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
