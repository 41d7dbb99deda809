"""Compiling a function with Numba, its machine code cached on disk (the modules that compile
import this where they are used: loading Numba takes a few tenths of a second)."""
from __future__ import annotations

import sys


def loaded() -> bool:
    """Whether this process has loaded Numba already: compiled code then costs no start-up, so
    it may serve problems smaller than those worth loading Numba for."""
    return "numba" in sys.modules


def jit(function):
    """``function`` compiled, its machine code cached where Numba finds a writable place (beside
    its file, or in the user's cache); compiled again in each process where it finds none."""
    from numba import njit

    try:
        return njit(cache=True)(function)
    except RuntimeError:  # Numba: "cannot cache function ...: no locator available"
        return njit(function)
