"""Sweep files: instances x methods x option grids (``bille sweep SPEC.yaml``).

```yaml
name: small                     # optional; the results folder defaults to sweep-NAME
max_runs: 10000                 # optional: the sweep's runs at most (default 10,000)
time_limit: 10                  # seconds per run (each run's own time_limit option wins)
memory_limit: 2000              # megabytes per run (optional)
instances:
  - compare-2                   # a bundled name
  - maps/*.yaml                 # files, globs relative to the sweep file
  - gen: random --moved 3 --robots 2 --seed 0..9   # a generator call, seeds as a range a..b
  - {instance: compare-2, moveset: S5}             # a name or file with another moveset
methods:                        # optional: without it, auto with its defaults (as bille solve)
  temporal-astar: {horizon: [2, 5], epsilon: [1, 2]}   # every combination of the lists
  mstar: {}
  lacam: {improve: 0}           # a single value is a list of one
```

Every run is keyed by its instance's hash (the SHA-256 of its YAML, as ``bille`` writes it), the
method and its options, so a sweep started again skips the runs already recorded; an instance or
an option set listed twice is refused. Errors name the file, the line and the entry. A name is a
safe file name (letters, digits, ``-``, ``_``, ``.``); the number of runs is checked before any
instance is generated.
"""
from __future__ import annotations

import contextlib
import dataclasses
import glob
import io
import hashlib
import itertools
import json
import math
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import click
from bille.instances import BilleError, OptionError, dump_instance, load_instance
from bille.instances.bundled import bundled_names, bundled_path
from bille.solvers import METHODS
from bille.solvers.options import check_options

_RANGE = re.compile(r"^(\d+)\.\.(\d+)$")
_NAME = re.compile(r"^[A-Za-z0-9._-]{1,100}$")
MAX_RUNS = 10_000
KEYS = ("name", "time_limit", "memory_limit", "max_runs", "instances", "methods")


@dataclass(frozen=True)
class Run:
    """One solve: an instance (as YAML text), a method and its options."""

    instance: str  # the instance's label: bundled name, file name, or generator call
    text: str
    method: str
    options: tuple  # sorted (name, value) pairs

    @property
    def instance_hash(self) -> str:
        return hashlib.sha256(self.text.encode()).hexdigest()[:16]

    @property
    def options_json(self) -> str:
        return json.dumps(dict(self.options), sort_keys=True)

    @property
    def key(self) -> str:
        return f"{self.instance_hash}|{self.method}|{self.options_json}"

    @property
    def label(self) -> str:
        """``method`` or ``method:name=value,...``, as ``bille gap`` writes configurations."""
        if not self.options:
            return self.method
        return self.method + ":" + ",".join(f"{k}={_show(v)}" for k, v in self.options)


@dataclass(frozen=True)
class Limits:
    """What each run of a sweep may take: ``seconds`` (a run's own ``time_limit`` option wins)
    and ``memory_mb`` megabytes on top of what its process has mapped when it starts (None: no
    limit)."""

    seconds: float
    memory_mb: int | None = None


@dataclass(frozen=True)
class Spec:
    name: str
    runs: list
    time_limit: float
    memory_limit: int | None

    @property
    def limits(self) -> Limits:
        return Limits(self.time_limit, self.memory_limit)


def _show(v) -> str:
    return "true" if v is True else "false" if v is False else str(v)


SHIPPED = Path(__file__).resolve().parent / "files"


def shipped_names() -> list[str]:
    return sorted(p.stem for p in SHIPPED.glob("*.yaml"))


def load_spec(path: str | Path) -> Spec:
    """Read a sweep file, or one shipped with bille by name (``small``, ``planners``); raises
    :class:`BilleError` naming the file, the line and the entry at fault."""
    from bille.instances.yamlsource import load_yaml_file

    path = Path(path)
    if not path.exists() and str(path) in shipped_names():
        path = SHIPPED / f"{path}.yaml"
    if not path.is_file():
        raise BilleError(f"{path}: no such sweep file (shipped sweeps: {', '.join(shipped_names())})")
    data, src = load_yaml_file(path, BilleError)  # duplicate keys and YAML aliases refused, by line
    return parse_spec(data, path, src)


def _settings(data, path: Path, fail) -> tuple:
    """A sweep file's ``time_limit``, ``memory_limit``, ``max_runs`` and ``name``, checked
    (``fail(message, *field)`` raises), after its top level: a mapping of known keys."""
    if not isinstance(data, dict):
        fail("expected a mapping with instances and methods")
    unknown = set(data) - set(KEYS)
    if unknown:
        fail(f"unknown key {sorted(map(str, unknown))[0]!r} (expected {', '.join(KEYS)})")
    time_limit = data.get("time_limit", 60)
    if isinstance(time_limit, bool) or not isinstance(time_limit, (int, float)) or not 0 < time_limit < float("inf"):
        fail(f"time_limit: expected positive seconds, got {time_limit!r}", "time_limit")
    memory = data.get("memory_limit")
    if memory is not None and (isinstance(memory, bool) or not isinstance(memory, int) or memory < 50):
        fail(f"memory_limit: expected megabytes (at least 50), got {memory!r}", "memory_limit")
    max_runs = data.get("max_runs", MAX_RUNS)
    if isinstance(max_runs, bool) or not isinstance(max_runs, int) or max_runs < 1:
        fail(f"max_runs: expected a positive whole number, got {max_runs!r}", "max_runs")
    # a file's own name is a name already: only what a folder name cannot hold is replaced
    name = data.get("name", re.sub(r"[^A-Za-z0-9._-]", "_", path.stem)[:100])
    if not isinstance(name, str) or not _NAME.match(name) or set(name) == {"."}:
        fail(f"name: {name!r} is not a safe file name (letters, digits, '-', '_', '.'; no separators), the "
             "results folder is sweep-NAME" + ("" if "name" in data else ": give one with name:"), "name")
    return time_limit, memory, max_runs, name


def parse_spec(data, path: Path, src=None) -> Spec:
    def at(*field) -> str:
        line = src.line(field) if src is not None else None
        return f"{path}:{line}" if line else str(path)

    def fail(msg, *field):
        raise BilleError(f"{at(*field)}: {msg}")

    time_limit, memory, max_runs, name = _settings(data, path, fail)
    if not isinstance(data.get("instances"), list) or not data["instances"]:
        fail("instances: expected a list of bundled names, files, globs or {gen: ...} calls", "instances")
    methods = data.get("methods", {"auto": {}})  # the default method, as bille solve's
    if not isinstance(methods, dict) or not methods:
        fail("methods: expected a mapping of method names to option grids", "methods")
    configs: dict = {}
    for method, grid in methods.items():
        for c in _configs(method, grid, at("methods", method), max_runs - len(configs)):
            if c in configs:
                fail(f"methods.{method}: the options {dict(c[1])} are listed twice", "methods", method)
            configs[c] = True
    room = max_runs // len(configs)  # instances that fit the run budget
    instances: dict = {}
    for k, entry in enumerate(data["instances"]):
        where = f"{at('instances', k)}: instances[{k}]"
        for label, text in _instances(entry, path, where, lambda count: _budget(count + len(instances), room,
                                                                               len(configs), max_runs, where)):
            if text in instances:
                raise BilleError(f"{where}: {label!r} is the same instance as {instances[text]!r}, listed before "
                                 "(each run would be done twice)")
            instances[text] = label
            _budget(len(instances), room, len(configs), max_runs, where)
    runs = [Run(label, text, method, options) for text, label in instances.items() for method, options in configs]
    return Spec(name, runs, float(time_limit), memory)


def _budget(count: int, room: int, configs: int, max_runs: int, where: str) -> None:
    if count > room:
        raise BilleError(f"{where}: {count} instances x {configs} method configurations make {count * configs} "
                         f"runs, more than max_runs {max_runs} (raise max_runs in the sweep file to allow more)")


def _instances(entry, path: Path, where: str, check):
    """The ``(label, text)`` of each instance an entry names; ``check(n)`` is told how many an
    entry will make before they are made."""
    if isinstance(entry, dict) and set(entry) == {"gen"} and isinstance(entry["gen"], str):
        yield from _generated(entry["gen"], where, check)
        return
    if isinstance(entry, dict) and set(entry) == {"instance", "moveset"} and isinstance(entry["instance"], str):
        from bille.instances import check_instance, instance_from_text, load_moveset

        for label, text in _instances(entry["instance"], path, where, check):
            try:
                inst = check_instance(dataclasses.replace(instance_from_text(text), moveset=load_moveset(entry["moveset"])))
            except BilleError as exc:
                raise BilleError(f"{where}: {exc}") from None
            yield f"{label} {entry['moveset']}", dump_instance(inst)
        return
    if isinstance(entry, dict):
        raise BilleError(f"{where}: expected {{gen: 'GENERATOR OPTIONS'}} or {{instance: NAME, moveset: MOVESET}}, "
                         f"got {_short(entry)}")
    if not isinstance(entry, str) or not entry or "\0" in entry:
        raise BilleError(f"{where}: expected a name, a file, a glob or {{gen: ...}}, got {_short(entry)}")
    if entry in bundled_names():
        yield entry, dump_instance(load_instance(bundled_path(entry)))
        return
    pattern = entry if Path(entry).is_absolute() else str(path.parent / entry)
    files = sorted(glob.glob(pattern))
    if not files:
        raise BilleError(f"{where}: {_short(entry)} is no bundled instance and matches no file")
    check(len(files))
    for f in files:
        yield Path(f).name.removesuffix(".yaml"), dump_instance(load_instance(f))


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def _generated(call: str, where: str, check):
    """``random --moved 3 --seed 0..9``: the generator run once per seed of the range."""
    from ..gen import gen

    args = call.split()
    makers = sorted(set(gen.commands) - {"graph"})  # gen graph draws a graph, not an instance
    if not args or args[0] not in makers:
        raise BilleError(f"{where}: unknown generator {_short(args[0] if args else '')} "
                         f"(expected one of: {', '.join(makers)})")
    seeds = [None]
    if "--seed" in args:
        k = args.index("--seed")
        if k + 1 >= len(args):
            raise BilleError(f"{where}: --seed needs a value or a range a..b")
        match = _RANGE.match(args[k + 1])
        if match:
            first, last = int(match.group(1)), int(match.group(2))
            if last < first:
                raise BilleError(f"{where}: --seed {args[k + 1]}: an empty range (a..b with b >= a)")
            check(last - first + 1)
            seeds = range(first, last + 1)
            args = args[:k] + args[k + 2:]
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            argv = args + ([] if seed is None else ["--seed", str(seed)]) + ["-o", f"{tmp}/i.yaml"]
            try:
                with contextlib.redirect_stdout(io.StringIO()):
                    gen.main(args=argv, prog_name="bille gen", standalone_mode=False)
            except BilleError as exc:
                raise BilleError(f"{where}: {exc}") from None
            except click.ClickException as exc:  # a usage error in the call
                raise BilleError(f"{where}: {_short(call)}: {exc.format_message()}") from None
            label = " ".join(args) + ("" if seed is None else f" --seed {seed}")
            yield label, Path(f"{tmp}/i.yaml").read_text(encoding="utf-8")


def _configs(name, grid, path: str, room: int):
    if name not in METHODS:
        raise BilleError(f"{path}: methods: unknown method {_short(name)} (expected one of: {', '.join(METHODS)})")
    if grid is None:
        grid = {}
    if not isinstance(grid, dict):
        raise BilleError(f"{path}: methods.{name}: expected a mapping of options to values or lists")
    keys = sorted(grid, key=str)
    lists = [grid[k] if isinstance(grid[k], list) else [grid[k]] for k in keys]
    for k, values in zip(keys, lists):
        if not values:
            raise BilleError(f"{path}: methods.{name}.{k}: an empty list (no run)")
    if math.prod(len(v) for v in lists) > room:
        raise BilleError(f"{path}: methods.{name}: {math.prod(len(v) for v in lists)} option combinations, more "
                         f"than max_runs allows (raise max_runs in the sweep file to allow more)")
    for values in itertools.product(*lists):
        options = dict(zip(keys, values))
        try:
            check_options(name, options)
        except OptionError as exc:
            raise BilleError(f"{path}: methods.{name}: {exc}") from None
        yield name, tuple(sorted(options.items()))
