"""Named random streams: every purpose of an experiment draws its seeds from a stream of its own.

Seeds computed by arithmetic (``1000 * seed + 100 * r + i``) collide: one
experiment seed's correction runs reuse another's evaluation runs, and a
study over several seeds silently shares randomness between them. Here a
seed is drawn from ``numpy.random.SeedSequence(entropy=experiment seed,
spawn_key=(experiment, purpose, *indices))``: streams of different
experiments, seeds, purposes or indices are independent, and a new purpose
takes a new name instead of a new offset.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError

# Every experiment and purpose, by name. Append only: the position is the stream's spawn key,
# so reordering these would change every published number.
EXPERIMENTS = ("reproduce", "offline", "learning curve", "terrain suite")
PURPOSES = (
    "boards",           # terrain boards (training, test, flat, sweep)
    "correction runs",  # the robot's runs whose logs the expert corrects
    "inspection",       # the expert's own randomness while it inspects a run log
    "evaluation runs",  # the paired runs of Table II
    "sweep runs",       # runs on the difficulty sweep's boards
    "demonstrations",   # the synthetic expert's demonstrations (walker)
    "learning",         # the learner: template library sample, training pairs
    "calibration runs",  # the expert's runs on the calibration boards (the test difficulty)
    "confirmation runs",  # the expert's runs on the boards that confirm the test difficulty
)
SEED_BITS = 63  # seeds are non-negative 63-bit integers: any store or file keeps them exactly


@dataclass(frozen=True)
class SeedStreams:
    """The seed streams of one experiment run with seed ``seed``.

    ``streams.seed("evaluation runs", k)`` is the seed of the k-th
    evaluation run: an integer in [0, 2**63); the same arguments give the
    same seed, any other arguments an independent one.
    """

    experiment: str  # one of EXPERIMENTS
    seed: int  # the experiment's seed (>= 0), e.g. ``footfall reproduce --seed``

    def __post_init__(self) -> None:
        if self.experiment not in EXPERIMENTS:
            raise FootfallError(f"unknown experiment {self.experiment!r}; "
                                f"streams exist for {', '.join(EXPERIMENTS)}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, numbers.Integral) \
                or self.seed < 0:
            raise FootfallError(f"an experiment seed is an integer >= 0, got {self.seed!r}")

    def sequence(self, purpose: str, *index: int) -> np.random.SeedSequence:
        """The SeedSequence of ``purpose`` at ``index`` (non-negative integers)."""
        if purpose not in PURPOSES:
            raise FootfallError(f"unknown seed purpose {purpose!r}; purposes are "
                                f"{', '.join(PURPOSES)}")
        if not all(isinstance(i, numbers.Integral) and not isinstance(i, bool) and i >= 0
                   for i in index):
            raise FootfallError(f"stream indices are integers >= 0, got {index!r}")
        key = (EXPERIMENTS.index(self.experiment), PURPOSES.index(purpose), *map(int, index))
        return np.random.SeedSequence(entropy=int(self.seed), spawn_key=key)

    def seed_for(self, purpose: str, *index: int) -> int:
        """An integer seed in [0, 2**63) from the stream of ``purpose`` at ``index``."""
        word = self.sequence(purpose, *index).generate_state(1, dtype=np.uint64)[0]
        return int(word) >> (64 - SEED_BITS)

    def seeds(self, purpose: str, n: int, *index: int) -> list[int]:
        """The first ``n`` seeds of a purpose: ``seed_for(purpose, *index, k)`` for k < n."""
        return [self.seed_for(purpose, *index, k) for k in range(n)]

    def generator(self, purpose: str, *index: int) -> np.random.Generator:
        """A NumPy generator on the stream of ``purpose`` at ``index``."""
        return np.random.default_rng(self.sequence(purpose, *index))


def check_seed_span(first: int, count: int, what: str = "--seed") -> None:
    """Refuse seeds ``first .. first + count - 1`` (a batch's runs) that leave [0, 2**63).

    Every seed is a non-negative 63-bit integer so that a store keeps it exactly; a batch
    whose last seed would not be is refused before any run, in one line.

    Raises
    ------
    FootfallError
        Naming ``what``, the first seed, the count and the largest seed allowed.
    """
    last = int(first) + int(count) - 1
    if int(first) < 0 or last >= 2 ** SEED_BITS:
        raise FootfallError(f"{what} {first} with {count} runs reaches seed {last}, beyond the "
                            f"largest seed {2 ** SEED_BITS - 1}; choose a smaller seed")
