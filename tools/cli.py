"""The ``bille`` command line: load -> (solve) -> validate -> save -> print, each a library call.

Exit codes (DESIGN §5): 0 success, 1 a negative answer (invalid schedule, invalid instance shown,
infeasible, timeout without schedule), 2 bad input or usage. A user error is one line on stderr.
"""
from __future__ import annotations

import sys

import click

from bille.instances import BilleError

from .bench.commands import bench
from .common import EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE
from .convert import convert
from .execute.commands import robot_sim, run
from .files_commands import check, list_, show
from .gen import gen
from .methods_command import methods
from .solve_commands import gap, plan_sequence, solve_
from .sweep.commands import sweep
from .view_commands import view


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(None, "--version", package_name="bille", prog_name="bille", message="%(prog)s %(version)s")
def cli() -> None:
    """Multi-robot reconfiguration of 2D tile structures by Bill-E inchworm robots.

    INSTANCE and SCHEDULE are YAML files, or the names of bundled ones (see 'bille list').
    """

for command in (check, show, list_, solve_, methods, plan_sequence, gap, sweep, view, gen, convert, run, robot_sim,
                bench):
    cli.add_command(command)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bille`` console script."""
    try:
        code = cli.main(args=argv, prog_name="bille", standalone_mode=False)
    except click.exceptions.UsageError as exc:
        cmd = exc.ctx.command_path if exc.ctx else "bille"
        click.echo(f"{cmd}: {exc.format_message().rstrip('.')} (see '{cmd} --help')", err=True)
        code = EXIT_USAGE
    except click.exceptions.Abort:
        click.echo("bille: interrupted", err=True)
        code = EXIT_INTERRUPTED
    except BilleError as exc:
        click.echo(f"bille: error: {exc}", err=True)
        code = EXIT_USAGE
    except BrokenPipeError:
        code = EXIT_OK
    sys.exit(code if isinstance(code, int) else EXIT_OK)


if __name__ == "__main__":
    main()
