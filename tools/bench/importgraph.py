"""The call graph of one command: which of our modules it loads and how they import each other.

The command runs in a fresh interpreter; after it, the ``bille.*`` modules in ``sys.modules`` are
the nodes. Each node's syntax tree is read (imports at the top and inside functions alike) and
every import that resolves to another loaded node is an edge. A pair of modules that import each
other is counted once in ``both_ways``.
"""
from __future__ import annotations

import ast
import json
import subprocess
import sys

_PROBE = """
import json, sys
from bille.tools.cli import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
loaded = {name: getattr(mod, "__file__", None) for name, mod in list(sys.modules.items())
          if name == "bille" or name.startswith("bille.")}
sys.__stdout__.write("\\n@@modules@@" + json.dumps(loaded) + "\\n")
"""


def loaded_modules(argv: list[str]) -> dict[str, str | None]:
    """``{module: file}`` of our modules loaded by ``bille ARGV`` run in a fresh interpreter."""
    done = subprocess.run([sys.executable, "-c", _PROBE, *argv], capture_output=True, text=True)
    marker = done.stdout.rfind("@@modules@@")
    if marker < 0:
        raise RuntimeError(f"bille {' '.join(argv)} printed no module list: {done.stderr.strip()[-400:]}")
    return json.loads(done.stdout[marker + len("@@modules@@"):])


def imports_of(name: str, path: str, is_package: bool) -> set[str]:
    """The modules ``name`` (source at ``path``) imports, resolved to dotted names: for
    ``from X import y``, ``X.y`` when that is a module name and ``X`` as well."""
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read())
    package = name.split(".") if is_package else name.split(".")[:-1]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            out.add(module)
            out.update(f"{module}.{a.name}" for a in node.names)
    return out


def graph(argv: list[str]) -> dict:
    """Nodes, edges and the pairs imported both ways for ``bille ARGV``."""
    loaded = loaded_modules(argv)
    nodes = sorted(n for n, f in loaded.items() if f and f.endswith(".py"))
    edges = set()
    for name in nodes:
        path = loaded[name]
        for target in imports_of(name, path, path.endswith("__init__.py")):
            if target in loaded and target != name and target in nodes:
                edges.add((name, target))
    both = sorted({tuple(sorted(e)) for e in edges if (e[1], e[0]) in edges})
    return {"command": "bille " + " ".join(argv), "modules": nodes, "edges": sorted(edges), "both_ways": both}


def report(argv: list[str]) -> list[str]:
    """The graph's figures as lines of text, the pairs imported both ways listed."""
    g = graph(argv)
    lines = [f"{g['command']}: {len(g['modules'])} modules, {len(g['edges'])} import edges, "
             f"{len(g['both_ways'])} pairs both ways"]
    lines += [f"  {a} <-> {b}" for a, b in g["both_ways"]]
    return lines
