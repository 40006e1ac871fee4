"""Paired statistics of walking runs: exact McNemar and the paired (ratio) bootstrap, on known values."""

import math

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.stats import mcnemar_exact, paired_ratio_difference_ci


def test_mcnemar_is_the_two_sided_exact_binomial_on_the_discordant_pairs():
    assert mcnemar_exact(0, 0) == 1.0
    assert mcnemar_exact(5, 0) == pytest.approx(2 * 0.5 ** 5)  # 0.0625
    assert mcnemar_exact(3, 3) == 1.0
    assert mcnemar_exact(1, 6) == pytest.approx(mcnemar_exact(6, 1))
    # 10 discordant pairs split 9 / 1: 2 * (C(10,0) + C(10,1)) / 2^10 = 22 / 1024
    assert mcnemar_exact(9, 1) == pytest.approx(22 / 1024)
    # 12 split 2 / 10: 2 * (1 + 12 + 66) / 4096
    assert mcnemar_exact(2, 10) == pytest.approx(158 / 4096)
    for bad in (-1, 1.5, True):
        with pytest.raises(FootfallError, match="non-negative integer"):
            mcnemar_exact(bad, 1)


def test_identical_methods_give_a_zero_width_interval_at_zero():
    success = np.array([1, 0, 1, 1, 0, 1.0])
    ones = np.ones(6)
    assert paired_ratio_difference_ci((success, ones), (success, ones)) == (0.0, 0.0)


def test_a_constant_difference_in_every_pair_is_recovered_exactly():
    """Each unit's slip differs by exactly 2 mm per foothold: every resample gives 2."""
    footholds = np.array([10, 12, 8, 11.0])
    slip_b = np.array([5.0, 6.0, 4.0, 7.0]) * footholds  # sums of slips [mm]
    slip_a = slip_b + 2.0 * footholds
    lo, hi = paired_ratio_difference_ci((slip_a, footholds), (slip_b, footholds))
    assert lo == pytest.approx(2.0) and hi == pytest.approx(2.0)


def test_the_success_interval_covers_the_observed_difference_and_is_seeded():
    rng = np.random.default_rng(3)
    a = (rng.random(60) < 0.8).astype(float)
    b = (rng.random(60) < 0.5).astype(float)
    ones = np.ones(60)
    lo, hi = paired_ratio_difference_ci((a, ones), (b, ones), seed=1)
    observed = a.mean() - b.mean()
    assert lo < observed < hi and hi - lo < 0.5
    assert paired_ratio_difference_ci((a, ones), (b, ones), seed=1) == (lo, hi)
    # The paired bootstrap's width matches the normal approximation of paired differences.
    d = a - b
    half = 1.96 * d.std(ddof=1) / math.sqrt(d.size)
    assert (hi - lo) / 2 == pytest.approx(half, rel=0.2)


def test_strata_keep_each_boards_share_of_the_resample():
    """Board 0: a always succeeds, b never; board 1: both always fail. Resampled within the
    boards, every draw holds 3 runs of board 0: the difference is exactly 3 / 6."""
    a = np.array([1, 1, 1, 0, 0, 0.0])
    b = np.zeros(6)
    ones = np.ones(6)
    boards = np.array([0, 0, 0, 1, 1, 1])
    assert paired_ratio_difference_ci((a, ones), (b, ones), strata=boards) == (0.5, 0.5)
    lo, hi = paired_ratio_difference_ci((a, ones), (b, ones))  # unstratified: it varies
    assert lo < 0.5 < hi


def test_ratios_without_any_successful_run_are_not_a_number():
    zeros = np.zeros(5)
    lo, hi = paired_ratio_difference_ci((zeros, zeros), (zeros, zeros))
    assert math.isnan(lo) and math.isnan(hi)
    with pytest.raises(FootfallError, match="one entry per paired unit"):
        paired_ratio_difference_ci((np.ones(3), np.ones(3)), (np.ones(2), np.ones(2)))


def test_wilson_intervals_end_exactly_at_0_and_1_and_hold_the_observed_rate():
    """0 of n and n of n give exact ends (a plot's error bars must never turn negative)."""
    from footfall.core.stats import wilson_interval

    for n in range(1, 70):
        assert wilson_interval(0, n)[0] == 0.0 and wilson_interval(n, n)[1] == 1.0
        for k in range(n + 1):
            lo, hi = wilson_interval(k, n)
            assert lo <= k / n <= hi


def test_the_success_curves_draw_every_count_from_none_to_all(tmp_path):
    from footfall.experiments.batch import summarise
    from footfall.experiments.report import METHODS, _success_curves

    def row(ok, n):
        from types import SimpleNamespace

        records = [SimpleNamespace(result={"success": i < ok, "speed_cm_s": 5.0,
                                           "speed_body_lengths_s": 0.2},
                                   slips=lambda: np.zeros(0)) for i in range(n)]
        return summarise(records).as_dict()

    sweep = {f"{d:g}": {m: row(k, 3) for m in METHODS}
             for d, k in ((0.5, 3), (0.7, 2), (0.9, 1), (1.0, 0))}
    name, caption = _success_curves(tmp_path, {"sweep": sweep, "test_difficulty": 0.7,
                                               "config": {"sweep_runs": 3}})
    assert (tmp_path / name).stat().st_size > 0 and "Wilson" in caption


def test_the_pairs_a_mcnemar_test_would_need_follow_connors_formula():
    from footfall.core.stats import pairs_to_separate

    # 10 % and 30 % discordant one way and the other: Connor's n for alpha 0.05, power 0.8
    p10, p01 = 0.3, 0.1
    psi, delta = p10 + p01, p10 - p01
    expected = (1.959964 * psi ** 0.5 + 0.841621 * (psi - delta ** 2) ** 0.5) ** 2 / delta ** 2
    assert pairs_to_separate(30, 10, 100) == np.ceil(expected) == 77
    assert pairs_to_separate(10, 30, 100) == 77  # either way round
    assert pairs_to_separate(7, 7, 63) is None and pairs_to_separate(0, 0, 0) is None
    # a larger difference needs fewer runs
    assert pairs_to_separate(23, 7, 63) < pairs_to_separate(13, 7, 63)
