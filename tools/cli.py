"""The ``bille`` command line: load -> (solve) -> validate -> save -> print, each a library call.

Exit codes (docs/decisions.md, "The solve() contract"):
0 success, 1 a negative answer (invalid schedule, invalid instance shown,
infeasible, timeout without schedule), 2 bad input or usage. A user error is one line on stderr.
"""
from __future__ import annotations

import importlib
import sys

import click

from bille.instances import BilleError

from .common import EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE, interrupted_json

COMMANDS = {  # name -> (module, function, the line bille --help shows); each loaded when it runs
    "check": ("files_commands", "check", "Check a schedule against the rules of an instance."),
    "show": ("files_commands", "show", "Draw an instance: sizes, movesets, validity."),
    "list": ("files_commands", "list_", "List the bundled instances and their schedules."),
    "solve": ("solve_commands", "solve_", "Solve an instance: status, metrics, schedule."),
    "methods": ("methods_command", "methods", "What each method plans for, proves, and its options."),
    "plan-sequence": ("solve_commands", "plan_sequence", "The reconfiguration sequence of an instance."),
    "gap": ("solve_commands", "gap", "Methods against the optimum: certified gaps."),
    "sweep": ("sweep.commands", "sweep", "Experiments: instances x methods x options."),
    "view": ("view_commands", "view", "Schedules as a rerun recording, picture or GIF."),
    "gen": ("gen", "gen", "Generate instances (random, paper maps, graphs)."),
    "convert": ("convert", "convert", "Instances and schedules to and from other formats."),
    "run": ("execute.commands", "run", "Execute a schedule on robots over MQTT."),
    "robot-sim": ("execute.commands", "robot_sim", "A simulated robot for bille run."),
    "bench": ("bench.commands", "bench", "Benchmarks, with ratios to baselines of the run."),
    "warm": ("warm_command", "warm", "Compile the solvers' compiled parts now (the first run's cost)."),
}


class Commands(click.Group):
    """The subcommands of :data:`COMMANDS`, each module imported when its command is looked up
    (click's lazy group), so that a light command starts without loading the others."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in COMMANDS:
            return None
        module, function, _ = COMMANDS[name]
        return getattr(importlib.import_module(f"{__package__}.{module}"), function)

    def resolve_command(self, ctx: click.Context, args: list[str]):
        try:
            return super().resolve_command(ctx, args)
        except click.exceptions.NoSuchCommand:  # suggest from every name, loaded or not
            raise click.exceptions.NoSuchCommand(str(args[0]), possibilities=list(COMMANDS), ctx=ctx) from None

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        with formatter.section("Commands"):
            formatter.write_dl([(name, COMMANDS[name][2]) for name in self.list_commands(ctx)])


@click.group(cls=Commands, context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(None, "--version", package_name="bille", prog_name="bille", message="%(prog)s %(version)s")
def cli() -> None:
    """Multi-robot reconfiguration of 2D tile structures by Bill-E inchworm robots.

    INSTANCE and SCHEDULE are YAML files, or the names of bundled ones (see 'bille list').
    """


# flags looked for where they are not, and where what they would do lives
ELSEWHERE = {
    "--seed": "a method's seed is an option of the method (-O seed=N: lacam; bille methods METHOD lists them), "
              "a generator's is bille gen KIND --seed",
    "--jobs": "runs side by side are bille sweep's (--jobs)",
    "-j": "runs side by side are bille sweep's (--jobs)",
    "-v": "there is no verbose mode: --json prints all a run tells (stats), and a terminal shows a live line",
    "--verbose": "there is no verbose mode: --json prints all a run tells (stats), and a terminal shows a live line",
}


# the libraries of the optional dependencies (pyproject.toml's extras) and the extra that installs them
EXTRAS = {"distributed": "sweep", "dask": "sweep", "paho": "execute", "amqtt": "execute", "jsonschema": "execute"}


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bille`` console script."""
    try:
        code = cli.main(args=argv, prog_name="bille", standalone_mode=False)
    except click.exceptions.UsageError as exc:
        cmd = exc.ctx.command_path if exc.ctx else "bille"
        message = exc.format_message().rstrip(".")
        message = message[:1].lower() + message[1:]  # one style with every other error line
        hint = ELSEWHERE.get(exc.option_name) if isinstance(exc, click.NoSuchOption) else None
        if hint:  # instead of click's guess at a near name
            message = f"no such option '{exc.option_name}'; {hint}"
        click.echo(f"bille: error: {message} (see '{cmd} --help')", err=True)
        code = EXIT_USAGE
    except (click.exceptions.Abort, KeyboardInterrupt):
        click.echo("bille: interrupted", err=True)
        interrupted_json(sys.argv[1:] if argv is None else argv)
        code = EXIT_INTERRUPTED
    except BilleError as exc:
        click.echo(f"bille: error: {exc}", err=True)
        code = EXIT_USAGE
    except BrokenPipeError:
        code = EXIT_OK
    except ModuleNotFoundError as exc:
        extra = EXTRAS.get((exc.name or "").partition(".")[0])
        if extra is None:
            raise
        click.echo(f"bille: error: this command needs {exc.name.partition('.')[0]}, part of bille's optional "
                   f"'{extra}' dependencies: pip install 'bille[{extra}]'", err=True)
        code = EXIT_USAGE
    sys.exit(code if isinstance(code, int) else EXIT_OK)


if __name__ == "__main__":
    main()
