"""The gap report: methods (and schedule files) against the best proved lower bound on the same
instances.

Every method configuration runs on every instance under the same time limit. Per instance:

- ``lower_bound``: the best lower bound on the makespan proved by anything in the run: each
  method's own (``solve()`` reports the static bound at least, an exact or anytime search more).
  An optimum or bound in the instance's metadata (``optimum`` or ``lower_bound``, as ``bille gen
  hampath --search`` writes them) is shown in the note as the file's claim, never used as a proof
  (a file can be edited);
- ``best``: the shortest valid schedule of the run;
- per row, ``certified_gap_percent`` = (makespan - lower_bound) / lower_bound: how much longer
  the schedule is than the optimum *at most*, whatever the optimum; and ``gap_percent``, the
  exact gap, where some method proved the optimum;
- on an instance that moves tiles, ``classes``: the classes of schedules the row's schedule
  belongs to (:mod:`bille.solvers.bounds.classes`, read from the schedule), and against the narrowest
  of them (``class``), ``class_lower_bound`` (the best bound on that class proved in the run) and
  ``class_gap_percent``: how much longer the schedule is than the best schedule *of its class*,
  at most. A class gap is not a certified gap: a schedule outside the class may be shorter.

Interrupted (Ctrl-C), the report holds the instances' rows finished so far, measured the same
way (:class:`Interrupted`).

Method configurations are ``name`` or ``name:option=value,option=value`` (the short names ``H``
and ``d-tr`` of the command line work too). Methods that do not apply to an instance are listed
as ``n/a`` with the reason; two exact methods that disagree on an optimum stop the report.
"""
from __future__ import annotations

import csv
import statistics
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from bille.instances import BilleError, Instance, OptionError
from bille.instances.claim import EVERY, Claim, shown_status, status_key
from bille.solvers import METHODS, solve, validate
from bille.solvers.options import check_options, gather_options

from .tables import text_table

FIELDS = ["instance", "method", "status", "makespan", "own_lower_bound", "lower_bound", "best", "tiles_traveled",
          "time_s", "gap_percent", "certified_gap_percent", "classes", "class", "class_lower_bound",
          "class_gap_percent", "note"]
SHOWN_STATUS = {"unsolved": "gave up", "timeout": "out of time"}


@dataclass
class Config:
    """A method with options, labelled as the user wrote it."""

    label: str
    method: str
    options: dict = field(default_factory=dict)
    given: list = field(default_factory=list)  # (token, name, value) as written, before aliases are resolved


def parse_configs(texts: str | Iterable[str]) -> list[Config]:
    """``"temporal-astar:H=10,load_transfer=true,mstar"`` -> two configurations: a token with
    ``=`` and no ``:`` continues the options of the configuration before it. Several texts (a
    repeated ``--methods``) are read one by one, so options never run on from one text into the
    next. Raises :class:`OptionError` naming what is wrong, including a configuration named twice
    (its rows would be indistinguishable)."""
    texts = [texts] if isinstance(texts, str) else list(texts)
    configs: list[Config] = []
    for text in texts:
        configs += _parse_text(text)
    labels = [c.label for c in configs]
    twice = sorted({label for label in labels if labels.count(label) > 1})
    if twice:
        raise OptionError(f"method configuration {twice[0]!r} is named twice")
    for c in configs:  # a wrong option is bad input, found before anything runs
        c.options = gather_options(c.method, c.given)
        check_options(c.method, c.options)
    return configs


def _parse_text(text: str) -> list[Config]:
    configs: list[Config] = []
    for token in (t.strip() for t in text.split(",")):
        if not token:
            continue
        if "=" in token and ":" not in token.split("=", 1)[0]:
            if not configs:
                raise OptionError(f"option {token!r} comes before any method")
            _add_option(configs[-1], token)
            continue
        name, _, first = token.partition(":")
        if name not in METHODS:
            raise OptionError(f"unknown method {name!r} (expected one of: {', '.join(METHODS)})")
        configs.append(Config(name, name))
        if first:
            _add_option(configs[-1], first)
    if not configs:
        raise OptionError(f"no method named in {text!r}")
    return configs


def _add_option(config: Config, token: str) -> None:
    name, sep, value = token.partition("=")
    if not sep or not name.strip():
        raise OptionError(f"expected OPTION=VALUE after '{config.method}:', got {token!r}")
    name = name.strip()
    try:
        config.given.append((token.strip(), name, yaml.safe_load(value)))
    except yaml.YAMLError:
        raise OptionError(f"cannot read the value of {token!r}") from None
    config.label += (":" if config.label == config.method else ",") + token.strip()


def known_lower_bound(inst: Instance) -> tuple[int | None, str]:
    """A lower bound carried by the instance's metadata, and where it comes from."""
    meta = inst.meta or {}
    for key in ("optimum", "lower_bound"):
        if isinstance(meta.get(key), int) and not isinstance(meta.get(key), bool):
            return meta[key], f"metadata {key}"
    return None, ""


class Interrupted(Exception):
    """The user stopped the report: ``rows`` holds the rows finished before (and the stopped
    method's row where it returned its best so far), certified as usual."""

    def __init__(self, rows: list[dict]) -> None:
        super().__init__("interrupted")
        self.rows = rows


def run(instances: list[Instance], configs: list[Config], time_limit: float, threads: int = 1, progress=None,
        schedules: dict | None = None, files: dict | None = None) -> list[dict]:
    """One row per instance and configuration, then one per schedule file valid for the instance
    (``files``: label -> Schedule; see :func:`check_files`). ``schedules``, if given, receives every schedule found under
    ``(instance name, label)``. Raises :class:`Interrupted` on Ctrl-C."""
    rows = []
    for inst in instances:
        mine = []
        try:
            for c in configs:
                mine.append(_solve_row(inst, c, time_limit, threads, progress, schedules))
                if mine[-1]["status"] == "interrupted":
                    raise KeyboardInterrupt
        except KeyboardInterrupt:
            if mine:
                _certify(inst, mine)
            raise Interrupted(rows + mine) from None
        for label, schedule in (files or {}).items():
            if schedule.num_robots == inst.num_robots and validate(inst, schedule).valid:
                mine.append(_file_row(inst, label, schedule, schedules))
        _certify(inst, mine)
        rows += mine
    return rows


def check_files(instances: list[Instance], files: dict) -> None:
    """Raise :class:`OptionError` for a schedule file valid for none of the instances."""
    for label, schedule in files.items():
        reasons = []
        for inst in instances:
            if schedule.num_robots != inst.num_robots:
                reasons.append(f"{inst.name}: {inst.num_robots} robots, the schedule has {schedule.num_robots}")
                continue
            report = validate(inst, schedule)
            if report.valid:
                break
            reasons.append(f"{inst.name}: {report.violation}")
        else:
            raise OptionError(f"{label} is valid for none of the instances ({'; '.join(reasons)})")


def _row(inst, label, status, metrics=None, lower=None, time_s=None, note="", claim=None, classes=None,
         class_bounds=None) -> dict:
    """A row of the report; ``claim`` (not written to the CSV, but its status key is) is what an
    ``optimal`` status is optimal for (:class:`~bille.instances.claim.Claim`); ``class_bounds``
    (not written either) the class bounds the row's solve proved."""
    return dict(instance=inst.name, method=label, status=status, makespan=metrics.makespan if metrics else None,
                own_lower_bound=lower, lower_bound=None, best=None,
                tiles_traveled=metrics.tiles_traveled if metrics else None, time_s=time_s, gap_percent=None,
                certified_gap_percent=None, classes=None if classes is None else " ".join(classes),
                class_lower_bound=None, class_gap_percent=None, **{"class": None}, note=note, claim=claim or EVERY,
                own_class_bounds=class_bounds or {})


def _solve_row(inst, config: Config, time_limit, threads, progress, schedules) -> dict:
    if progress:
        progress(inst.name, config.label)
    options = {"time_limit": time_limit, **config.options}
    if config.method == "cpsat" and "threads" not in config.options:
        options["threads"] = threads
    try:
        result = solve(inst, config.method, bound=True, **options)
    except OptionError as exc:
        return _row(inst, config.label, "n/a", note=str(exc))
    if schedules is not None and result.schedule is not None:
        schedules[inst.name, config.label] = result.schedule
    note = ((result.failure and result.failure.text) or result.stats.get("reason") or result.stats.get("violation")
            or result.stats.get("contradiction") or "")
    if not note and not result.claim.unconditional:
        note = f"optimizes: {result.claim.text()}"
    return _row(inst, config.label, result.status, result.metrics, result.lower_bound, round(result.time_s, 3), note,
                result.claim, result.stats.get("classes"), result.stats.get("class_bounds"))


def _file_row(inst, label, schedule, schedules) -> dict:
    report = validate(inst, schedule)
    if schedules is not None:
        schedules[inst.name, label] = schedule
    from bille.solvers.bounds.classes import applies, classes_of

    return _row(inst, label, "given", report.metrics, note="schedule file",
                classes=classes_of(inst, schedule) if applies(inst) else None)


def _certify(inst: Instance, rows: list[dict]) -> None:
    # an optimum proved for the makespan itself, by whichever method: not one of a method's own
    # objective (walking only, sum of costs) or of a restricted set of schedules (single_carry),
    # which names it; solve() turns an unnamed optimum without a matching proof into an error
    proved = {r["makespan"] for r in rows if r["status"] == "optimal" and r["makespan"] is not None
              and r["claim"].unconditional}
    if len(proved) > 1:  # two exact methods disagree: a bug, never hide it
        raise BilleError(f"{inst.name}: exact methods disagree on the optimal makespan: {sorted(proved)}")
    # a row whose own proofs contradicted its schedule (status error) proves nothing
    lowers = [r["own_lower_bound"] for r in rows if r["own_lower_bound"] is not None and r["status"] != "error"]
    lower = max(lowers, default=None)
    spans = [r["makespan"] for r in rows if r["makespan"] is not None]
    best = min(spans, default=None)
    claim = _file_claim(inst, best)
    if lower is not None and best is not None and lower > best:
        raise BilleError(f"{inst.name}: a lower bound of {lower} above a valid schedule of {best} steps")
    optimum = proved.pop() if proved else (best if best is not None and best == lower else None)
    for r in rows:
        r["lower_bound"], r["best"] = lower, best
        if claim:
            r["note"] = f"{r['note']}; {claim}" if r["note"] else claim
        if r["makespan"] is None:
            continue
        if optimum is not None:
            r["gap_percent"] = _percent(r["makespan"], optimum)
        if lower is not None:
            r["certified_gap_percent"] = _percent(r["makespan"], lower)
    _certify_classes(inst, rows)


def _certify_classes(inst: Instance, rows: list[dict]) -> None:
    """Each row's gap within the narrowest class its schedule belongs to, against the best
    bound on that class proved by any row (a row whose proofs contradicted its schedule proves
    nothing)."""
    from bille.solvers.bounds.classes import CLASSES

    best: dict[str, int] = {}
    for r in rows:
        if r["status"] == "error":
            continue
        for key, got in r["own_class_bounds"].items():
            if got.get("lower_bound") is not None:
                best[key] = max(best.get(key, 0), got["lower_bound"])
    for r in rows:
        mine = [c.key for c in CLASSES if r["classes"] and c.key in r["classes"].split() and c.key in best]
        if r["makespan"] is None or not mine:
            continue
        key = mine[-1]  # the classes nest: the last one is the narrowest, with the highest bound
        if best[key] > r["makespan"]:
            raise BilleError(f"{inst.name}: a {key} bound of {best[key]} above a valid {key} schedule of "
                             f"{r['makespan']} steps")
        r["class"], r["class_lower_bound"] = key, best[key]
        r["class_gap_percent"] = _percent(r["makespan"], best[key])


def _file_claim(inst: Instance, best: int | None) -> str:
    """What the instance file says of its optimum, as a claim: shown, not proved here."""
    known, source = known_lower_bound(inst)
    if known is None:
        return ""
    key = source.removeprefix("metadata ")
    if best is not None and known > best:
        return f"the file's {key} {known} is wrong: a valid schedule has {best} steps"
    return f"the file's {key} {known}, not proved here"


def _percent(makespan: int, base: int) -> float:
    return round(100.0 * (makespan - base) / base, 1) if base else 0.0


def table(rows: list[dict], wide: bool = False) -> list[str]:
    """The report's table: ``wide``, every column, each status in words; else the columns that
    fit 120 characters, an optimum of another objective marked ``optimal*`` and said below."""
    columns = ["instance", "method", "status", "makespan", "LB", "best", "tiles", "time [s]", "gap", "certified"]
    body = []
    for r in rows:
        status = SHOWN_STATUS.get(r["status"], shown_status(r["status"], _claim(r)))
        if not wide and status.startswith("optimal ("):
            status = "optimal*"
        body.append([r["instance"], r["method"], status, r["makespan"], r["lower_bound"], r["best"],
                     r["tiles_traveled"], _show(r["time_s"], "{:.3f}"), _show(r["gap_percent"], "{:+.1f}%"),
                     _show(r["certified_gap_percent"], "<= {:.1f}%")]
                    + ([_in_class(r), _show(r["class_gap_percent"], "<= {:.1f}%"), r["note"]] if wide else []))
    out = text_table(columns + (["in class (LB)", "class gap", "note"] if wide else []), body,
                     right={"makespan", "LB", "best", "tiles", "time [s]", "gap", "certified"})
    if wide:
        return out
    starred = {r["method"]: _claim(r) for r in rows if r["status"] == "optimal" and not _claim(r).unconditional}
    out += [f"* {method}: optimal for {claim.text()}" for method, claim in starred.items()]
    if any(r["classes"] is not None or r["note"] for r in rows):
        out.append("--wide shows the classes of schedules and the notes (failures, objectives)")
    return out


def _in_class(r: dict) -> str | None:
    if r["classes"] is None or r["makespan"] is None:
        return None
    if not r["classes"]:
        return "none"
    return None if r["class"] is None else f"{r['class_lower_bound']} ({r['class']})"


def summary(rows: list[dict]) -> list[str]:
    """Per method: instances with a schedule, median and worst certified gap over them."""
    out = []
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method and r["status"] != "n/a"]
        gaps = [r["certified_gap_percent"] for r in mine if r["certified_gap_percent"] is not None]
        solved = sum(r["makespan"] is not None for r in mine)
        out.append([method, f"{solved}/{len(mine)}", _show(statistics.median(gaps) if gaps else None, "{:.1f}%"),
                    _show(max(gaps) if gaps else None, "{:.1f}%")])
    return text_table(["method", "schedules", "median certified gap", "worst"], out,
                      right={"schedules", "median certified gap", "worst"})


def write_csv(rows: list[dict], path: Path) -> None:
    from bille.instances.files import write_atomic
    import io

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=FIELDS, extrasaction="ignore")
    w.writeheader()
    w.writerows({**r, "status": status_key(r["status"], r["claim"])} for r in rows)
    write_atomic(path, buf.getvalue(), BilleError)


def json_row(r: dict) -> dict:
    """A row as ``bille gap --json`` prints it: the status as ``bille solve --json`` has it, with
    the claim whole (:func:`table` reads such rows back)."""
    return {**r, "claim": r["claim"].to_json()}


def _claim(r: dict) -> Claim:
    claim = r["claim"]
    return claim if isinstance(claim, Claim) else Claim.from_json(claim)


def _show(v, fmt="{}"):
    return None if v is None else fmt.format(v)
