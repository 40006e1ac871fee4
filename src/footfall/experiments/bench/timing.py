"""The benchmarks' clock: the best of several timings of the same work."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def best_time(work: Callable[[], object], repeats: int) -> float:
    """The shortest wall time [s] of ``repeats`` calls of ``work`` (the least disturbed one)."""
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        work()
        best = min(best, time.perf_counter() - t)
    return best
