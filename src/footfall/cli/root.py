"""The ``footfall`` command group and its entry point: user errors become one line and status 2.

Every command lives in the module of its group (terrain, features, demos, store, learning,
walking, experiments, bench) and is added here.
"""

from __future__ import annotations

import sys

import click

from footfall.cli.bench import bench
from footfall.cli.demos import demos
from footfall.cli.experiments import ablation, demo, offline, reproduce, study
from footfall.cli.features import features
from footfall.cli.learning import learn, rank_eval_cmd
from footfall.cli.store import store
from footfall.cli.teach import teach
from footfall.cli.terrain import terrain
from footfall.cli.walking import walk_cmd, walk_many_cmd
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


for _command in (terrain, features, demos, store, learn, rank_eval_cmd, walk_cmd,
                 walk_many_cmd, offline, reproduce, study, ablation, demo, bench, teach):
    cli.add_command(_command)


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
