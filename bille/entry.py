"""The ``bille`` console script: from its first instant on, Ctrl-C ends it with one line (and,
with ``--json``, one JSON object) and exit code 130, never a traceback."""
import os
import signal
import sys


def _early(signum, frame) -> None:
    """Ctrl-C while the command line loads: nothing has run, nothing is written."""
    os.write(2, b"bille: interrupted\n")
    if "--json" in sys.argv[1:]:
        os.write(1, b'{"status": "interrupted", "stats": {"failure": "interrupted before the command started"}}\n')
    os._exit(130)


def main() -> None:
    signal.signal(signal.SIGINT, _early)
    from bille.tools.cli import main as command_line

    signal.signal(signal.SIGINT, signal.default_int_handler)  # from here on the command's own handling
    try:
        command_line()
    except KeyboardInterrupt:  # after the command's own handling, before the exit: its answer is out
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        sys.exit(130)
    finally:  # the exit itself (flushing, clean-ups) is not interrupted
        signal.signal(signal.SIGINT, signal.SIG_IGN)
