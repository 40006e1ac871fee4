"""``--executor``, ``--ray-address`` and ``--processes``: where a command's batch of runs is walked.

Shared by every command that walks many runs (``walk-many``, ``reproduce``,
``ablation``); the executors themselves are :mod:`footfall.experiments.executors`.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import click

from footfall.cli.choices import RegistryChoice
from footfall.experiments.executors import EXECUTORS, Executor, make_executor


def _executor_names() -> tuple[str, ...]:
    return tuple(EXECUTORS)


def executor_options(f):
    """Add --processes, --executor and --ray-address to a command."""
    f = click.option("--ray-address", default=None, metavar="HOST:PORT",
                     help="With --executor ray: the address of a running Ray cluster "
                          "(`ray start --head` prints it); default: start one on this "
                          "machine, on the loopback interface.")(f)
    f = click.option("--executor", "executor_name", type=RegistryChoice(_executor_names),
                     default="local", show_default=True,
                     help="Where the runs are walked: a local process pool, or a Ray cluster "
                          "(pip install 'footfall[ray]'). The same seeds give the same runs "
                          "on either.")(f)
    return click.option("--processes", type=click.IntRange(1, 1024), default=None,
                        help="Parallel runs of the local pool, or the CPUs of a Ray cluster "
                             "started here [default: the available cores].")(f)


@contextlib.contextmanager
def opened_executor(name: str, processes: int | None,
                    address: str | None) -> Iterator[Executor]:
    """The executor the options chose, closed (its cluster connection ended) afterwards."""
    executor = make_executor(name, processes, address)
    try:
        yield executor
    finally:
        executor.close()
