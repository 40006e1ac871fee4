"""Strided window sums of a map (the dense scorer's sums of heights and squared heights)."""

import numpy as np
import pytest

from footfall.features.window_sums import window_sums


def _literal(q, tap, x0, y0, nu, nv):
    """Every window's samples gathered and summed, one window at a time."""
    s1 = np.empty((x0.size, y0.size))
    s2 = np.empty_like(s1)
    for a, x in enumerate(x0):
        for b, y in enumerate(y0):
            w = q[x:x + tap * nu:tap, y:y + tap * nv:tap]
            assert w.shape == (nu, nv)
            s1[a, b], s2[a, b] = w.sum(), (w * w).sum()
    return s1, s2


@pytest.mark.parametrize("tap, step, nu, nv", [(3, 5, 9, 9), (3, 5, 49, 19), (1, 2, 4, 7),
                                               (2, 2, 3, 1)])
def test_window_sums_equal_the_windows_summed_one_by_one(tap, step, nu, nv):
    rng = np.random.default_rng(tap * 100 + nu)
    q = rng.normal(size=(tap * nu + 60, tap * nv + 45)) * 0.05 + 0.3  # heights off their mean
    x0 = np.arange(0, q.shape[0] - tap * (nu - 1), step)
    y0 = np.arange(1, q.shape[1] - tap * (nv - 1), step)
    s1, s2 = window_sums(q, tap, x0, y0, nu, nv)
    e1, e2 = _literal(q, tap, x0, y0, nu, nv)
    np.testing.assert_allclose(s1, e1, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(s2, e2, rtol=1e-12, atol=1e-12)


def test_counts_of_a_mask_are_exact():
    mask = (np.random.default_rng(3).random((80, 70)) < 0.3).astype(float)
    x0, y0 = np.arange(0, 80 - 3 * 8, 5), np.arange(0, 70 - 3 * 8, 5)
    s1, _ = window_sums(mask, 3, x0, y0, 9, 9)
    np.testing.assert_array_equal(s1, _literal(mask, 3, x0, y0, 9, 9)[0])


def test_a_window_past_the_edge_is_refused():
    with pytest.raises(ValueError, match="past the map"):
        window_sums(np.zeros((20, 20)), 3, np.array([0, 5]), np.array([0]), 6, 3)
