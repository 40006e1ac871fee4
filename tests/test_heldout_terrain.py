"""The held-out terrain kinds: each of its documented character, seeded and reproducible."""

import numpy as np
import pytest

from footfall.sim.hfield import terrain_surface
from footfall.terrain import make_board, make_module
from footfall.terrain.heldout import EDGE
from footfall.terrain.kinds import HELD_OUT_KINDS


def _inner(h):
    """The cells between the flat approach and exit (x is the first index, 1 mm cells)."""
    return h[int(EDGE * 1000) + 2:-int(EDGE * 1000) - 2]


@pytest.mark.parametrize("kind", HELD_OUT_KINDS)
def test_a_kind_is_seeded_reproducible_and_flat_before_and_after(kind):
    a, b = make_module(kind, 0.7, 5).heights, make_module(kind, 0.7, 5).heights
    assert np.array_equal(a, b, equal_nan=True)
    assert not np.array_equal(a, make_module(kind, 0.7, 6).heights, equal_nan=True)
    edge = int(EDGE * 1000) - 1
    assert np.all(a[:edge] == 0) and np.all(a[-edge:] == 0)  # no data only inside
    assert np.nanmax(_inner(a)) > 0.02


def test_stepping_stones_leave_gaps_at_the_ground_that_widen_with_difficulty():
    easy, hard = (_inner(make_module("stones", d, 1).heights) for d in (0.0, 1.0))
    gap_easy, gap_hard = np.mean(easy == 0), np.mean(hard == 0)
    assert 0.1 < gap_easy < gap_hard and gap_hard > 0.5
    assert np.percentile(hard[hard > 0], 50) > 0.04  # the stones stand several cm high


def test_the_washboard_has_holes_to_the_ground_through_a_raised_bed():
    h = make_module("washboard", 0.7, 2).heights
    bed = h[100:510]  # past the ramps
    assert 0 < np.mean(bed == 0) < 0.1  # the holes
    assert np.percentile(bed[bed > 0], 5) >= 0.005 + 0.025 * 0.7 - 1e-9  # the bed under them


def test_a_scan_has_no_data_behind_rises_and_the_simulator_fills_it_down():
    board = make_board([("scan", 0.8), ("scan", 0.8)], seed=3)
    holes = np.isnan(board.heights)
    assert 0.01 < holes.mean() < 0.3
    surface = terrain_surface(board)
    assert np.isfinite(surface).all() and np.all(surface[holes] == np.nanmin(board.heights))
    h = make_module("scan", 0.8, 3).heights  # a hidden cell lies behind something higher
    i, j = np.argwhere(np.isnan(h))[0]
    assert np.nanmax(h[:i, j]) > 0
