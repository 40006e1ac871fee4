"""How every command prints: its figures as JSON with ``--json``, as text otherwise.

Progress goes to standard error, so that standard output holds only the result.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Callable, Iterator
from typing import Any

import click

from footfall.core.files import plain_json
from footfall.core.progress import BatchProgress

json_option = click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")


def emit(as_json: bool, data: dict[str, Any], text: str) -> None:
    """Print a command's result: ``data`` as JSON, or ``text``.

    JSON has no NaN or infinity: a figure that is not defined (NaN) or not finite is
    printed as null, never as the invalid token ``NaN`` and never as a traceback.
    """
    if as_json:
        click.echo(json.dumps(plain_json(data, nonfinite="null"), indent=2, allow_nan=False))
    else:
        click.echo(text)


def progress_log(as_json: bool) -> Callable[[str], None]:
    """A log of progress lines on standard error; silent with ``--json``."""
    if as_json:
        return lambda line: None
    return lambda line: click.echo(line, err=True)


@contextlib.contextmanager
def progress_bar(total: int | Callable[[], int], desc: str, unit: str, quiet: bool,
                 failed: Callable[[Any], bool] | None = None,
                 log_lines: bool = False) -> Iterator[Callable[[Any], None]]:
    """A step counter on standard error (not with ``quiet``): a bar on a terminal; with
    ``log_lines`` (batches of runs, minutes long) a line every few steps otherwise
    (:class:`footfall.core.progress.BatchProgress`).

    ``failed`` says of a finished item whether it failed (counted in the lines). The
    progress opens at the first step, so that an argument refused before any work leaves
    the error as the only line; ``total`` may be a function, asked then (the items left
    once a resumed batch knows what it holds).
    """
    bar = None
    started = time.monotonic()  # the work began here, before the first item finished

    def step(item: Any) -> None:
        nonlocal bar
        if bar is None:
            bar = BatchProgress(total() if callable(total) else total, desc, unit, quiet=quiet,
                                lines=log_lines, started=started)
        bar.update(None if failed is None else failed(item))

    try:
        yield step
    finally:
        if bar is not None:
            bar.close()
