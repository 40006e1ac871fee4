"""Confidence intervals (bootstrap, Wilson) and paired feature-set comparisons."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.stats import bootstrap_ci, wilson_interval
from footfall.experiments.offline import compare_feature_sets
from footfall.learning.ranker import L2_LOG_C, FootholdRanker


def test_bootstrap_interval_brackets_the_mean_and_shrinks_with_more_data():
    rng = np.random.default_rng(3)
    small = rng.normal(2.0, 1.0, size=20)
    large = rng.normal(2.0, 1.0, size=2000)
    lo_s, hi_s = bootstrap_ci(small)
    lo_l, hi_l = bootstrap_ci(large)
    assert lo_s < small.mean() < hi_s
    assert lo_l < large.mean() < hi_l
    assert hi_l - lo_l < (hi_s - lo_s) / 5  # ~ 1/sqrt(n): 10x narrower for 100x the data
    # For normal data the interval is close to mean +- 1.96 sd / sqrt(n).
    half = 1.96 * large.std() / np.sqrt(large.size)
    assert abs((hi_l - lo_l) / 2 - half) < 0.15 * half
    assert bootstrap_ci(small) == (lo_s, hi_s)  # seeded: the same interval every time


def test_bootstrap_of_a_constant_is_that_constant():
    assert bootstrap_ci(np.full(7, 1.5)) == pytest.approx((1.5, 1.5))


def _row(fs, losses):
    scores = {"losses": list(losses)}
    return {"feature_set": fs, "learner": "l1", "test-modules": scores, "test-kind": scores}


def test_paired_comparison_counts_wins_and_sees_a_consistent_difference():
    base = np.linspace(0.0, 5.0, 30)
    results = [_row("terrain", base + 1.0), _row("templates", base + 0.5), _row("both", base)]
    comps = {(c["a"], c["b"], c["split"]): c for c in compare_feature_sets(results)}
    c = comps[("both", "templates", "test-modules")]
    assert c["mean_difference"] == pytest.approx(-0.5)
    assert c["a_better"] == 30 and c["b_better"] == 0
    # Paired: the large spread of the losses themselves does not widen the interval.
    assert c["ci95"] == pytest.approx([-0.5, -0.5])
    assert comps[("templates", "terrain", "test-kind")]["mean_difference"] == pytest.approx(-0.5)


def test_l2_path_spans_its_six_decades():
    r = FootholdRanker(learner="l2", Cs=7)
    Cs = r._path(np.ones((4, 2)), np.array([1.0, -1.0, 1.0, -1.0]))
    assert Cs[0] == pytest.approx(10 ** L2_LOG_C[0]) and Cs[-1] == pytest.approx(10 ** L2_LOG_C[1])


def test_wilson_interval_on_known_values():
    # Reference values of the Wilson score interval (z = 1.959964).
    assert wilson_interval(10, 21) == pytest.approx((0.2833, 0.6763), abs=5e-4)
    assert wilson_interval(21, 21) == pytest.approx((0.8454, 1.0), abs=5e-4)
    assert wilson_interval(0, 21) == pytest.approx((0.0, 0.1546), abs=5e-4)
    assert wilson_interval(5, 10) == pytest.approx((0.2366, 0.7634), abs=5e-4)
    with pytest.raises(FootfallError, match="successes <= trials"):
        wilson_interval(22, 21)
