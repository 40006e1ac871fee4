"""Swing-foot trajectories over the terrain's convex hull."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from footfall.control.swing import SwingConfig, swing_trajectory, terrain_profile
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG

RES = 0.001  # [m/cell] the maps of these tests
ORIGIN = (-0.1, -0.1)  # [m]


def step_map(before, after=None, x_step=0.05):
    """Ground at height ``before`` [m] up to x_step, ``after`` beyond (0.4 x 0.2 m at 1 mm)."""
    x = ORIGIN[0] + np.arange(400) * RES
    h = np.full((400, 200), float(before))
    h[x > x_step] = before if after is None else after
    return HeightMap(h, RES, ORIGIN)


def rough_map(seed):
    """Smoothed random terrain, up to ~3 cm high."""
    rng = np.random.default_rng(seed)
    h = gaussian_filter(rng.normal(size=(400, 200)), 6)
    h = 0.03 * (h - h.min()) / (h.max() - h.min())
    return HeightMap(h, RES, ORIGIN)


def footprint_max(hmap, xy, radius):
    """Highest terrain [m] under discs of ``radius`` (the ball foot's footprint) around points (n, 2)."""
    offsets = np.arange(-radius, radius + 1e-12, RES / 2)
    ox, oy = np.meshgrid(offsets, offsets, indexing="ij")
    disc = np.stack([ox.ravel(), oy.ravel()], axis=-1)
    disc = disc[np.hypot(disc[:, 0], disc[:, 1]) <= radius]
    return hmap.height_at(xy[:, None, :] + disc[None]).max(axis=1)


def assert_clears(traj, hmap, band):
    """Every sample strictly between lift-off and touch-down in xy is ``clearance`` above the terrain."""
    t = np.linspace(0.0, traj.duration, 801)
    p = traj.position(t)
    along = (p[:, :2] - traj.start[:2]) @ traj.direction
    length = np.linalg.norm(traj.end[:2] - traj.start[:2])
    inner = (along > 1e-9) & (along < length - 1e-9)
    assert inner.sum() > 200  # much of the swing is above the terrain between the footholds
    ground = footprint_max(hmap, p[inner, :2], band)
    assert np.min(p[inner, 2] - ground) >= traj.clearance - 1e-9


def test_flat_swing_starts_and_ends_at_rest_and_lifts_vertically():
    hm = step_map(0.0)
    start, end = np.array([0.0, 0.02, 0.0]), np.array([0.1, 0.05, 0.0])
    traj = swing_trajectory(hm, start, end, 0.3)
    np.testing.assert_allclose(traj.position(0.0), start, atol=1e-12)
    np.testing.assert_allclose(traj.position(0.3), end, atol=1e-12)
    np.testing.assert_allclose(traj.velocity(np.array([0.0, 0.3])), 0.0, atol=1e-12)
    # Before and after the swing the foot rests.
    np.testing.assert_allclose(traj.position(np.array([-1.0, 2.0])), [start, end], atol=1e-12)
    # Knots: lift-off, straight above it at the lift height, ..., straight above touch-down.
    cfg = SwingConfig()
    np.testing.assert_allclose(traj.knots[1], start + [0, 0, cfg.lift_height], atol=1e-12)
    np.testing.assert_allclose(traj.knots[-2], end + [0, 0, cfg.lift_height], atol=1e-12)
    # The foot rises straight up to the first knot: xy does not move until it is there.
    t = np.linspace(0.0, traj.knot_times[1], 50)
    np.testing.assert_allclose(traj.position(t)[:, :2] - start[:2], 0.0, atol=1e-12)
    assert np.all(np.diff(traj.position(t)[:, 2]) > 0)
    assert_clears(traj, hm, LITTLEDOG.foot_radius)


@pytest.mark.parametrize("before, after", [(0.0, 0.06), (0.06, 0.0)])
def test_path_clears_an_up_step_and_a_down_step(before, after):
    hm = step_map(before, after)
    z0, z1 = hm.height_at([[0.0, 0.0], [0.1, 0.0]])
    start, end = np.array([0.0, 0.0, z0]), np.array([0.1, 0.0, z1])
    for clearance in (0.01, 0.03):
        traj = swing_trajectory(hm, start, end, 0.25, config=SwingConfig(clearance=clearance))
        assert_clears(traj, hm, LITTLEDOG.foot_radius)
        # The path rises just as high as it must: the step's top plus the clearance, or the
        # lift height above the higher foothold.
        top = 0.06 + max(clearance, SwingConfig().lift_height)
        assert traj.position(np.linspace(0, 0.25, 501))[:, 2].max() == pytest.approx(top, abs=1e-6)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_path_clears_random_rough_terrain(seed):
    hm = rough_map(seed)
    rng = np.random.default_rng(seed)
    a, b = rng.uniform(-0.05, 0.0, 2), rng.uniform(0.1, 0.2, 2) * [1, 0.3]
    start = np.array([*a, hm.height_at(a)])
    end = np.array([*b, hm.height_at(b)])
    traj = swing_trajectory(hm, start, end, 0.4, config=SwingConfig(clearance=0.015))
    assert_clears(traj, hm, LITTLEDOG.foot_radius)
    np.testing.assert_allclose(traj.position(0.4), end, atol=1e-12)


def test_path_is_monotone_between_knots_and_velocity_is_its_derivative():
    hm = rough_map(4)
    start = np.array([0.0, 0.0, hm.height_at([0.0, 0.0])])
    end = np.array([0.15, 0.03, hm.height_at([0.15, 0.03])])
    traj = swing_trajectory(hm, start, end, 0.3)
    assert len(traj.knots) >= 5  # lift-off, above it, hull vertices, above touch-down, touch-down
    times = traj.knot_times
    np.testing.assert_allclose(traj.position(times), traj.knots, atol=1e-9)
    for t0, t1 in zip(times[:-1], times[1:]):
        d = np.diff(traj.position(np.linspace(t0, t1, 200)), axis=0)
        for axis in range(3):  # each coordinate rises or falls, never both, between two knots
            assert np.all(d[:, axis] >= -1e-12) or np.all(d[:, axis] <= 1e-12)
    t = np.linspace(0.01, 0.29, 57)
    h = 1e-6
    numeric = (traj.position(t + h) - traj.position(t - h)) / (2 * h)
    np.testing.assert_allclose(traj.velocity(t), numeric, atol=1e-5)


def test_cubic_timing_also_rests_at_both_ends():
    hm = step_map(0.0, 0.03)
    traj = swing_trajectory(hm, [0, 0, 0], [0.1, 0, 0.03], 0.2, config=SwingConfig(timing="cubic"))
    np.testing.assert_allclose(traj.velocity(np.array([0.0, 0.2])), 0.0, atol=1e-12)
    assert_clears(traj, hm, LITTLEDOG.foot_radius)


def test_step_on_the_spot_goes_up_and_down():
    hm = step_map(0.0)
    traj = swing_trajectory(hm, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], 0.2)
    p = traj.position(np.linspace(0, 0.2, 101))
    np.testing.assert_allclose(p[:, :2], 0.0, atol=1e-12)
    assert p[:, 2].max() == pytest.approx(SwingConfig().lift_height)


def test_missing_terrain_counts_as_the_highest_data_nearby():
    h = np.zeros((400, 200))
    x = ORIGIN[0] + np.arange(400) * RES
    h[(x > 0.03) & (x < 0.04)] = 0.02  # a ridge ...
    h[(x > 0.05) & (x < 0.07)] = np.nan  # ... and a hole (no data) after it
    hm = HeightMap(h, RES, ORIGIN)
    s, ground = terrain_profile(hm, np.array([0.0, 0.0]), np.array([0.1, 0.0]), 0.01, RES)
    assert np.isfinite(ground).all()
    np.testing.assert_allclose(ground[(s > 0.055) & (s < 0.065)], 0.02)
    traj = swing_trajectory(hm, [0, 0, 0], [0.1, 0, 0], 0.3)
    p = traj.position(np.linspace(0, 0.3, 1001))
    over_hole = (p[:, 0] > 0.05) & (p[:, 0] < 0.07)
    assert over_hole.any() and np.all(p[over_hole, 2] >= 0.02 + SwingConfig().clearance - 1e-9)


def test_bad_input_raises():
    hm = step_map(0.0)
    with pytest.raises(FootfallError, match="duration"):
        swing_trajectory(hm, [0, 0, 0], [0.1, 0, 0], 0.0)
    with pytest.raises(FootfallError, match=r"\(3,\)"):
        swing_trajectory(hm, [0, 0], [0.1, 0, 0], 0.3)
    with pytest.raises(FootfallError, match="finite"):
        swing_trajectory(hm, [0, 0, np.nan], [0.1, 0, 0], 0.3)
    with pytest.raises(FootfallError, match="clearance"):
        SwingConfig(clearance=-0.01)
    with pytest.raises(FootfallError, match="lift_height must be > 0"):
        SwingConfig(lift_height=0.0)
    with pytest.raises(FootfallError, match="timing"):
        SwingConfig(timing="linear")
