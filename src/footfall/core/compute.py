"""What this process may compute on: the one place that counts usable cores."""

from __future__ import annotations

import os


def usable_cores() -> int:
    """The number of cores this process may run on (its CPU affinity), at least 1."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)
