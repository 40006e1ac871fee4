"""The training kinds beyond the paper's: each of its documented character, seeded and reproducible."""

import math

import numpy as np
import pytest

from footfall.core.robot import RobotDescription
from footfall.terrain import make_module
from footfall.terrain.added import PIT_REACH
from footfall.terrain.kinds import ADDED_KINDS

FOOT = RobotDescription().foot_radius  # [m]


@pytest.mark.parametrize("kind", ADDED_KINDS)
def test_an_added_kind_is_seeded_reproducible_and_meets_its_neighbours_at_zero(kind):
    a, b = make_module(kind, 0.7, 5).heights, make_module(kind, 0.7, 5).heights
    assert np.array_equal(a, b)
    assert not np.array_equal(a, make_module(kind, 0.7, 6).heights)
    assert np.all(a[:10] == 0) and np.all(a[-10:] == 0) and np.all(a >= 0)


def test_ridges_cover_the_ground_with_flanks_near_the_friction_cone_that_grow_with_difficulty():
    def flanks(d):
        h = make_module("ridges", d, 3).heights
        gx = np.gradient(h, 0.001, axis=0)  # [-] along the path, across the ridges
        inner = np.abs(gx[80:530])  # past the fade at either end
        return h, np.degrees(np.arctan(np.percentile(inner, 99)))

    h, steep = flanks(0.7)
    assert np.mean(h[80:530] > 0.005) > 0.8  # ridges and troughs, hardly any flat ground
    assert 0.025 < h.max() <= 0.008 + 0.042 * 0.7 + 1e-12  # the documented height
    assert 30 < steep < 41  # [deg] the steepest flanks: 34-40 deg at d = 0.7, rounded by the cells
    assert flanks(0.2)[1] < flanks(1.0)[1]


def test_a_pitted_deck_has_pits_the_ball_sinks_into_to_the_ground():
    h = make_module("pitted", 0.7, 2).heights
    deck = h.max()
    assert 0.01 + 0.04 * 0.7 * 0.85 - 1e-12 <= deck <= 0.01 + 0.04 * 0.7 + 1e-12
    assert set(np.unique(h)) == {0.0, deck}  # a flat deck and the ground
    middle = h[150:460, int(0.305e3 - PIT_REACH * 1e3):int(0.305e3 + PIT_REACH * 1e3)]
    pits = middle == 0
    assert 0.02 < pits.mean() < 0.3
    # Every pit is wider than the ball: a ball-sized disc of ground fits in the widest.
    from scipy.ndimage import binary_erosion, label
    labels, n = label(pits)
    assert n >= 6
    r = int(math.ceil(FOOT * 1e3))
    disc = np.hypot(*np.mgrid[-r:r + 1, -r:r + 1]) <= r
    assert binary_erosion(pits, disc).any()
