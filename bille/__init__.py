"""bille: multi-robot reconfiguration of 2D tile structures by Bill-E inchworm robots.

The layers are subpackages: :mod:`bille.instances` (the problem, the rules, files),
:mod:`bille.heuristics` (the planners), :mod:`bille.encodings` (the time-expanded model),
:mod:`bille.solvers` (``solve()``, the validator, bounds, exact and anytime solving) and
:mod:`bille.tools` (the command line). ``python -m bille`` is the ``bille`` command.

One package, found the same way everywhere: a ``bille`` folder met earlier on ``sys.path`` (the
repository's own, when Python runs from its root) shares its path with the installed one
(``pkgutil.extend_path``), so ``bille.instances`` and the rest are found wherever they live.
"""
from pkgutil import extend_path

__path__ = extend_path(__path__, __name__)


def __getattr__(name: str):
    if name == "__version__":  # read on use: importlib.metadata is slow to load
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("bille")
        except PackageNotFoundError:  # run from a source tree that is not installed
            return "0+unknown"
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
