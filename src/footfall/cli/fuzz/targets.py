"""What a fuzz target is, and the registry of them.

A target turns one drawn case into a file or an argument list in a scratch directory, runs
the loader or command on it, and -- when it is accepted -- checks the result as a user
would rely on it (:mod:`.oracles`; :class:`~footfall.cli.fuzz.harness.Garbage` if not).
The targets register themselves: :mod:`.files` (map and model files, imported scans),
:mod:`.stores`, :mod:`.commands`; importing :mod:`footfall.cli.fuzz` loads them all.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hypothesis import strategies as st

from footfall.cli.fuzz.bases import Bases
from footfall.cli.fuzz.harness import Outcome, guarded
from footfall.core.registry import Registry


@dataclass(frozen=True)
class Target:
    """A loader or command under fuzz."""

    name: str
    cases: st.SearchStrategy  # what one input is made from
    work: Callable[[Any, Bases, Path], Callable[[], None]]  # (case, bases, scratch) -> work
    seconds: float = 10.0  # [s] the time limit of one input


TARGETS: Registry[Target] = Registry("fuzz target")
"""Every loader and command under fuzz, by name."""


def register_target(target: Target) -> Target:
    """Add ``target`` to :data:`TARGETS` (by its name)."""
    return TARGETS.register(target.name, target)


def run_case(target: Target, case: Any, bases: Bases, scratch: Path) -> Outcome:
    """Run one case of ``target`` in a fresh ``scratch`` directory and classify it."""
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    return guarded(target.name, repr(case)[:500], target.work(case, bases, scratch),
                   target.seconds)
