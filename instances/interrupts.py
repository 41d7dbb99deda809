"""Ctrl-C held back while C code runs.

A ``KeyboardInterrupt`` that arrives inside a C extension is not always raised as one: python-sat's
encoders turn it into their own error (``pycard.error: Caught keyboard interrupt``), and some numpy
paths clear it. Inside :func:`held_back` the interrupt is only recorded, and raised as an ordinary
``KeyboardInterrupt`` once the block is done, at a point where Python code can unwind and keep what
the run found. Outside the main thread (where Python delivers no signal) and where a handler other
than Python's default one is installed, the block runs as it is.
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def held_back() -> Iterator[None]:
    """Run the block with Ctrl-C recorded, not raised; raise it (once) when the block ends.

    >>> with held_back():
    ...     pass
    """
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    caught: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    if caught:
        raise KeyboardInterrupt
