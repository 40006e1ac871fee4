"""The ``footfall`` command group and its entry point: user errors become one line and status 2.

The group finds its commands in the table of :mod:`footfall.cli.root` and imports
a command's module when the command is first asked for, so :func:`main` runs the
whole command line (the fuzz suite, :mod:`footfall.cli.fuzz`, drives it through
:func:`main` too) and ``footfall --help`` stays quick.
"""

from __future__ import annotations

import contextlib
import importlib
import signal
import sys
import threading
import warnings
from collections.abc import Iterator

import click

from footfall.cli.root import COMMANDS
from footfall.core.errors import FootfallError, one_line
from footfall.core.limits import apply_assignments, limits_of_one_command
from footfall.core.plugins import load_plugins

EXIT_USER_ERROR = 2  # a bad file or argument
EXIT_INTERRUPTED = 130  # Ctrl-C, as a shell reports SIGINT


class LazyGroup(click.Group):
    """A command group whose commands are imported by name from a table, when first used.

    The one deliberate import by name in footfall: a command's module and its
    dependencies load when that command runs, not for ``--help`` (which prints the
    table's lines of help).
    """

    def __init__(self, *args, table: dict[str, tuple[str, str, str]], **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.table = table

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(self.table) | set(self.commands))

    def get_command(self, ctx: click.Context | None, name: str) -> click.Command | None:
        if name not in self.commands and name in self.table:
            module, attribute, _ = self.table[name]
            command = getattr(importlib.import_module(module), attribute)
            self.add_command(refusing_repeats(command), name)
        return self.commands.get(name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        limit = formatter.width - 6 - max(len(name) for name in self.list_commands(ctx))
        rows = [(name, (self.commands[name] if name in self.commands else
                        click.Command(name, help=self.table[name][2])).get_short_help_str(limit))
                for name in self.list_commands(ctx)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


def repeated_option(command: click.Command, args: list[str]) -> str | None:
    """The first option of ``command`` that ``args`` give twice and that takes one value (or is
    a flag), as given; None if there is none. Options end at ``--``."""
    args = args[:args.index("--")] if "--" in args else args
    for param in command.params:
        if not isinstance(param, click.Option) or param.multiple or param.count \
                or not param.expose_value:
            continue
        names = [*param.opts, *param.secondary_opts]
        given = [a for a in args if a in names
                 or any(n.startswith("--") and a.startswith(n + "=") for n in names)]
        if len(given) > 1:
            return given[1].split("=", 1)[0]
    return None


def refusing_repeats(command: click.Command) -> click.Command:
    """``command`` (and a group's commands) refusing an option given twice: click would take
    the last silently (``--seed 1 --seed 2``), and which one the user meant is unknown."""
    if isinstance(command, click.Group):
        for sub in command.commands.values():
            refusing_repeats(sub)
        return command
    parse = command.parse_args

    def parse_args(ctx: click.Context, args: list[str]) -> list[str]:
        twice = repeated_option(command, args)
        if twice is not None:
            raise click.UsageError(f"{twice} is given twice: give it once", ctx)
        return parse(ctx, args)

    command.parse_args = parse_args  # type: ignore[method-assign]
    return command


@click.group(cls=LazyGroup, table=COMMANDS,
             context_settings={"help_option_names": ["-h", "--help"]})
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
    with limits_of_one_command(), _terminate_interrupts():  # --limit: this command only
        return _run(args, debug)


@contextlib.contextmanager
def _terminate_interrupts() -> Iterator[None]:
    """SIGTERM (``kill``, a scheduler's stop) interrupts the command as Ctrl-C does: its stores
    close, its worker processes are stopped, it exits with status 130 -- rather than dying
    with its workers left running. Only in the main thread (where signals are delivered)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


MISSING_GLYPH = r"Glyph \d+ .* missing from (current )?font"  # Matplotlib's warning on a
# character of a name or label its font cannot draw: the picture shows a box, not a failure


def _run(args: list[str], debug: bool) -> int:
    try:
        load_plugins()  # their learners, feature sets and terrain kinds become choices
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=MISSING_GLYPH, category=UserWarning)
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
