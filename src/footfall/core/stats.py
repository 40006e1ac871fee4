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
    lo = 0.0 if successes == 0 else max(0.0, centre - half)  # exact ends: no rounding
    hi = 1.0 if successes == trials else min(1.0, centre + half)  # past the observed rate
    return float(lo), float(hi)


def pairs_to_separate(a_only: int, b_only: int, pairs: int, alpha: float = 0.05,
                      power: float = 0.8) -> float | None:
    """Paired runs [-] a McNemar test would need to tell two methods apart at level ``alpha``
    with probability ``power``, if their discordant shares stayed as measured: ``a_only`` /
    ``pairs`` and ``b_only`` / ``pairs`` (Connor's sample size for McNemar's test, 1987).
    None where the measured shares do not differ (no number of runs separates them)."""
    if pairs <= 0 or a_only == b_only:
        return None
    p10, p01 = a_only / pairs, b_only / pairs
    psi, delta = p10 + p01, p10 - p01
    z_a, z_b = norm.ppf(1.0 - alpha / 2.0), norm.ppf(power)
    n = (z_a * np.sqrt(psi) + z_b * np.sqrt(psi - delta * delta)) ** 2 / (delta * delta)
    return float(np.ceil(n))


def mcnemar_exact(a_only: int, b_only: int) -> float:
    """Two-sided exact McNemar p-value [-] of two methods walked on the same (paired) runs.

    ``a_only``: the pairs the first method succeeded in and the second did
    not; ``b_only``: the reverse. Only these discordant pairs carry evidence;
    under the null hypothesis each is either way with probability 1/2, so the
    p-value is the two-sided exact binomial test of ``a_only`` of
    ``a_only + b_only`` at 1/2 (1 without discordant pairs).
    """
    from scipy.stats import binomtest  # about a second to import: only where a p-value is asked

    for v, what in ((a_only, "a_only"), (b_only, "b_only")):
        if isinstance(v, bool) or not isinstance(v, numbers.Integral) or v < 0:
            raise FootfallError(f"{what} must be a non-negative integer, got {v!r}")
    n = int(a_only) + int(b_only)
    return 1.0 if n == 0 else float(binomtest(int(a_only), n, 0.5).pvalue)


def paired_ratio_difference_ci(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray],
                               strata: np.ndarray | None = None, level: float = 0.95,
                               n: int = BOOTSTRAP, seed: int = 0) -> tuple[float, float]:
    """Percentile bootstrap interval of ``sum(num_a) / sum(den_a) - sum(num_b) / sum(den_b)``.

    ``a`` and ``b`` are (numerator (k,), denominator (k,)) per paired unit
    (a run seed on a board, walked by both methods): success rate is
    (success, 1) per run; mean slip over the successful runs' footholds is
    (sum of slips [mm], footholds) per run, (0, 0) for a failed run. The
    units are resampled *as pairs* (the same draw for both methods), within
    each stratum of ``strata`` (k,) (e.g. the board) when given, so the
    interval reflects the pairing and keeps each board's share. Resamples in
    which a ratio's denominator is 0 (no successful run drawn) are left
    out; NaN if fewer than half remain. Seeded: the same input gives the
    same interval.
    """
    num_a, den_a, num_b, den_b = (np.asarray(x, dtype=np.float64).ravel() for x in (*a, *b))
    k = num_a.size
    if not all(x.size == k for x in (den_a, num_b, den_b)):
        raise FootfallError("paired values must all have one entry per paired unit")
    if not 0 < level < 1:
        raise FootfallError(f"confidence level must be in (0, 1), got {level}")
    if k == 0:
        return float("nan"), float("nan")
    groups = np.zeros(k, dtype=np.int64) if strata is None else np.unique(
        np.asarray(strata).ravel(), return_inverse=True)[1]
    if groups.size != k:
        raise FootfallError("strata must have one entry per paired unit")
    rng = np.random.default_rng(seed)
    counts = np.zeros((n, k))  # how often each unit is drawn in each resample
    for g in np.unique(groups):  # a few strata (boards): resample within each
        members = np.flatnonzero(groups == g)
        draws = members[rng.integers(0, members.size, size=(n, members.size))]
        np.add.at(counts, (np.arange(n)[:, None], draws), 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = counts @ num_a / (counts @ den_a) - counts @ num_b / (counts @ den_b)
    diff = diff[np.isfinite(diff)]
    if diff.size < n / 2:
        return float("nan"), float("nan")
    lo, hi = np.quantile(diff, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return float(lo), float(hi)
