"""``footfall store``: check a demonstration store file, without changing it."""

from __future__ import annotations

import click

from footfall.cli.output import emit, json_option
from footfall.data.check import check_store


@click.group("store")
def store() -> None:
    """Inspect a demonstration store file (.sqlite)."""


@store.command("check")
@click.argument("store_path", metavar="STORE.sqlite")
@json_option
def store_check(store_path: str, as_json: bool) -> None:
    """Check every page, the schema and every row of a store; the file is only read.

    Prints "STORE: ok (...)" and exits 0, or one line per problem found (the
    first 20) and exits 2, the last line on standard error naming the first.
    """
    report = check_store(store_path)
    emit(as_json, report.as_dict(), "\n".join(report.lines()))
    if not report.ok:
        raise report.error()
