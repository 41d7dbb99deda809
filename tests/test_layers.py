"""The layers of docs/decisions.md, "Layers and proofs", one way with no exceptions, and modules small enough to read.

``instances`` imports nothing of ours; ``heuristics`` and ``encodings`` import only
``instances``; ``solvers`` imports ``instances``, ``heuristics`` and ``encodings``; ``tools``
imports anything; nothing imports ``tools``. Every import counts, inside functions too: the test
walks each module's syntax tree.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
LAYERS = ("instances", "heuristics", "encodings", "solvers", "tools")
ALLOWED = {
    "instances": set(),
    "heuristics": {"instances"},
    "encodings": {"instances"},
    "solvers": {"instances", "heuristics", "encodings"},
    "tools": {"instances", "heuristics", "encodings", "solvers"},
}
MAX_LINES = 400


def modules():
    for layer in LAYERS:
        for path in sorted((ROOT / layer).rglob("*.py")):
            yield layer, path


def imported_layers(path: Path, layer: str):
    """``(line, layer)`` of every import of another of our layers in the module."""
    package = ("bille",) + path.relative_to(ROOT).with_suffix("").parts[:-1]
    return layers_in(path.read_text(encoding="utf-8"), package)


def layers_in(source: str, package: tuple[str, ...]):
    """``(line, layer)`` of every import of one of our layers in ``source``, a module of
    ``package`` (relative imports resolve against it)."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: resolve against the module's package
                base = package[: len(package) - node.level + 1]
                names = [".".join(base + ((node.module,) if node.module else ()))]
            else:
                names = [node.module or ""]
        else:
            continue
        for name in names:
            parts = name.split(".")
            if parts[0] == "bille" and len(parts) > 1 and parts[1] in LAYERS:
                yield node.lineno, parts[1]


@pytest.mark.parametrize("layer, path", list(modules()), ids=lambda v: str(v.relative_to(ROOT)) if isinstance(v, Path) else v)
def test_imports_go_one_way(layer, path):
    bad = [(line, other) for line, other in imported_layers(path, layer)
           if other != layer and other not in ALLOWED[layer]]
    assert not bad, f"{path.relative_to(ROOT)} imports " + ", ".join(f"bille.{o} (line {n})" for n, o in bad)


def test_the_layer_walker_sees_function_level_and_relative_imports():
    probe = "def f():\n    from bille.solvers import solve\n    from ..tools import cli\n"
    assert sorted(o for _, o in layers_in(probe, ("bille", "heuristics"))) == ["solvers", "tools"]


@pytest.mark.parametrize("layer, path", list(modules()), ids=lambda v: str(v.relative_to(ROOT)) if isinstance(v, Path) else v)
def test_modules_stay_small(layer, path):
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(ROOT)} has {lines} lines (at most {MAX_LINES}: split it by concept)"


def test_no_two_modules_import_each_other():
    # the rule of `bille bench imports`, over every module rather than those one command loads
    from bille.tools.bench.importgraph import imports_of

    def name(path: Path) -> str:
        parts = path.relative_to(ROOT).with_suffix("").parts
        return ".".join(("bille",) + (parts[:-1] if parts[-1] == "__init__" else parts))

    paths = {name(path): path for _, path in modules()}
    edges = {(module, target) for module, path in paths.items()
             for target in imports_of(module, str(path), path.name == "__init__.py")
             if target in paths and target != module}
    both = sorted({tuple(sorted(edge)) for edge in edges if edge[::-1] in edges})
    assert not both, "modules that import each other: " + ", ".join(f"{a} <-> {b}" for a, b in both)
