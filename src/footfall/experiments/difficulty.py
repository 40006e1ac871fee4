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

**Confirmation on fresh boards.** A level chosen because its runs came out
at or above the threshold is, by that choice, a level whose runs came out
lucky more often than not: the chosen level's own count overstates the
teacher (the winner's curse). The first reproduction that decided on 30 runs
chose 1 on 27 / 30, and the teacher then crossed 32 / 63 of its test-board
runs; 48 runs on 16 further boards of that difficulty gave 34 / 48. So the
choice is confirmed on boards it never saw (:func:`next_to_confirm`,
:func:`confirm_choice`): the chosen level is walked again on fresh boards
(``confirmation_runs``, 30 by default, two a board), and it stands if those
runs do not show the teacher below the threshold -- the upper end of their
95 % Wilson interval reaches it (24 / 30 or more at 90 %). Otherwise the next
easier level is walked on fresh boards of its own, and so on down the grid;
if no level stands, the easiest is used and the rule is reported as not met.
The confirmation's runs, not the chosen level's, are what the test boards are
held against (:func:`calibration_held`): they were not used to choose.
This rule was written down before any confirmation was walked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.stats import fisher_exact
from sklearn.isotonic import IsotonicRegression

from footfall.core.errors import FootfallError
from footfall.core.stats import wilson_interval

RULE = ("the hardest grid difficulty at which the teacher, choosing every foothold, "
        "crosses at least {threshold:.0%} of its runs, its success against difficulty fitted "
        "non-increasing (isotonic regression over every level, weighted by runs)")
CONFIRMED = ("; then confirmed on fresh boards: the level stands if the 95 % Wilson interval "
             "of the teacher's runs there reaches {threshold:.0%}, else the next easier level "
             "is walked on fresh boards")


@dataclass(frozen=True)
class DifficultyChoice:
    """The rule's answer and what it was based on."""

    difficulty: float  # [-] the chosen test difficulty
    met: bool  # whether the expert reached the threshold at the chosen level
    threshold: float  # [-] the success rate required
    levels: dict  # "d" -> {"difficulty", "successes", "runs", "success_rate", "success_ci",
    # "fitted" (the non-increasing fit), "passes" (fitted >= threshold)}, in grid order
    rule: str  # the rule in words
    selected: float | None = None  # [-] the level the calibration runs chose, before the
    # confirmation (None: not confirmed)
    confirmations: dict = field(default_factory=dict)  # "d" -> {"difficulty", "successes",
    # "runs", "success_ci", "confirmed"} of the fresh boards walked, hardest first

    def as_dict(self) -> dict:
        return {"difficulty": self.difficulty, "met": self.met, "threshold": self.threshold,
                "rule": self.rule, "levels": self.levels, "selected": self.selected,
                "confirmations": self.confirmations}


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


def confirms(successes: int, runs: int, threshold: float) -> bool:
    """Whether fresh runs confirm a level: the upper end of their 95 % Wilson interval reaches
    ``threshold`` [-] (they do not show the teacher below it)."""
    return bool(wilson_interval(successes, runs)[1] >= threshold - 1e-12)


def next_to_confirm(choice: DifficultyChoice, grid: tuple[float, ...] | list[float],
                    walked: dict[float, tuple[int, int]]) -> float | None:
    """The grid level whose fresh boards are walked next, or None once the confirmation is over.

    ``walked``: level -> the teacher's (successes, runs) on its confirmation boards, so far.
    The first is the level ``choice`` selected; after a level that does not confirm, the next
    easier one; None after a level that confirms, or after the easiest.
    """
    levels = sorted(grid)
    d = choice.difficulty
    while d in walked:
        if confirms(*walked[d], choice.threshold):
            return None
        k = levels.index(d)
        if k == 0:
            return None
        d = levels[k - 1]
    return d


def confirm_choice(choice: DifficultyChoice, walked: dict[float, tuple[int, int]]
                   ) -> DifficultyChoice:
    """The test difficulty after the confirmation (:func:`next_to_confirm` walked to its end):
    the hardest walked level its fresh runs confirm, else the easiest walked, not met."""
    if not walked:
        return choice
    out = {}
    for d in sorted(walked, reverse=True):
        k, n = walked[d]
        lo, hi = wilson_interval(k, n)
        out[f"{d:g}"] = {"difficulty": float(d), "successes": int(k), "runs": int(n),
                         "success_ci": [lo, hi], "confirmed": confirms(k, n, choice.threshold)}
    good = [v["difficulty"] for v in out.values() if v["confirmed"]]
    chosen = max(good) if good else min(walked)
    return replace(choice, difficulty=float(chosen), met=bool(good) and choice.met,
                   selected=choice.difficulty, confirmations=out,
                   rule=choice.rule + CONFIRMED.format(threshold=choice.threshold))


def calibration_held(choice: dict, successes: int, runs: int) -> dict | None:
    """Whether the expert's success on the test boards (``successes`` of ``runs``) stayed what
    the calibration measured at the chosen test difficulty: inside the 95 % Wilson interval of
    that level's confirmation runs (of its calibration runs where it was not confirmed), and
    Fisher's exact test (two-sided) of the two counts. ``choice`` is
    :meth:`DifficultyChoice.as_dict`; None when it holds no level at that difficulty (a
    difficulty given, not calibrated) or no test runs were walked."""
    key = f"{choice['difficulty']:g}"
    level = choice.get("confirmations", {}).get(key)
    source = "confirmation"
    if level is None:
        level, source = choice["levels"].get(key), "calibration"
    if level is None or runs < 1:
        return None
    k, n = level["successes"], level["runs"]
    lo, hi = level["success_ci"]
    rate = successes / runs
    p = float(fisher_exact([[k, n - k], [successes, runs - successes]]).pvalue)
    return {"calibration": [k, n], "calibration_ci": [lo, hi], "test": [successes, runs],
            "test_rate": rate, "inside": bool(lo <= rate <= hi), "fisher_p": p,
            "against": source}


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
