"""The training kinds beyond the paper's: each of its documented character, seeded and reproducible."""

import math

import numpy as np
import pytest

from footfall.core.robot import RobotDescription
from footfall.terrain import make_module
from footfall.terrain.added import PIT_REACH
from footfall.terrain.kinds import ADDED_KINDS
from footfall.terrain.occlusion import SCANNER_BEHIND, SCANNER_HEIGHT, SEEN_EDGE, shadow

FOOT = RobotDescription().foot_radius  # [m]
SEEN_EDGE_CELLS = int(SEEN_EDGE * 1000) - 1  # cells at either end that always have data


@pytest.mark.parametrize("kind", ADDED_KINDS)
def test_an_added_kind_is_seeded_reproducible_and_meets_its_neighbours_at_zero(kind):
    a, b = make_module(kind, 0.7, 5).heights, make_module(kind, 0.7, 5).heights
    assert np.array_equal(a, b, equal_nan=True)
    assert not np.array_equal(a, make_module(kind, 0.7, 6).heights, equal_nan=True)
    assert np.all(a[:10] == 0) and np.all(a[-10:] == 0) and np.all(a[np.isfinite(a)] >= 0)


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


def test_rock_as_scanned_is_the_rocky_module_with_no_data_only_where_a_scanner_sees_nothing():
    scanned = make_module("rockyscan", 0.7, 4).heights
    rock = make_module("rocky", 0.7, 4).heights  # the same generator from the same seed stream
    holes = np.isnan(scanned)
    assert np.array_equal(scanned[~holes], rock[~holes])
    assert 0.05 < holes.mean() < 0.4
    assert not holes[:SEEN_EDGE_CELLS].any() and not holes[-SEEN_EDGE_CELLS:].any()
    hidden = shadow(rock)
    assert hidden.any() and np.all(holes[hidden])  # every shadowed cell is a hole ...
    dropouts = holes & ~hidden
    assert dropouts.any()  # ... and a few holes are dropouts where the scanner could see
    # A shadowed cell lies below the ray from the scanner over some nearer cell.
    x = (np.arange(rock.shape[0]) + 0.5) * 0.001  # [m] cell centres along the path
    i, j = np.argwhere(hidden)[len(np.argwhere(hidden)) // 2]
    ray = SCANNER_HEIGHT + (rock[i, j] - SCANNER_HEIGHT) * (x[:i] + SCANNER_BEHIND) / (
        x[i] + SCANNER_BEHIND)  # [m] the ray's height over the nearer cells
    assert np.any(rock[:i, j] > ray)


def test_more_difficult_rock_hides_more_of_itself_from_the_scanner():
    share = [np.isnan(make_module("rockyscan", d, s).heights).mean()
             for d in (0.2, 1.0) for s in (0, 1)]
    assert max(share[:2]) < min(share[2:])


def test_pavers_are_level_tops_of_the_documented_heights_with_joints_open_to_the_ground():
    from scipy.ndimage import binary_erosion, label

    d = 0.7
    h = make_module("pavers", d, 8).heights
    labels, n = label(h > 0)
    tops = [np.unique(h[labels == k]) for k in range(1, n + 1)]
    assert n >= 20 and all(t.size == 1 for t in tops)  # every paver is level, one height
    top = np.concatenate(tops)
    high = 0.01 + 0.04 * d  # [m] the documented top height, times U(0.5, 1)
    assert np.all(top >= 0.5 * high - 1e-12) and np.all(top <= high + 1e-12)
    assert top.max() - top.min() > 0.25 * high  # neighbours stand at different heights
    # The joints are open ground of the documented width, 36 mm at 0.7: on
    # pavers about 7 cm across they take most of the strip, and the ball fits
    # into them: a joint eroded by the ball's radius keeps (36 - 20) / 36 =
    # 44 % of its width, more where joints meet.
    middle = h[150:460] == 0
    assert 0.5 < middle.mean() < 0.9
    r = int(math.ceil(FOOT * 1e3))
    disc = np.hypot(*np.mgrid[-r:r + 1, -r:r + 1]) <= r
    assert binary_erosion(middle, disc).mean() > 0.44 * middle.mean()
    # At d = 0 the joints are 4 mm cracks: the strip is nearly all paver.
    assert (make_module("pavers", 0.0, 8).heights[150:460] > 0).mean() > 0.85
