"""bille: multi-robot reconfiguration of 2D tile structures by Bill-E inchworm robots.

The layers are subpackages: :mod:`bille.instances` (the problem, the rules, files),
:mod:`bille.heuristics` (the planners), :mod:`bille.encodings` (the time-expanded model),
:mod:`bille.solvers` (``solve()``, the validator, bounds, exact and anytime solving) and
:mod:`bille.tools` (the command line). ``python -m bille`` is the ``bille`` command.
"""


def __getattr__(name: str):
    if name == "__version__":  # read on use: importlib.metadata is slow to load
        from importlib.metadata import PackageNotFoundError, version

        try:
            return version("bille")
        except PackageNotFoundError:  # run from a source tree that is not installed
            return "0+unknown"
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
