"""The test difficulty chosen by a rule, not by hand (issue 20).

The paper's Table II compares ranking functions on one test terrain; whether
10 against 13 crossings out of 21 is a difference depends on how hard that
terrain is. Too easy, and every function crosses; too hard, and the robot
falls whatever it chooses. So the reproduction walks the synthetic expert --
choosing every foothold itself, the best a function learned from its
demonstrations can hope to do -- on calibration boards of the test kinds
(their own board and run seeds, never trained or tested on) at each
difficulty of a grid, and tests at

    the hardest grid difficulty up to which the expert crosses at least
    ``threshold`` (90 %) of its runs at every level,

i.e. walking up the grid from its easiest level, the last level before the
expert's success first drops below the threshold. A level above a failing
one that passes again (one board's draw of rocks can be kinder than an
easier board's) does not count: the rule asks where the expert *still*
crosses. If the expert misses the threshold at the easiest level already,
the easiest level is used and the rule is reported as not met.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from footfall.core.errors import FootfallError
from footfall.core.stats import wilson_interval

RULE = ("the hardest grid difficulty up to which the synthetic expert, choosing every foothold, "
        "crosses at least {threshold:.0%} of its runs at every level")


@dataclass(frozen=True)
class DifficultyChoice:
    """The rule's answer and what it was based on."""

    difficulty: float  # [-] the chosen test difficulty
    met: bool  # whether the expert reached the threshold at the chosen level
    threshold: float  # [-] the success rate required
    levels: dict  # "d" -> {"difficulty", "successes", "runs", "success_rate", "success_ci",
    # "passes"}, in grid order
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
    levels = {}
    chosen, met, failed = None, False, False
    for d in sorted(outcomes):
        if not (isinstance(d, (int, float)) and math.isfinite(d) and 0 <= d <= 1):
            raise FootfallError(f"grid difficulties are numbers in [0, 1], got {d!r}")
        ok, runs = outcomes[d]
        lo, hi = wilson_interval(ok, runs)  # (checks the counts)
        passes = ok / runs >= threshold - 1e-12
        levels[f"{d:g}"] = {"difficulty": float(d), "successes": int(ok), "runs": int(runs),
                            "success_rate": ok / runs, "success_ci": [lo, hi],
                            "passes": bool(passes)}
        if passes and not failed:
            chosen, met = float(d), True
        failed = failed or not passes
    if chosen is None:
        chosen = float(min(outcomes))
    return DifficultyChoice(chosen, met, float(threshold), levels,
                            RULE.format(threshold=threshold))
