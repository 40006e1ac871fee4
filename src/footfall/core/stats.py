"""Small statistics of measured results: confidence intervals of means and of success rates."""

from __future__ import annotations

import numbers

import numpy as np
from scipy.stats import norm

from footfall.core.errors import FootfallError

BOOTSTRAP = 2000  # resamples for a bootstrap confidence interval


def bootstrap_ci(values: np.ndarray, level: float = 0.95, n: int = BOOTSTRAP,
                 seed: int = 0) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean of ``values`` (n,) over resampled entries.

    For a paired comparison pass the per-demonstration differences. Seeded:
    the same values give the same interval.
    """
    v = np.asarray(values, dtype=np.float64).ravel()
    if v.size == 0:
        return float("nan"), float("nan")
    rng = np.random.default_rng(seed)
    means = v[rng.integers(0, v.size, size=(n, v.size))].mean(axis=1)
    a = (1.0 - level) / 2.0
    lo, hi = np.quantile(means, [a, 1.0 - a])
    return float(lo), float(hi)



def wilson_interval(successes: int, trials: int, level: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of a success rate (e.g. 10 successes of 21 runs).

    Unlike the normal approximation it stays inside [0, 1] and is sensible at
    0 and n successes, which small run counts hit often.
    """
    for v, what in ((successes, "successes"), (trials, "trials")):
        if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 0:
            raise FootfallError(f"{what} must be a non-negative integer, got {v!r}")
    if trials == 0 or successes > trials:
        raise FootfallError(f"need 0 <= successes <= trials and trials > 0, got "
                            f"{successes} of {trials}")
    if not 0 < level < 1:
        raise FootfallError(f"confidence level must be in (0, 1), got {level}")
    z = float(norm.ppf(0.5 + level / 2))
    p = successes / trials
    denom = 1 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denom
    half = z * np.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials)) / denom
    return float(max(0.0, centre - half)), float(min(1.0, centre + half))
