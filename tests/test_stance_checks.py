"""The leg clearance over the stance: knee and shin against the terrain, at touch-down and a
stride on, on scripted maps; and the footstep planner's use of it, within F."""

import numpy as np
import pytest

from footfall.control.stance_checks import stride_on
from footfall.core.clearance import leg_gaps, posed_leg_gaps, shin_fractions
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import body_to_world, inverse_kinematics, knee_position, world_to_body
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import nominal_state
from footfall.features.candidates import leg_clearances
from scenes import centre_line_planner

RHO = LITTLEDOG.lower_leg_radius  # [m] 0.006


def bar_map(height: float = 0.07) -> HeightMap:
    """Flat ground with a bar ``height`` [m] high across the path at x in [0.40, 0.44] m."""
    x = np.arange(901) * 0.001
    heights = np.repeat(np.where((x >= 0.40) & (x <= 0.44), height, 0.0)[:, None], 601, axis=1)
    return HeightMap(heights, 0.001, (0.0, -0.3))


def test_a_vertical_shin_over_flat_ground_clears_it_by_its_lowest_sample():
    hmap = bar_map(0.0)  # flat
    centre = np.array([[0.2, 0.0, LITTLEDOG.foot_radius]])  # a ball standing on the ground
    knee = centre + (0.0, 0.0, LITTLEDOG.lower_leg)
    lowest = shin_fractions(LITTLEDOG, 10)[-1]  # where the shin meets the ball
    assert lowest == pytest.approx(1 - (LITTLEDOG.foot_radius + RHO) / LITTLEDOG.lower_leg)
    expected = knee[0, 2] - lowest * LITTLEDOG.lower_leg - RHO  # its sphere above the ground
    assert leg_gaps(hmap, knee, centre, LITTLEDOG, 10)[0] == pytest.approx(expected, abs=1e-9)
    # a shorter span stops higher up the shin
    short = knee[0, 2] - 0.5 * LITTLEDOG.lower_leg - RHO
    assert leg_gaps(hmap, knee, centre, LITTLEDOG, 10, 0.5)[0] == pytest.approx(short, abs=1e-9)


def test_a_shin_leaning_over_a_bar_cuts_into_it_by_the_sphere_s_depth():
    hmap = bar_map(0.07)
    centre = np.array([[0.38, 0.0, 0.01]])  # a ball 1.5 cm before the bar's face
    knee = np.array([[0.43, 0.0, 0.09]])  # the knee forward, over the bar
    gap = leg_gaps(hmap, knee, centre, LITTLEDOG, 50)[0]
    t = np.linspace(0.0, shin_fractions(LITTLEDOG, 2)[-1], 2001)
    pts = knee + t[:, None] * (centre - knee)
    # the sphere of a point over the bar (or within RHO of its face) rests on it
    d = np.clip(0.40 - pts[:, 0], 0.0, None)  # [m] horizontal distance to the bar
    rest = np.where(d < RHO, 0.07 + np.sqrt(np.clip(RHO ** 2 - d ** 2, 0, None)), RHO)
    assert gap < -0.02  # two centimetres inside the bar
    assert gap == pytest.approx(np.min(pts[:, 2] - rest), abs=2e-3)  # to a cell and a sample


def test_a_stride_on_moves_the_body_along_the_path_and_with_the_other_feet_s_ground():
    hmap = bar_map(0.0)
    st0 = nominal_state(hmap, (0.2, 0.0), 0.0, "LF")
    legs = ["LF", "RH", "RF", "LH", "LF"]
    body_xy = np.array([[0.21, 0.0], [0.23, 0.0], [0.25, 0.0], [0.27, 0.0], [0.29, 0.0]])
    grounds = [0.0, 0.04, np.nan, 0.02, 0.0]  # RH's ground 4 cm up, RF's unknown, LH's 2 cm
    later = stride_on(st0, legs, body_xy, grounds)
    z = st0.feet[:, 2]
    rise = ((0.04 - z[LEG_NAMES.index("RH")]) + (0.02 - z[LEG_NAMES.index("LH")])) / 4
    np.testing.assert_allclose(later.body_position - st0.body_position, [0.08, 0.0, rise])
    np.testing.assert_array_equal(later.body_rpy, st0.body_rpy)
    np.testing.assert_array_equal(later.feet, st0.feet)


def test_a_front_foot_just_before_a_bar_would_lean_its_shin_on_it_a_stride_on():
    hmap = bar_map()
    state = nominal_state(hmap, (0.23, 0.0), 0.0, "LF")
    plain = centre_line_planner(hmap).plan(state)
    assert 0.36 < plain.foothold[0] < 0.40  # without the check: 1-3 cm before the bar
    ahead = centre_line_planner(hmap)._horizon(state)
    later = stride_on(plain.state, ahead.legs, ahead.body_xy, ahead.grounds)
    now = leg_clearances(hmap, plain.state, plain.candidates)
    then = leg_clearances(hmap, later, plain.candidates)
    i = plain.index
    assert then[i] < min(now[i] - 0.01, -0.02)  # deep into the bar a stride on, deeper than now
    clear = np.fmin(now, then) >= 0.005
    assert 0 < clear.sum() < clear.size
    checked = centre_line_planner(hmap, leg_clearance=0.005).plan(state)
    np.testing.assert_array_equal(checked.candidates, plain.candidates[clear])
    assert min(leg_clearances(hmap, plain.state, checked.foothold[None])[0],
               leg_clearances(hmap, later, checked.foothold[None])[0]) >= 0.005
    # a clearance no foothold of F has drops nothing: F stays F, not every reachable foothold
    none = centre_line_planner(hmap, leg_clearance=1.0).plan(state)
    np.testing.assert_array_equal(none.candidates, plain.candidates)


def test_the_leg_clearance_is_nan_where_the_leg_cannot_reach():
    hmap = bar_map(0.0)
    state = nominal_state(hmap, (0.2, 0.0), 0.0, "RH")
    foot = state.feet[LEG_NAMES.index("RH")][None]
    out = leg_clearances(hmap, state, np.vstack([foot, foot + (0.5, 0.0, 0.0)]))
    assert np.isfinite(out[0]) and out[0] > 0.01 and np.isnan(out[1])


def test_the_compiled_posed_clearance_is_the_numpy_composition():
    """posed_leg_gaps (one compiled pass) against the functions it fuses -- world_to_body,
    inverse_kinematics, knee_position, body_to_world, leg_gaps -- on rough maps with holes, at
    tilted body poses, for every leg: the same NaN (no posture) and inf (no data) points, the
    gaps to rounding (the body-frame products may be summed in another order)."""
    rng = np.random.default_rng(7)
    no_data = 0
    for trial in range(6):
        h = rng.normal(0.0, 0.004, (400, 300)).cumsum(axis=0) * 0.1
        h[rng.random(h.shape) < 0.02 * (trial % 2)] = np.nan
        if trial % 3 == 2:
            h[150:260, :] = np.nan  # a wide hole: samples with no data at all
        hmap = HeightMap(h, 0.002, (-0.3, -0.3))
        body = np.array([rng.uniform(0.0, 0.3), rng.uniform(-0.05, 0.05), 0.15])
        rpy = rng.uniform(-0.2, 0.2, 3)
        for name in LEG_NAMES:
            leg = LITTLEDOG.leg(name)
            hip = body_to_world(np.array(leg.hip), body, rpy)
            centre = np.column_stack([hip[:2] + rng.uniform(-0.15, 0.15, (300, 2)),
                                      rng.uniform(-0.03, 0.06, 300)])
            got = posed_leg_gaps(hmap, leg, centre, body, rpy, LITTLEDOG, 10, None)
            q, _ = inverse_kinematics(leg, world_to_body(centre, body, rpy), LITTLEDOG)
            solved = np.isfinite(q).all(axis=1)
            knee = body_to_world(knee_position(leg, q, LITTLEDOG), body, rpy)
            want = np.where(solved, leg_gaps(hmap, np.where(solved[:, None], knee, 0.0), centre,
                                             LITTLEDOG, 10), np.nan)
            assert 0 < solved.sum() < solved.size
            np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
            np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
            finite = np.isfinite(want)
            np.testing.assert_allclose(got[finite], want[finite], rtol=0, atol=1e-12)
            no_data += int(np.isinf(want).sum())
    assert no_data > 0  # the wide holes left some legs with no terrain below any sample
