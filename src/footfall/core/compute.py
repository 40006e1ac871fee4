"""What this process may compute on: the one place that counts usable cores and free memory,
and starts worker processes."""

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


def available_memory() -> int | None:
    """Bytes of memory the machine can give new work without swapping (Linux's MemAvailable),
    or None where it cannot be read."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def jobs_that_fit(jobs: int, each: int, available: int | None, spare: float = 0.25) -> int:
    """How many of ``jobs`` tasks, each needing ``each`` bytes, may run at once in ``available``
    bytes while ``spare`` of them stays free: at least 1, at most ``jobs`` (all of them where
    the memory is unknown)."""
    if available is None or each <= 0:
        return max(1, jobs)
    return max(1, min(jobs, int(available * (1.0 - spare)) // each))


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
