import os
import signal

import pytest

from hypothesis import HealthCheck, settings

# Deterministic property tests: the same examples on every run and machine.
settings.register_profile(
    "default", derandomize=True, deadline=None, max_examples=150,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("thorough", deadline=None, max_examples=2000, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("BILLE_HYPOTHESIS", "default"))


@pytest.fixture(autouse=True)
def _ctrl_c_as_python_sets_it():
    """Every test starts with Ctrl-C as Python sets it up (its handler, not blocked), whatever an
    earlier test did in this process."""
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    yield


@pytest.fixture
def cli():
    """``cli(argv)``: the command line's exit code for the argument list."""
    from bille.tools.cli import main

    def run(argv) -> int:
        with pytest.raises(SystemExit) as exc:
            main([str(a) for a in argv])
        return exc.value.code
    return run


@pytest.fixture
def rejects(cli, capsys):
    """``rejects(argv, message, out=None)``: the arguments (with ``-o out`` if given) are bad
    input: exit 2, one line on stderr that contains ``message``, and nothing written to ``out``."""
    def check(argv, message, out=None) -> None:
        capsys.readouterr()
        assert cli([*argv, "-o", out] if out is not None else argv) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
        assert out is None or not out.exists()
    return check
