"""Terrain features on analytic surfaces, mirroring, holes."""

import numpy as np
import pytest

from footfall.core.heightmap import HeightMap, PatchGrid
from footfall.features.config import FeatureConfig
from footfall.features.patches import foothold_patches
from footfall.features.terrain_features import (
    QUAD_COLUMNS,
    QUANTITIES,
    TERRAIN_FEATURE_NAMES,
    fit_kernels,
    moment_basis,
    quad_to_fits,
    raw_features,
    terrain_features_from_patches,
)

RES = 0.001
CONFIG = FeatureConfig()


def surface(f, size=0.4):
    n = int(round(size / RES))
    x = np.arange(n) * RES - size / 2
    xx, yy = np.meshgrid(x, x, indexing="ij")
    return HeightMap(f(xx, yy), RES, (-size / 2, -size / 2))


def features_at(hm, pos, yaw=0.0, mirror=False):
    fp = foothold_patches(hm, np.atleast_2d(pos), yaw, mirror, CONFIG)
    assert fp.valid.all()
    return dict(zip(TERRAIN_FEATURE_NAMES, terrain_features_from_patches(fp.relative, CONFIG)[0]))


def test_names_are_27_and_stable():
    assert len(TERRAIN_FEATURE_NAMES) == 27
    assert TERRAIN_FEATURE_NAMES[0] == "small.slope_x_pos"
    assert TERRAIN_FEATURE_NAMES[-1] == "large.std"
    assert len(QUANTITIES) == 9


def test_plane_gives_its_gradient_and_zero_curvature():
    hm = surface(lambda x, y: 0.3 * x - 0.2 * y + 0.05)
    f = features_at(hm, [0.01, 0.02])
    for s in ("small", "medium", "large"):
        assert f[f"{s}.slope_x_pos"] == pytest.approx(0.3, abs=1e-9)
        assert f[f"{s}.slope_x_neg"] == 0.0
        assert f[f"{s}.slope_y_pos"] == 0.0
        assert f[f"{s}.slope_y_neg"] == pytest.approx(0.2, abs=1e-9)
        for q in ("curv_x_pos", "curv_x_neg", "curv_y_pos", "curv_y_neg"):
            assert abs(f[f"{s}.{q}"]) < 1e-7


def test_slopes_are_in_the_body_frame():
    hm = surface(lambda x, y: 0.3 * x)
    f = features_at(hm, [0.0, 0.0], yaw=np.pi / 2)  # body x along world y
    assert f["medium.slope_x_pos"] == pytest.approx(0.0, abs=1e-9)
    assert f["medium.slope_y_neg"] == pytest.approx(0.3, abs=1e-9)  # body y is world -x


def test_paraboloid_gives_its_curvature():
    a, b = 4.0, -1.5  # z = a x^2 + b y^2: curvatures 2a = 8 /m (a hollow), 2b = -3 /m
    hm = surface(lambda x, y: a * x ** 2 + b * y ** 2)
    f = features_at(hm, [0.0, 0.0])
    for s in ("small", "medium", "large"):
        assert f[f"{s}.curv_x_pos"] == pytest.approx(2 * a, rel=1e-6)
        assert f[f"{s}.curv_x_neg"] == 0.0
        assert f[f"{s}.curv_y_neg"] == pytest.approx(-2 * b, rel=1e-6)
        assert f[f"{s}.slope_x_pos"] == pytest.approx(0.0, abs=1e-9)
    # Off-centre, the slope is the gradient at the foothold (symmetric window).
    f2 = features_at(hm, [0.02, 0.0])
    assert f2["small.slope_x_pos"] == pytest.approx(2 * a * 0.02, rel=1e-6)


def test_std_is_the_standard_deviation_of_the_patch():
    hm = surface(lambda x, y: np.where(x > 0, 0.01, 0.0))
    grid = CONFIG.grids[1]
    fp = foothold_patches(hm, [[0.0005, 0.0]], 0.0, False, CONFIG)
    expected = np.std(fp.relative[1][0])
    assert features_at(hm, [0.0005, 0.0])["medium.std"] == pytest.approx(expected)
    assert expected == pytest.approx(0.005, rel=0.1)
    assert grid.shape == (19, 19)


def test_right_leg_equals_left_leg_on_mirrored_terrain():
    rng = np.random.default_rng(5)
    from scipy.ndimage import gaussian_filter
    h = gaussian_filter(rng.normal(size=(400, 400)), 6) * 0.05
    hm = HeightMap(h, RES, (-0.2, -0.2))
    pos = np.array([[0.013, 0.021], [-0.03, 0.05]])
    right = foothold_patches(hm, pos, 0.4, True, CONFIG)
    left = foothold_patches(hm.mirrored_y(), pos * [1, -1], -0.4, False, CONFIG)
    np.testing.assert_allclose(terrain_features_from_patches(right.relative, CONFIG),
                               terrain_features_from_patches(left.relative, CONFIG), atol=1e-10)


def test_kernels_match_least_squares_and_ignore_offsets():
    grid = PatchGrid(0.054, 0.054, 0.003)
    k = fit_kernels(grid)
    np.testing.assert_allclose(k.sum(axis=0), 0.0, atol=1e-9)
    rng = np.random.default_rng(0)
    z = rng.normal(size=grid.size) * 0.01
    u, v = np.meshgrid(grid.u, grid.v, indexing="ij")
    u, v = u.ravel(), v.ravel()
    plane = np.linalg.lstsq(np.stack([u, v, np.ones_like(u)], 1), z, rcond=None)[0]
    quad = np.linalg.lstsq(np.stack([u * u, v * v, u * v, u, v, np.ones_like(u)], 1), z,
                           rcond=None)[0]
    np.testing.assert_allclose(z @ k, [plane[0], plane[1], 2 * quad[0], 2 * quad[1]], rtol=1e-9)


@pytest.mark.parametrize("scale", range(3))
def test_fits_follow_from_the_quadric_sums_of_a_full_patch(scale):
    """The dense scorer's route: a full patch's sums against the quadric's monomials, mapped by
    quad_to_fits, give the same slopes and curvatures as the fit kernels."""
    grid = CONFIG.grids[scale]
    z = np.random.default_rng(scale).normal(size=(50, grid.size)) * 0.01
    sums = z @ moment_basis(grid)[:, QUAD_COLUMNS]
    np.testing.assert_allclose(sums @ quad_to_fits(grid).T, z @ fit_kernels(grid), rtol=0,
                               atol=1e-12)


def test_holes_are_fitted_over_the_data_that_is_there():
    grid = CONFIG.grids[2]
    u, v = np.meshgrid(grid.u, grid.v, indexing="ij")
    plane = (0.2 * u - 0.1 * v).ravel()
    bowl = (3.0 * u ** 2 - 1.0 * v ** 2 + 0.5 * u * v + 0.2 * u).ravel()
    rng = np.random.default_rng(1)
    holes = rng.choice(plane.size, size=plane.size // 3, replace=False)
    holed_plane, holed_bowl = plane.copy(), bowl.copy()
    holed_plane[holes] = np.nan
    holed_bowl[holes] = np.nan
    raw = raw_features(np.stack([holed_plane, holed_bowl]), grid)
    # An exact plane's slope and an exact quadric's curvature are recovered from
    # any 2/3 of the samples; the std is over the samples that hold data.
    np.testing.assert_allclose(raw[0, :2], [0.2, -0.1], rtol=1e-7)
    np.testing.assert_allclose(raw[1, 2:4], [6.0, -2.0], rtol=1e-6)
    assert raw[1, 4] == pytest.approx(np.nanstd(holed_bowl))
    assert np.isfinite(raw).all()
    empty = np.full((1, grid.size), np.nan)
    assert np.isnan(raw_features(empty, grid)).all()  # no data: no guess


def test_low_coverage_makes_a_foothold_invalid():
    h = np.zeros((300, 300))
    h[150:, :] = np.nan  # no data for x >= 0 ...
    h[:, :140] = np.nan  # ... nor for y < -0.01 m
    hm = HeightMap(h, RES, (-0.15, -0.15))
    fp = foothold_patches(hm, [[-0.05, 0.05], [-0.0015, 0.05], [-0.0015, -0.0095], [0.01, 0.05]],
                          0.0, False, CONFIG)
    # Half of the large patch over the edge at x = 0 leaves 25 of 49 rows: still enough.
    assert fp.coverage[1, 2] == pytest.approx(25 / 49)
    # In the corner only 25 x 10 of 49 x 19 large-patch samples have data: not a candidate.
    assert fp.coverage[2, 2] == pytest.approx(250 / 931)
    assert fp.valid.tolist() == [True, True, False, False]


def test_patch_coverage_equals_the_coverage_of_the_patches():
    from footfall.features.patches import patch_coverage

    rng = np.random.default_rng(4)
    h = rng.normal(size=(200, 150)) * 0.01
    h[60:90, 40:47] = np.nan
    hm = HeightMap(h, RES, (0.0, 0.0))
    pos = np.column_stack([rng.uniform(-0.01, 0.21, 400), rng.uniform(-0.01, 0.16, 400)])
    yaw = rng.uniform(-np.pi, np.pi, 400)
    mirror = rng.random(400) < 0.5
    expected = foothold_patches(hm, pos, yaw, mirror, CONFIG).coverage
    np.testing.assert_allclose(patch_coverage(hm, pos, yaw, mirror, CONFIG), expected)
    full = HeightMap(np.zeros((200, 150)), RES)  # no holes: only the border counts
    np.testing.assert_allclose(patch_coverage(full, pos, yaw, mirror, CONFIG),
                               foothold_patches(full, pos, yaw, mirror, CONFIG).coverage)
