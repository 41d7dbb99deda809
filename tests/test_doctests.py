"""The examples in docstrings run."""
import doctest
import importlib
import pkgutil

import pytest

import bille

MODULES = sorted(
    m.name for pkg in ("instances", "solvers", "encodings", "heuristics", "tools")
    for m in pkgutil.walk_packages(importlib.import_module(f"bille.{pkg}").__path__, f"bille.{pkg}.")
    if m.name.rsplit(".", 1)[-1] not in ("__main__",)
)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"


def test_modules_found():
    assert len(MODULES) > 30 and "bille.instances.grid" in MODULES and bille
