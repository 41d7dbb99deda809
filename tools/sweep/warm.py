"""Imported by the fork server of a sweep's runs: every module of the layers a run uses, and the
libraries they import where used, so that each run starts with them loaded (in milliseconds) and
its memory limit counts on top of them, whatever its method imports."""
import importlib
import pkgutil

import bille.encodings
import bille.heuristics
import bille.instances
import bille.solvers

for _package in (bille.instances, bille.heuristics, bille.encodings, bille.solvers):
    for _module in pkgutil.walk_packages(_package.__path__, _package.__name__ + "."):
        importlib.import_module(_module.name)
for _library in ("scipy.ndimage", "pysat.card", "ortools.sat.python.cp_model"):
    importlib.import_module(_library)
