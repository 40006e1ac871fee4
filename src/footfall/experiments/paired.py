"""Paired comparisons of walking methods: every method walks the same boards with the same seeds.

A run's seed fixes its start pose, registration error, friction and sensor
noise, so two methods walked with the same seed on the same board differ
only in their foothold choices: a *paired* unit. Comparing them pair by pair
removes the luck of the draw that separate samples would keep. For each
pair of methods this module gives

* success: the runs only the first crossed and those only the second did,
  with the exact McNemar test's two-sided p-value, and a paired bootstrap
  interval of the difference in success rate (resampled within each board);
* slip (the paper's measure, over the footholds of the successful runs): the
  difference in mean slip with a paired bootstrap interval;
* the distance walked, a second measure of robustness that sees how far a
  failed run got.

The verdict on an ordering the paper reports (A above B) is "held" when the
difference is in the paper's direction and significant (McNemar p < 0.05 for
success; the bootstrap interval of the slip difference excludes 0), "reversed"
when it is significant the other way, and "not separated" otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from footfall.core.stats import mcnemar_exact, paired_ratio_difference_ci, pairs_to_separate

ALPHA = 0.05  # significance level of the verdicts
Unit = tuple[str, int]  # a paired unit: (board name, run seed)


@dataclass(frozen=True)
class RunOutcome:
    """What a comparison needs of one run."""

    success: bool
    distance: float  # [m] walked forward from the start before the run ended
    slip_sum_mm: float  # [mm] sum of the slip of every foothold measured in the run
    footholds: int  # footholds whose slip was measured

    @classmethod
    def of(cls, result: dict, slips_m: np.ndarray) -> RunOutcome:
        """From a run record's result and its per-foothold slips [m]."""
        return cls(bool(result.get("success")), float(result.get("distance", 0.0)),
                   1e3 * float(np.sum(slips_m)), int(np.size(slips_m)))


Outcomes = dict[str, dict[Unit, RunOutcome]]  # method -> paired unit -> its run


def _arrays(runs: list[RunOutcome]) -> dict[str, np.ndarray]:
    ok = np.array([r.success for r in runs], dtype=np.float64)
    return {"success": ok, "ones": np.ones(len(runs)),
            "slip": ok * np.array([r.slip_sum_mm for r in runs]),  # successful runs only
            "footholds": ok * np.array([r.footholds for r in runs], dtype=np.float64),
            "distance": np.array([r.distance for r in runs])}


def compare(outcomes: Outcomes, a: str, b: str, seed: int = 0) -> dict:
    """Method ``a`` against ``b`` on the units both walked (see the module)."""
    units = sorted(set(outcomes[a]) & set(outcomes[b]))
    x = _arrays([outcomes[a][u] for u in units])
    y = _arrays([outcomes[b][u] for u in units])
    boards = np.array([u[0] for u in units])
    a_only = int(np.sum((x["success"] == 1) & (y["success"] == 0)))
    b_only = int(np.sum((x["success"] == 0) & (y["success"] == 1)))
    out = {"a": a, "b": b, "pairs": len(units), "a_only": a_only, "b_only": b_only,
           "p_value": mcnemar_exact(a_only, b_only),
           "pairs_to_separate": pairs_to_separate(a_only, b_only, len(units)),
           "success_difference": (float(x["success"].mean() - y["success"].mean())
                                  if units else float("nan")),
           "success_difference_ci": list(paired_ratio_difference_ci(
               (x["success"], x["ones"]), (y["success"], y["ones"]), boards, seed=seed)),
           "distance_difference_m": (float(x["distance"].mean() - y["distance"].mean())
                                     if units else float("nan"))}
    with np.errstate(invalid="ignore", divide="ignore"):
        slip = x["slip"].sum() / x["footholds"].sum() - y["slip"].sum() / y["footholds"].sum()
    out["slip_difference_mm"] = float(slip) if np.isfinite(slip) else None
    out["slip_difference_ci_mm"] = list(paired_ratio_difference_ci(
        (x["slip"], x["footholds"]), (y["slip"], y["footholds"]), boards, seed=seed))
    out["success_verdict"] = success_verdict(out)
    out["slip_verdict"] = slip_verdict(out)
    return out


def compare_all(outcomes: Outcomes, methods: tuple[str, ...], seed: int = 0) -> list[dict]:
    """:func:`compare` of every pair of ``methods`` (in their order: the first is ``a``)."""
    return [compare(outcomes, a, b, seed) for a, b in combinations(methods, 2)
            if a in outcomes and b in outcomes]


def success_verdict(c: dict, alpha: float = ALPHA) -> str:
    """Whether ``a`` crossed more often than ``b``: "held" (significantly more, exact McNemar),
    "reversed" (significantly fewer) or "not separated"."""
    if c["p_value"] >= alpha or c["a_only"] == c["b_only"]:
        return "not separated"
    return "held" if c["a_only"] > c["b_only"] else "reversed"


def slip_verdict(c: dict) -> str:
    """Whether ``a`` slipped less than ``b``: "held" if the bootstrap interval of the
    difference (a - b) lies below 0, "reversed" if above, else "not separated"."""
    lo, hi = c["slip_difference_ci_mm"]
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "not separated"
    return "held" if hi < 0 else "reversed" if lo > 0 else "not separated"


def distance_summary(runs: list[RunOutcome]) -> dict:
    """Distance walked [m]: the mean over all runs (a crossing walks the whole course) and
    over the failed runs alone (how far a failure got)."""
    d = np.array([r.distance for r in runs])
    failed = np.array([not r.success for r in runs])
    return {"distance_mean_m": float(d.mean()) if d.size else None,
            "distance_failed_mean_m": float(d[failed].mean()) if failed.any() else None,
            "failed": int(failed.sum())}
