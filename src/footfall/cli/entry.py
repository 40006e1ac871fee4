"""The ``footfall`` command group and its entry point: user errors become one line and status 2.

The group holds no commands itself: :mod:`footfall.cli.root` adds every command
group's commands to it when :mod:`footfall.cli` is imported, so :func:`main` runs
the whole command line (the fuzz suite, :mod:`footfall.cli.fuzz`, drives it
through :func:`main` too).
"""

from __future__ import annotations

import sys

import click

from footfall.core.errors import FootfallError, one_line
from footfall.core.limits import apply_assignments, limits_of_one_command
from footfall.core.plugins import load_plugins

EXIT_USER_ERROR = 2  # a bad file or argument
EXIT_INTERRUPTED = 130  # Ctrl-C, as a shell reports SIGINT


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks for errors.")
@click.option("--limit", "limits", multiple=True, metavar="NAME=VALUE",
              help="Raise (or lower) a size limit, e.g. max_map_cells=400000000; "
                   "see docs/configuration.md.")
@click.version_option(package_name="footfall")
def cli(debug: bool, limits: tuple[str, ...]) -> None:
    """footfall: learning where a legged robot should put its feet, with terrain templates."""
    apply_assignments(limits)


def main(argv: list[str] | None = None) -> int:
    """Entry point: run the CLI, turning user errors into one line and exit status 2."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    with limits_of_one_command():  # --limit holds for this command (and its workers) only
        return _run(args, debug)


def _run(args: list[str], debug: bool) -> int:
    try:
        load_plugins()  # their learners, feature sets and terrain kinds become choices
        cli.main(args=args, prog_name="footfall", standalone_mode=False)
    except FootfallError as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {one_line(str(exc))}", err=True)
        return EXIT_USER_ERROR
    except click.exceptions.Abort:
        click.echo("footfall: interrupted", err=True)
        return EXIT_INTERRUPTED
    except click.ClickException as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {one_line(exc.format_message())} (see --help)", err=True)
        return EXIT_USER_ERROR
    except (OSError, MemoryError) as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {one_line(str(exc)) or type(exc).__name__}", err=True)
        return EXIT_USER_ERROR
    return 0


def _console() -> None:  # pragma: no cover - the console script
    sys.exit(main())
