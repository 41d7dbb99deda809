"""Reading YAML while remembering where every value came from.

Errors in user files must name the file, the line and the field (docs/files.md), so files are read
into plain Python data plus a :class:`Source` that maps each field path, e.g.
``("robots", 1, "front")``, to its line. The small ``expect_*`` helpers check types and raise
the caller's error class with that location.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import BilleError, where

try:  # libyaml when present: large schedules parse several times faster
    _Loader = yaml.CSafeLoader
except AttributeError:  # pragma: no cover - depends on the PyYAML build
    _Loader = yaml.SafeLoader

Path_ = tuple  # a field path: keys and list indices


def field_name(path: Path_) -> str:
    """``("robots", 1, "front")`` -> ``"robots[1].front"``."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


@dataclass
class Source:
    """Where the values of one YAML document came from."""

    name: str | None
    error: type[BilleError] = BilleError
    lines: dict[Path_, int] = field(default_factory=dict)
    text_start: dict[Path_, int] = field(default_factory=dict)  # first content line of block text

    def line(self, path: Path_) -> int | None:
        """Line of the field, or of its closest enclosing field that has one."""
        path = tuple(path)
        while path not in self.lines and path:
            path = path[:-1]
        return self.lines.get(path)

    def at(self, path: Path_ = (), line: int | None = None) -> str:
        return where(self.name, line if line is not None else self.line(path), field_name(path))

    def fail(self, path: Path_, message: str, line: int | None = None) -> BilleError:
        """An error of this source's class, located at ``path`` (return it, then ``raise``)."""
        return self.error(f"{self.at(path, line)}{message}")


def load_yaml_text(text: str, name: str | None, error: type[BilleError]) -> tuple[Any, Source]:
    """Parse one YAML document into plain data and its :class:`Source`.

    Raises ``error`` for YAML syntax errors, duplicate keys and empty documents.
    """
    src = Source(name, error)
    try:
        _refuse_aliases(text, src)
        node = yaml.compose(text, Loader=_Loader)
        if node is None:
            raise src.fail((), "the file is empty")
        _record_lines(node, (), src)
        data = yaml.constructor.SafeConstructor().construct_document(node)
    except yaml.YAMLError as exc:
        raise _yaml_failure(exc, src) from None
    return data, src


def _refuse_aliases(text: str, src: Source) -> None:
    """Our files need no anchors and aliases, and an alias can make a few lines expand to
    gigabytes (the "billion laughs"): the first alias is refused, by its line, before anything
    is built."""
    for event in yaml.parse(text, Loader=_Loader):
        if isinstance(event, yaml.AliasEvent):
            raise src.fail((), f"YAML aliases (*{event.anchor}) are not allowed in bille files",
                           event.start_mark.line + 1)


def _yaml_failure(exc: yaml.YAMLError, src: Source) -> BilleError:
    """PyYAML's several-line messages as one line: the problem and its line."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    what = getattr(exc, "problem", None) or getattr(exc, "context", None) or str(exc).splitlines()[0]
    return src.fail((), f"YAML syntax error: {what}", mark.line + 1 if mark else None)


def mrp_name(path: str | Path) -> bool:
    """Whether a file name asks for libMultiRobotPlanning YAML (``*.mrp.yaml``; the format is
    :mod:`.interop`'s, the name is read here so that reading a bille file does not load it)."""
    return Path(path).name.endswith((".mrp.yaml", ".mrp.yml"))


def load_yaml_file(path: str | Path, error: type[BilleError]) -> tuple[Any, Source]:
    """Read and parse a YAML file; unreadable files raise ``error`` naming the path."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{path}: no such file") from None
    except IsADirectoryError:
        raise error(f"{path}: is a directory, expected a YAML file") from None
    except UnicodeDecodeError as exc:
        raise error(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise error(f"{path}: cannot read ({exc.strerror})") from None
    return load_yaml_text(text, str(path), error)


def _record_lines(node: yaml.Node, path: Path_, src: Source) -> None:
    src.lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        seen: set = set()
        for key_node, value_node in node.value:
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            if key in seen:
                raise src.fail(path, f"duplicate key '{key}'", key_node.start_mark.line + 1)
            seen.add(key)
            _record_lines(value_node, path + (key,), src)
            # a key's own line is more precise than its value's for block values
            src.lines[path + (key,)] = key_node.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _record_lines(item, path + (i,), src)
    elif node.style in ("|", ">"):
        src.text_start[path] = node.start_mark.line + 2


# ----------------------------------------------------------------------------------------------
# typed access


def expect_mapping(value: Any, src: Source, path: Path_, *, required=(), optional=()) -> dict:
    """Check that ``value`` is a mapping with exactly the allowed keys."""
    if not isinstance(value, dict):
        raise src.fail(path, f"expected a mapping, got {_kind(value)}")
    allowed = tuple(dict.fromkeys((*required, *optional)))  # each once, in order
    for key in value:
        if key not in allowed:
            raise src.fail(path + (key,), f"unknown field (expected one of: {', '.join(allowed)})")
    for key in required:
        if key not in value:
            raise src.fail(path, f"missing field '{key}'")
    return value


def expect_list(value: Any, src: Source, path: Path_, what: str = "a list") -> list:
    if not isinstance(value, list):
        raise src.fail(path, f"expected {what}, got {_kind(value)}")
    return value


def expect_str(value: Any, src: Source, path: Path_, what: str = "a string") -> str:
    if not isinstance(value, str) or not value:
        raise src.fail(path, f"expected {what}, got {_kind(value)}")
    return value


def expect_bool(value: Any, src: Source, path: Path_) -> bool:
    if not isinstance(value, bool):
        raise src.fail(path, f"expected true or false, got {_kind(value)}")
    return value


def expect_xy(value: Any, src: Source, path: Path_) -> tuple[int, int]:
    """A coordinate pair ``[x, y]`` of integers."""
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, int) and not isinstance(v, bool) for v in value)
    ):
        raise src.fail(path, f"expected a pair of integers [x, y], got {_kind(value)}")
    return int(value[0]), int(value[1])


def _kind(value: Any) -> str:
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, (int, float)):
        return f"the number {value}"
    if isinstance(value, str):
        shown = value if len(value) <= 40 else value[:37] + "..."
        return f"the string {shown!r}"
    if isinstance(value, list):
        return f"a list of {len(value)}" if len(value) != 2 else f"{value!r}"
    if isinstance(value, dict):
        return "a mapping"
    return type(value).__name__
