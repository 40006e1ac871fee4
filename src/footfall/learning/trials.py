"""Learning from the robot's own trials: footholds labelled by what followed, no expert at all.

The paper's future work (§VI): instead of, or besides, an expert's corrections,
the robot learns from its own runs. Every foothold it stood on is labelled by
its outcome (:mod:`footfall.data.outcomes`) -- *bad* if any of
:data:`BAD_OUTCOMES` followed (its foot slid in stance, the swing into it or
the next one out of it missed, or the run fell within a gait cycle) -- and
becomes a comparison for the same pairwise learners that learn from
demonstrations: each bad foothold is ranked below ``pairs`` good ones drawn
at random from the same board and leg group (front or hind). Comparing within
one board keeps a hard board's many failures from teaching "hard boards are
bad", which no foothold choice can act on.

A comparison spans two decisions (two robot states), so its two footholds are
prepared each in its own state and stacked as one two-row example
(:func:`footfall.learning.dataset.pair_example`); cross-validation folds never
split the comparisons of one run's foothold (with folds by board, a board's).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.data.outcomes import FALL_HORIZON, stored_outcomes
from footfall.data.store import DemoStore

BAD_OUTCOMES = ("slid", "missed", "next_missed", "fall")  # a foothold followed by any went wrong
DEFAULT_PAIRS = 4  # good footholds each bad one is ranked below


@dataclass(frozen=True)
class TrialFoothold:
    """A foothold the robot stood on in one of its runs, and whether it went wrong."""

    hmap: HeightMap  # the board the run walked
    state: RobotState  # the state the planner chose the foothold in
    foothold: np.ndarray  # (3,) [m] the planned foothold
    bad: bool  # one of BAD_OUTCOMES followed
    board: str  # the board's content hash
    run: str  # "<store path>#<run id>": the run it came from
    front: bool  # a front leg's foothold


def trial_footholds(paths: Sequence[str | os.PathLike], key_prefix: str | None = None,
                    horizon: int = FALL_HORIZON, robot: RobotDescription = LITTLEDOG
                    ) -> list[TrialFoothold]:
    """Every foothold stood on in the run logs of the stores (runs whose key starts with
    ``key_prefix``), labelled bad or not, in store and run order.

    Raises
    ------
    FootfallError
        If a store cannot be read or the stores hold no run with a foothold stood on.
    """
    out: list[TrialFoothold] = []
    for path in paths:
        with DemoStore(path, read_only=True) as store:
            for head, run, hmap, outcome in stored_outcomes(store, key_prefix, horizon):
                bad = np.any([getattr(outcome, name) for name in BAD_OUTCOMES], axis=0)
                out += [TrialFoothold(hmap, run.steps[k].state, np.asarray(run.steps[k].foothold,
                                                                          dtype=np.float64),
                                      bool(bad[k]), run.terrain_hash, f"{os.fspath(path)}#{head['id']}",
                                      robot.leg(run.steps[k].swing_leg).front)
                        for k in np.flatnonzero(outcome.used)]
    if not out:
        raise FootfallError("the stores hold no run with a foothold the robot stood on")
    return out


def trial_pairs(board: np.ndarray, front: np.ndarray, bad: np.ndarray, pairs: int,
                rng: np.random.Generator) -> np.ndarray:
    """Comparisons (m, 2) of footholds: [good, bad] index pairs, each bad foothold against up
    to ``pairs`` good ones of the same board and leg group, drawn without replacement.

    ``board`` (n,) labels each foothold's board, ``front`` (n,) bool its leg group and
    ``bad`` (n,) bool its outcome. Bad footholds without a good one to compare are left out.
    """
    if isinstance(pairs, bool) or not isinstance(pairs, (int, np.integer)) or pairs < 1:
        raise FootfallError(f"comparisons per bad foothold must be a whole number >= 1, "
                            f"got {pairs!r}")
    board, front, bad = np.asarray(board), np.asarray(front, bool), np.asarray(bad, bool)
    cell = np.unique(np.stack([board.astype(str), front.astype(str)], axis=1), axis=0,
                     return_inverse=True)[1].ravel()
    out = []
    for c in range(int(cell.max()) + 1 if cell.size else 0):  # board x leg group: a few dozen
        good_i = np.flatnonzero((cell == c) & ~bad)
        bad_i = np.flatnonzero((cell == c) & bad)
        if good_i.size == 0 or bad_i.size == 0:
            continue
        k = min(pairs, good_i.size)
        drawn = np.argsort(rng.random((bad_i.size, good_i.size)), axis=1)[:, :k]
        out.append(np.stack([good_i[drawn].ravel(), np.repeat(bad_i, k)], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2), dtype=np.intp)
