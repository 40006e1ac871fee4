"""The COG trajectory of the crawl gait, and support margins."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from footfall.control.cog import GRAVITY, CogConfig, incircle, plan_cog, support_margin
from footfall.core.errors import FootfallError
from footfall.core.robot import LEG_NAMES, LITTLEDOG


def nominal_feet():
    return np.array([[*LITTLEDOG.nominal_foot(n)[:2], 0.0] for n in LEG_NAMES])


def crawl(n_steps, stride=0.08, rng=None, feet=None):
    """The next ``n_steps`` crawl steps: each leg in gait order moves ``stride`` [m] forward.

    With ``rng``, every foothold is jittered by up to 1.5 cm in x and y and 3 cm in z.
    """
    current = nominal_feet() if feet is None else feet.copy()
    steps = []
    for i in range(n_steps):
        leg = LITTLEDOG.gait_order[i % 4]
        k = LEG_NAMES.index(leg)
        foothold = current[k] + [stride, 0.0, 0.0]
        if rng is not None:
            foothold += rng.uniform(-1, 1, 3) * [0.015, 0.015, 0.03]
        current[k] = foothold
        steps.append((leg, foothold))
    return steps


def swing_times(traj, k, n=400):
    return np.linspace(traj.lift_off[k], traj.touch_down[k], n, endpoint=False)


def assert_stable(traj, config):
    """COG and ZMP inside every swing's support triangle by the margin; ZMP inside the shifts' polygons."""
    for k in range(len(traj.legs)):
        t = swing_times(traj, k)
        for points in (traj.position(t), traj.zmp(t)):
            assert support_margin(traj.triangles[k], points).min() >= config.margin - 1e-9


def test_support_margin_is_the_signed_distance_to_the_nearest_edge():
    tri = np.array([[0.0, 0.0], [0.4, 0.0], [0.0, 0.3]])  # legs 0.4, 0.3; hypotenuse 0.5
    points = np.array([[0.1, 0.1], [0.1, 0.05], [-0.1, 0.1], [0.4, 0.3], [0.0, 0.0]])
    expected = [0.1, 0.05, -0.1, -0.24, 0.0]  # (0.4, 0.3) is 0.24 beyond the hypotenuse
    np.testing.assert_allclose(support_margin(tri, points), expected, atol=1e-12)
    np.testing.assert_allclose(support_margin(tri[::-1], points), expected, atol=1e-12)
    # Broadcasting: triangles (2, 3, 2) against points (5, 1, 2) -> (5, 2).
    both = np.stack([tri, tri + [1.0, 0.0]])
    out = support_margin(both, points[:, None])
    assert out.shape == (5, 2)
    np.testing.assert_allclose(out[:, 0], expected, atol=1e-12)
    # The incentre is the inradius inside.
    centre, radius = incircle(tri)
    assert radius == pytest.approx(0.1)
    assert support_margin(tri, centre) == pytest.approx(radius)


def test_flat_crawl_keeps_cog_and_zmp_inside_the_inset_triangles():
    config = CogConfig()
    steps = crawl(5)
    traj = plan_cog(nominal_feet(), steps, np.zeros(2), np.zeros(2), config)
    assert traj.status == "optimal" and not traj.pinned.any()
    assert traj.legs == tuple(LITTLEDOG.gait_order) + (LITTLEDOG.gait_order[0],)
    assert_stable(traj, config)
    # During the shifts the ZMP stays inside the four feet's polygon, inset by the margin.
    feet = nominal_feet()[:, :2]
    for k, (leg, foothold) in enumerate(steps):
        hull = feet[ConvexHull(feet).vertices]
        t = np.linspace(traj.shift_start[k], traj.lift_off[k], 200)
        zmp = traj.zmp(t)
        for a, b in zip(hull, np.roll(hull, -1, axis=0)):  # counter-clockwise edges
            edge = b - a
            inside = (edge[0] * (zmp - a)[:, 1] - edge[1] * (zmp - a)[:, 0]) / np.linalg.norm(edge)
            assert inside.min() >= config.margin - 1e-9
        feet[LEG_NAMES.index(leg)] = foothold[:2]
    # The body walks on: a cycle of strides later it is about a stride ahead.
    assert traj.position(traj.touch_down[3])[0] == pytest.approx(0.08, abs=0.03)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_uneven_footholds_keep_cog_and_zmp_inside(seed):
    rng = np.random.default_rng(seed)
    config = CogConfig(margin=0.015, swing_duration=0.25, shift_duration=0.1)
    feet = nominal_feet()
    feet[:, 2] = rng.uniform(0, 0.05, 4)
    traj = plan_cog(feet, crawl(5, stride=rng.uniform(0.04, 0.09), rng=rng, feet=feet),
                    np.array([0.005, 0.0]), np.array([0.02, 0.0]), config)
    assert traj.status in ("optimal", "slowed")
    assert_stable(traj, config)


def test_position_and_velocity_are_continuous_and_start_where_told():
    start, v0 = np.array([0.01, -0.005]), np.array([0.05, 0.02])
    traj = plan_cog(nominal_feet(), crawl(4), start, v0)
    np.testing.assert_allclose(traj.position(0.0), start, atol=1e-12)
    np.testing.assert_allclose(traj.velocity(0.0), v0, atol=1e-12)
    eps = 1e-7
    boundaries = np.concatenate([traj.lift_off, traj.touch_down[:-1]])
    for f, tol in ((traj.position, 1e-6), (traj.velocity, 1e-5)):  # ~ eps * rate of change
        np.testing.assert_allclose(f(boundaries - eps), f(boundaries + eps), atol=tol)
    np.testing.assert_allclose(traj.shift_start[1:], traj.touch_down[:-1])
    np.testing.assert_allclose(traj.lift_off - traj.shift_start, CogConfig().shift_duration)
    np.testing.assert_allclose(traj.touch_down - traj.lift_off, CogConfig().swing_duration)
    # Derivatives agree with finite differences; the ZMP is the cart-table formula.
    t = np.linspace(0.01, traj.end - 0.01, 97)
    h = 1e-6
    np.testing.assert_allclose((traj.position(t + h) - traj.position(t - h)) / (2 * h),
                               traj.velocity(t), atol=1e-6)
    np.testing.assert_allclose((traj.velocity(t + h) - traj.velocity(t - h)) / (2 * h),
                               traj.acceleration(t), atol=1e-4)
    np.testing.assert_allclose(traj.zmp(t), traj.position(t) - LITTLEDOG.nominal_height / GRAVITY
                               * traj.acceleration(t), atol=1e-12)


def test_thin_triangle_pins_the_cog_to_its_incentre():
    steps = crawl(4)
    leg, foothold = steps[0]  # LH lands right beside RH: the next swing's (LF) triangle is thin
    assert leg == "LH"
    rh = nominal_feet()[LEG_NAMES.index("RH")]
    steps[0] = (leg, rh + [0.0, 0.02, 0.0])
    config = CogConfig()
    traj = plan_cog(nominal_feet(), steps, np.zeros(2), np.zeros(2), config)
    centre, radius = incircle(traj.triangles[1])
    assert radius < config.margin
    assert traj.pinned.tolist() == [False, True, False, False]
    t = swing_times(traj, 1)
    np.testing.assert_allclose(traj.position(t), np.broadcast_to(centre, (t.size, 2)), atol=1e-9)
    np.testing.assert_allclose(traj.velocity(t), 0.0, atol=1e-9)
    for k in (0, 2, 3):
        assert support_margin(traj.triangles[k], traj.position(swing_times(traj, k))).min() \
            >= config.margin - 1e-9


def test_a_start_far_outside_still_gives_a_plan():
    # Starting 6 cm behind with a backward velocity: the shifts' ZMP cannot be kept inside at the
    # configured pace, so the plan slows down (or, failing that, relaxes) but the swings stay safe.
    config = CogConfig(shift_duration=0.05)
    traj = plan_cog(nominal_feet(), crawl(3), np.array([-0.06, 0.03]), np.array([-0.3, 0.2]), config)
    assert traj.status in ("slowed", "relaxed")
    assert_stable(traj, config)


def test_bad_input_raises():
    feet = nominal_feet()
    with pytest.raises(FootfallError, match="at least one step"):
        plan_cog(feet, [], np.zeros(2), np.zeros(2))
    with pytest.raises(FootfallError, match="unknown leg"):
        plan_cog(feet, [("XX", np.zeros(3))], np.zeros(2), np.zeros(2))
    with pytest.raises(FootfallError, match=r"foothold must be \(3,\)"):
        plan_cog(feet, [("LH", np.zeros(2))], np.zeros(2), np.zeros(2))
    with pytest.raises(FootfallError, match="feet"):
        plan_cog(feet[:3], crawl(1), np.zeros(2), np.zeros(2))
    with pytest.raises(FootfallError, match="finite"):
        plan_cog(feet, crawl(1), np.array([np.inf, 0.0]), np.zeros(2))
    with pytest.raises(FootfallError, match="support_margin"):
        support_margin(np.zeros((4, 2)), np.zeros(2))
    with pytest.raises(FootfallError, match="swing_duration"):
        CogConfig(swing_duration=0.0)
    traj = plan_cog(feet, crawl(1), np.zeros(2), np.zeros(2))
    with pytest.raises(FootfallError, match="defined for t"):
        traj.position(traj.end + 0.1)


# ------------------------------------------------------------------ the legs' reach
def _worst_reach(traj, feet, steps):
    """Largest x or y distance [m] of a foot down from its nominal place under the COG."""
    home = nominal_feet()[:, :2]
    current, worst = feet[:, :2].copy(), 0.0
    for k, (leg, foothold) in enumerate(steps):
        j = LEG_NAMES.index(leg)
        for phase, t0, t1 in (("shift", traj.shift_start[k], traj.lift_off[k]),
                              ("swing", traj.lift_off[k], traj.touch_down[k])):
            down = [i for i in range(4) if phase == "shift" or i != j]
            cog = traj.position(np.linspace(t0, t1, 200))
            gap = np.abs(current[down][None] - home[down][None] - cog[:, None])
            worst = max(worst, float(gap.max()))
        current[j] = foothold[:2]
    return worst


def test_with_a_reach_the_cog_keeps_every_foot_down_within_it():
    feet = nominal_feet()
    steps = crawl(4, stride=0.08)
    steps[1] = ("LF", steps[1][1] + [0.03, 0.0, 0.0])  # a long stride of the front left foot
    free = plan_cog(feet, steps, np.zeros(2), np.zeros(2), CogConfig())
    config = CogConfig(reach=0.07)
    kept = plan_cog(feet, steps, np.zeros(2), np.zeros(2), config)
    assert kept.status == "optimal"
    assert _worst_reach(free, feet, steps) > 0.09  # without it a foot is left far behind
    assert _worst_reach(kept, feet, steps) <= 0.07 + 1e-9
    assert_stable(kept, config)


def test_a_reach_that_cannot_be_kept_is_dropped():
    feet = nominal_feet()
    steps = crawl(4)
    traj = plan_cog(feet, steps, np.zeros(2), np.zeros(2), CogConfig(reach=0.005))
    assert traj.status == "out of reach"
    same = plan_cog(feet, steps, np.zeros(2), np.zeros(2), CogConfig())
    np.testing.assert_allclose(traj.waypoints, same.waypoints)
