"""Ctrl-C: a run cancelled, or held back while C code runs.

Inside ``solve()`` (:func:`cancelling`) the first Ctrl-C only cancels the run's budget
(:mod:`.run`): every search polls it and ends with what it holds, and no exception unwinds
through anything. A second Ctrl-C raises ``KeyboardInterrupt`` as usual, for a user who wants out
at once.

Outside it, Ctrl-C is Python's ``KeyboardInterrupt``, and :func:`held_back` keeps it out of C code.

A ``KeyboardInterrupt`` that arrives inside a C extension is not always raised as one: python-sat's
encoders and solvers install a SIGINT handler of their own, which jumps out of the C++ code
(``pycard.error: Caught keyboard interrupt``), and some numpy paths clear it. Inside
:func:`held_back` SIGINT is blocked for this thread and only recorded by Python, and python-sat is
told it runs outside the main thread, so it installs no handler: a Ctrl-C sent to the process
goes to another thread that does not block it (numpy's BLAS workers), and python-sat's handler,
had it been installed, would jump from that thread into the main thread's stack (it crashed the
process in about 1 run in 10). The Ctrl-C is raised as an ordinary ``KeyboardInterrupt`` once the
block is done, at a point where Python code can unwind and keep what the run found. Outside the
main thread (where Python delivers no signal) the block runs as it is; where a handler other than
Python's default one is installed (:func:`cancelling`'s, which raises nothing), python-sat is
still told it is not in the main thread, and the signal goes to that handler. Threads that run solvers block SIGINT for good
(:func:`quiet_thread`), so that a terminal's Ctrl-C always reaches the main thread.
"""
from __future__ import annotations

import signal
import sys
import threading
from contextlib import contextmanager
from typing import Iterator

_SIGINT = {signal.SIGINT}


@contextmanager
def held_back() -> Iterator[None]:
    """Run the block with Ctrl-C held, not raised; raise it (once) when the block ends.

    >>> with held_back():
    ...     pass
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    with _pysat_outside_main():
        if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:  # cancelling(), or the user's own
            yield
            return
        caught: list[int] = []
        signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, _SIGINT)
        try:
            yield
        finally:
            try:  # unblocked first: a Ctrl-C that waited is recorded, not raised in the middle of this
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)
            finally:
                signal.signal(signal.SIGINT, signal.default_int_handler)
    if caught:
        raise KeyboardInterrupt


@contextmanager
def cancelling(budget) -> Iterator[None]:
    """Run the block with Ctrl-C cancelling ``budget`` (the first one) or raising
    ``KeyboardInterrupt`` (the second), in the main thread where Python's default handler is
    installed; elsewhere the block runs as it is. python-sat is told it runs outside the main
    thread inside :func:`held_back`, so that it installs no handler of its own."""
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return

    def cancel(signum, frame) -> None:
        if budget.cancelled:
            raise KeyboardInterrupt
        budget.cancel()

    signal.signal(signal.SIGINT, cancel)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)


@contextmanager
def _pysat_outside_main() -> Iterator[None]:
    """python-sat's test for the main thread answers no in the block."""
    main_thread = getattr(sys.modules.get("pysat._utils"), "MainThread", None)
    check = None if main_thread is None else main_thread.__dict__.get("check")
    if check is not None:
        main_thread.check = staticmethod(_not_main)
    try:
        yield
    finally:
        if check is not None:
            main_thread.check = check


def _not_main() -> bool:
    """python-sat's test for the main thread, inside :func:`held_back` (module docstring)."""
    return False


def quiet_thread() -> None:
    """Block SIGINT in the calling thread (not the main one): the kernel then hands a Ctrl-C to
    the main thread, the one Python raises it in."""
    if threading.current_thread() is not threading.main_thread():
        signal.pthread_sigmask(signal.SIG_BLOCK, _SIGINT)
