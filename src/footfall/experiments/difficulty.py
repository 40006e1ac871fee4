"""The test difficulty chosen by a rule, not by hand.

The paper's Table II compares ranking functions on one test terrain; whether
10 against 13 crossings out of 21 is a difference depends on how hard that
terrain is. Too easy, and every function crosses; too hard, and the robot
falls whatever it chooses. So the reproduction walks its teacher --
choosing every foothold itself, what a function learned from its
corrections imitates (:mod:`footfall.expert.teachers`) -- on calibration boards of the test kinds
(their own board and run seeds, never trained or tested on) at each
difficulty of a grid, and tests at

    the hardest grid difficulty at which the expert still crosses at least
    ``threshold`` (90 %) of its runs, its success rate at each level
    estimated under the one assumption that harder terrain does not make it
    succeed more often (a non-increasing fit to all levels at once).

The fit is the weighted isotonic regression of the success rates on
difficulty (scikit-learn's ``IsotonicRegression``, decreasing, each level
weighted by its runs): levels that break the order are pooled. With ten runs
a level, one level's luck decides less this way: read raw, 8 / 10 at 0.6
between 10 / 10 at 0.5 and 10 / 10 at 0.8 would stop the climb at 0.5 (the
first rule footfall tried; docs/reproduce-history.md has that run), and a lucky 10 / 10 at
one hard level would alone set the test difficulty; fitted, each level borrows
strength from its neighbours. If even the easiest level's fit misses the
threshold, the easiest level is used and the rule is reported as not met.
The report gives each level's raw count, its Wilson interval and the fit.

Boards differ more than runs on one board do (the expert crossed 10, 15 and
14 of 21 runs on three test boards of one difficulty, and 10 of 10 on that
difficulty's two calibration boards), so the reproduction spends its
calibration runs on many boards with few runs each (5 boards x 2 runs a
level by default; the first default run used 2 x 5, and its test boards
came out far harder for the expert than its calibration boards -- docs/reproduce-history.md
has the numbers).

Ten runs cannot place a 90 % threshold: 10 / 10 has a Wilson interval down
to 72 %. So the rule decides only once the levels its choice rests on -- the
chosen level and the next harder one, between which it places the threshold
(:func:`deciding_levels`) -- hold at least ``calibration_level_runs`` runs
(30 by default): first every level's runs, then more boards of those levels,
and the rule again, until its deciding levels are measured that well.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import fisher_exact
from sklearn.isotonic import IsotonicRegression

from footfall.core.errors import FootfallError
from footfall.core.stats import wilson_interval

RULE = ("the hardest grid difficulty at which the teacher, choosing every foothold, "
        "crosses at least {threshold:.0%} of its runs, its success against difficulty fitted "
        "non-increasing (isotonic regression over every level, weighted by runs)")


@dataclass(frozen=True)
class DifficultyChoice:
    """The rule's answer and what it was based on."""

    difficulty: float  # [-] the chosen test difficulty
    met: bool  # whether the expert reached the threshold at the chosen level
    threshold: float  # [-] the success rate required
    levels: dict  # "d" -> {"difficulty", "successes", "runs", "success_rate", "success_ci",
    # "fitted" (the non-increasing fit), "passes" (fitted >= threshold)}, in grid order
    rule: str  # the rule in words

    def as_dict(self) -> dict:
        return {"difficulty": self.difficulty, "met": self.met, "threshold": self.threshold,
                "rule": self.rule, "levels": self.levels}


def choose_difficulty(outcomes: dict[float, tuple[int, int]], threshold: float = 0.9
                      ) -> DifficultyChoice:
    """The test difficulty by the module's rule from the expert's (successes, runs) per level.

    Parameters
    ----------
    outcomes : dict
        Grid difficulty [-] in [0, 1] -> (successes, runs) of the expert on the
        calibration boards of that difficulty (runs >= 1).
    threshold : float
        Success rate [-] in (0, 1] the expert must reach.
    """
    if not outcomes:
        raise FootfallError("the difficulty rule needs at least one grid level")
    if isinstance(threshold, bool) or not (isinstance(threshold, (int, float))
                                           and 0 < threshold <= 1):
        raise FootfallError(f"the success threshold must be in (0, 1], got {threshold!r}")
    grid = sorted(outcomes)
    for d in grid:
        if not (isinstance(d, (int, float)) and math.isfinite(d) and 0 <= d <= 1):
            raise FootfallError(f"grid difficulties are numbers in [0, 1], got {d!r}")
        wilson_interval(*outcomes[d])  # checks the counts
    rates = np.array([outcomes[d][0] / outcomes[d][1] for d in grid])
    runs = np.array([outcomes[d][1] for d in grid], dtype=np.float64)
    fitted = IsotonicRegression(increasing=False).fit_transform(
        np.array(grid, dtype=np.float64), rates, sample_weight=runs)
    passes = fitted >= threshold - 1e-12
    levels = {}
    for d, rate, fit, ok in zip(grid, rates, fitted, passes):
        lo, hi = wilson_interval(*outcomes[d])
        levels[f"{d:g}"] = {"difficulty": float(d), "successes": int(outcomes[d][0]),
                            "runs": int(outcomes[d][1]), "success_rate": float(rate),
                            "success_ci": [lo, hi], "fitted": float(fit), "passes": bool(ok)}
    met = bool(passes.any())
    chosen = float(grid[int(np.flatnonzero(passes)[-1])]) if met else float(grid[0])
    return DifficultyChoice(chosen, met, float(threshold), levels,
                            RULE.format(threshold=threshold))


def calibration_held(choice: dict, successes: int, runs: int) -> dict | None:
    """Whether the expert's success on the test boards (``successes`` of ``runs``) stayed what
    the calibration measured at the chosen test difficulty: inside that level's 95 % Wilson
    interval, and Fisher's exact test (two-sided) of the two counts. ``choice`` is
    :meth:`DifficultyChoice.as_dict`; None when it holds no level at that difficulty (a
    difficulty given, not calibrated) or no test runs were walked."""
    level = choice["levels"].get(f"{choice['difficulty']:g}")
    if level is None or runs < 1:
        return None
    k, n = level["successes"], level["runs"]
    lo, hi = level["success_ci"]
    rate = successes / runs
    p = float(fisher_exact([[k, n - k], [successes, runs - successes]]).pvalue)
    return {"calibration": [k, n], "calibration_ci": [lo, hi], "test": [successes, runs],
            "test_rate": rate, "inside": bool(lo <= rate <= hi), "fisher_p": p}


def deciding_levels(outcomes: dict[float, tuple[int, int]], threshold: float, runs: int
                    ) -> list[float]:
    """The grid levels the rule's choice rests on that hold fewer than ``runs`` runs.

    Those are the chosen level and the next harder one (if any), between
    which the rule places the threshold; where no level passes, the easiest
    and the next. ``outcomes`` and ``threshold`` as :func:`choose_difficulty`'s.
    """
    choice = choose_difficulty(outcomes, threshold)
    grid = sorted(outcomes)
    k = grid.index(choice.difficulty)
    return [d for d in grid[k:k + 2] if outcomes[d][1] < runs]
