"""Sweep files: instances x methods x option grids (``bille sweep SPEC.yaml``).

```yaml
name: small                     # optional; the results folder defaults to sweep-NAME
time_limit: 10                  # seconds per run (each run's own time_limit option wins)
memory_limit: 2000              # megabytes per run (optional)
instances:
  - compare-2                   # a bundled name
  - maps/*.yaml                 # files, globs relative to the sweep file
  - gen: random --moved 3 --robots 2 --seed 0..9   # a generator call, seeds as a range a..b
  - {instance: compare-2, moveset: S5}             # a name or file with another moveset
methods:
  temporal-astar: {horizon: [2, 5], epsilon: [1, 2]}   # every combination of the lists
  mstar: {}
  lacam: {improve: 0}           # a single value is a list of one
```

Every run is keyed by its instance's hash (the SHA-256 of its YAML, as ``bille`` writes it), the
method and its options, so a sweep started again skips the runs already recorded. Errors name
the file and the entry.
"""
from __future__ import annotations

import contextlib
import dataclasses
import glob
import io
import hashlib
import itertools
import json
import re
import tempfile
from dataclasses import dataclass
from pathlib import Path

import click
import yaml

from bille.instances import BilleError, OptionError, dump_instance, load_instance
from bille.instances.bundled import bundled_names, bundled_path
from bille.solvers import METHODS
from bille.solvers.options import check_options

_RANGE = re.compile(r"^(\d+)\.\.(\d+)$")


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
class Spec:
    name: str
    runs: list
    time_limit: float
    memory_limit: int | None


def _show(v) -> str:
    return "true" if v is True else "false" if v is False else str(v)


SHIPPED = Path(__file__).resolve().parent / "files"


def shipped_names() -> list[str]:
    return sorted(p.stem for p in SHIPPED.glob("*.yaml"))


def load_spec(path: str | Path) -> Spec:
    """Read a sweep file, or one shipped with bille by name (``small``, ``planners``); raises
    :class:`BilleError` naming the file and the entry at fault."""
    path = Path(path)
    if not path.exists() and str(path) in shipped_names():
        path = SHIPPED / f"{path}.yaml"
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise BilleError(f"{path}: cannot read ({exc.strerror}; shipped sweeps: {', '.join(shipped_names())})") from None
    except yaml.YAMLError as exc:
        raise BilleError(f"{path}: not YAML ({str(exc).splitlines()[0]})") from None
    return parse_spec(data, path)


def parse_spec(data, path: Path) -> Spec:
    def fail(msg):
        raise BilleError(f"{path}: {msg}")

    if not isinstance(data, dict):
        fail("expected a mapping with instances and methods")
    unknown = set(data) - {"name", "time_limit", "memory_limit", "instances", "methods"}
    if unknown:
        fail(f"unknown key {sorted(unknown)[0]!r} (expected name, time_limit, memory_limit, instances, methods)")
    time_limit = data.get("time_limit", 60)
    if isinstance(time_limit, bool) or not isinstance(time_limit, (int, float)) or time_limit <= 0:
        fail(f"time_limit: expected positive seconds, got {time_limit!r}")
    memory = data.get("memory_limit")
    if memory is not None and (isinstance(memory, bool) or not isinstance(memory, int) or memory < 50):
        fail(f"memory_limit: expected megabytes (at least 50), got {memory!r}")
    if not isinstance(data.get("instances"), list) or not data["instances"]:
        fail("instances: expected a list of bundled names, files, globs or {gen: ...} calls")
    if not isinstance(data.get("methods"), dict) or not data["methods"]:
        fail("methods: expected a mapping of method names to option grids")
    instances = [inst for k, entry in enumerate(data["instances"]) for inst in _instances(entry, path, k)]
    configs = [c for name, grid in data["methods"].items() for c in _configs(name, grid, path)]
    runs = [Run(label, text, method, options) for label, text in instances for method, options in configs]
    return Spec(str(data.get("name") or path.stem), runs, float(time_limit), memory)


def _instances(entry, path: Path, k: int):
    where = f"{path}: instances[{k}]"
    if isinstance(entry, dict) and set(entry) == {"gen"} and isinstance(entry["gen"], str):
        yield from _generated(entry["gen"], where)
        return
    if isinstance(entry, dict) and set(entry) == {"instance", "moveset"} and isinstance(entry["instance"], str):
        from bille.instances import check_instance, instance_from_text, load_moveset

        for label, text in _instances(entry["instance"], path, k):
            try:
                inst = check_instance(dataclasses.replace(instance_from_text(text), moveset=load_moveset(entry["moveset"])))
            except BilleError as exc:
                raise BilleError(f"{where}: {exc}") from None
            yield f"{label} {entry['moveset']}", dump_instance(inst)
        return
    if isinstance(entry, dict):
        raise BilleError(f"{where}: expected {{gen: 'GENERATOR OPTIONS'}} or {{instance: NAME, moveset: MOVESET}}, "
                         f"got {entry!r}")
    if not isinstance(entry, str):
        raise BilleError(f"{where}: expected a name, a file, a glob or {{gen: ...}}, got {entry!r}")
    if entry in bundled_names():
        yield entry, dump_instance(load_instance(bundled_path(entry)))
        return
    pattern = entry if Path(entry).is_absolute() else str(path.parent / entry)
    files = sorted(glob.glob(pattern))
    if not files:
        raise BilleError(f"{where}: {entry!r} is no bundled instance and matches no file")
    for f in files:
        yield Path(f).name.removesuffix(".yaml"), dump_instance(load_instance(f))


def _generated(call: str, where: str):
    """``random --moved 3 --seed 0..9``: the generator run once per seed of the range."""
    from ..gen import gen

    args = call.split()
    if not args or args[0] not in gen.commands:
        raise BilleError(f"{where}: unknown generator {args[0] if args else ''!r} "
                         f"(expected one of: {', '.join(sorted(gen.commands))})")
    seeds = [None]
    if "--seed" in args:
        k = args.index("--seed")
        if k + 1 >= len(args):
            raise BilleError(f"{where}: --seed needs a value or a range a..b")
        match = _RANGE.match(args[k + 1])
        if match:
            seeds = list(range(int(match.group(1)), int(match.group(2)) + 1))
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
                raise BilleError(f"{where}: {call!r}: {exc.format_message()}") from None
            label = " ".join(args) + ("" if seed is None else f" --seed {seed}")
            yield label, Path(f"{tmp}/i.yaml").read_text(encoding="utf-8")


def _configs(name, grid, path: Path):
    if name not in METHODS:
        raise BilleError(f"{path}: methods: unknown method {name!r} (expected one of: {', '.join(METHODS)})")
    if grid is None:
        grid = {}
    if not isinstance(grid, dict):
        raise BilleError(f"{path}: methods.{name}: expected a mapping of options to values or lists")
    keys = sorted(grid)
    lists = [grid[k] if isinstance(grid[k], list) else [grid[k]] for k in keys]
    for values in itertools.product(*lists):
        options = dict(zip(keys, values))
        try:
            check_options(name, METHODS[name], options, internal=("bounds", "progress", "incumbent"))
        except OptionError as exc:
            raise BilleError(f"{path}: methods.{name}: {exc}") from None
        yield name, tuple(sorted(options.items()))
