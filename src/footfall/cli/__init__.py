"""The ``footfall`` command line.

Every command has ``--help`` and ``--json``. A user error (a bad file, a bad
argument) prints one line on standard error and exits with status 2; a
traceback only with ``--debug``. A command parses its options, calls one
library function and prints the result it returns (:mod:`footfall.cli.output`);
choices come from the registries (:mod:`footfall.cli.choices`). The group and
its entry point are :mod:`footfall.cli.entry`; :mod:`footfall.cli.root` is the
table of every command.
"""

from footfall.cli.entry import EXIT_USER_ERROR, _console, cli, main

__all__ = ["EXIT_USER_ERROR", "_console", "cli", "main"]
