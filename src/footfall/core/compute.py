"""What this process may compute on: the one place that counts usable cores and starts worker
processes."""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager


def usable_cores() -> int:
    """The number of cores this process may run on (its CPU affinity), at least 1."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


@contextmanager
def worker_pool(processes: int) -> Iterator[ProcessPoolExecutor]:
    """``processes`` spawned worker processes (a fresh interpreter each: no forked BLAS or
    renderer state).

    Left normally, the pool finishes its work and closes. Left by an exception -- an error,
    Ctrl-C, a SIGTERM the command line turns into one, a consumer that stops early -- the
    queued work is cancelled and the workers are stopped at once: a worker in the middle of
    an hour-long task would otherwise run on without its driver, holding its memory.
    """
    pool = ProcessPoolExecutor(max_workers=processes, mp_context=multiprocessing.get_context(
        "spawn"))
    before = set(multiprocessing.active_children())
    try:
        yield pool
    except BaseException:
        workers = set(multiprocessing.active_children()) - before
        pool.shutdown(wait=False, cancel_futures=True)
        for worker in workers:
            worker.terminate()
        for worker in workers:
            worker.join(timeout=5.0)
        raise
    pool.shutdown(wait=True)
