"""The ball's rest surface: the compiled dilation gives scipy's grey dilation by the cap, bit for bit."""

import math

import numpy as np
import pytest
from scipy import ndimage

from footfall.core.ball import ball_centre_surface


def _scipy(heights, resolution, radius):
    """The definition, as scipy computes it: a grey dilation by the ball's cap."""
    reach = int(math.ceil(radius / resolution))
    off = np.arange(-reach, reach + 1) * resolution
    d2 = off[:, None] ** 2 + off[None, :] ** 2
    footprint = d2 <= radius * radius * (1 + 1e-9)
    cap = np.sqrt(np.clip(radius * radius - d2, 0.0, None))
    return ndimage.grey_dilation(np.where(np.isnan(heights), -np.inf, heights),
                                 footprint=footprint, structure=np.where(footprint, cap, 0.0),
                                 mode="constant", cval=-np.inf)


@pytest.mark.parametrize("radius", [0.006, 0.010, 0.0125])
def test_the_rest_surface_is_scipy_s_dilation_by_the_cap(radius):
    rng = np.random.default_rng(3)
    h = np.cumsum(rng.normal(0, 0.002, size=(157, 90)), axis=0)  # rough, 1 mm cells
    h[rng.random(h.shape) < 0.02] = np.nan  # scattered no-data cells
    h[30:70, 10:60] = np.nan  # a hole wider than the ball: -inf inside it
    h[0, :] = -np.inf
    got = ball_centre_surface(h, 0.001, radius)
    np.testing.assert_array_equal(got, _scipy(h, 0.001, radius))
    assert np.isneginf(got[50, 35]) and np.isfinite(got[100, 50])
    assert np.all(got[np.isfinite(h)] >= h[np.isfinite(h)] + radius - 1e-15)  # rests on its cell


def test_a_flat_map_lifts_the_ball_by_its_radius_and_nothing_gives_nothing():
    np.testing.assert_array_equal(ball_centre_surface(np.zeros((9, 7)), 0.002, 0.01),
                                  np.full((9, 7), 0.01))
    assert np.isneginf(ball_centre_surface(np.full((5, 5), np.nan), 0.002, 0.01)).all()
