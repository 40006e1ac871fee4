"""Dense scoring of a board (score_grid) against the per-candidate definitions."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from footfall.core.heightmap import HeightMap
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.reward import LinearReward
from footfall.features.template_library import extract_templates
from footfall.features.templates import TemplateFeatures
from footfall.features.terrain_features import TerrainFeatures

CONFIG = FeatureConfig()
RES = 0.001  # [m/cell]
SPACING = 0.005  # [m] lattice spacing of score_grid


def _terrain(seed: int = 0) -> HeightMap:
    """Rough terrain on a tilt, 0.42 x 0.16 m, with a hole of no data inside it."""
    rng = np.random.default_rng(seed)
    nx, ny = 420, 160
    x = np.arange(nx)[:, None] * RES
    y = np.arange(ny)[None, :] * RES
    h = 0.08 * x - 0.05 * y + gaussian_filter(rng.normal(size=(nx, ny)), 4) * 0.03
    h[200:214, 70:82] = np.nan  # a hole: windows over it are fitted on the data around it
    return HeightMap(h, RES, (0.3, -0.1))


def _reward(hmap: HeightMap, seed: int = 1) -> LinearReward:
    """Random terrain and template weights; templates taken from the map itself."""
    rng = np.random.default_rng(seed)
    x0, x1, y0, y1 = hmap.bounds
    pos = np.column_stack([rng.uniform(x0 + 0.08, x1 - 0.08, 12),
                           rng.uniform(y0 + 0.03, y1 - 0.03, 12)])
    library = extract_templates(hmap, pos, 0.0, False, CONFIG)
    assert min(library.counts) >= 3  # every scale has templates
    templates = TemplateFeatures(CONFIG, library).with_rms((0.004,) * len(CONFIG.scales))
    terrain_weights = rng.normal(size=27)
    template_weights = np.concatenate([rng.normal(size=n) for n in library.counts])
    return LinearReward((TerrainFeatures(CONFIG), templates), (terrain_weights, template_weights),
                        CONFIG)


def _templates(reward: LinearReward) -> tuple[TemplateFeatures, list[np.ndarray]]:
    """The reward's template family and its weights split by scale."""
    family, w = reward.family("templates")
    bounds = np.cumsum((0,) + family.library.counts)
    return family, [w[a:b] for a, b in zip(bounds[:-1], bounds[1:])]


HMAP = _terrain()
REWARD = _reward(HMAP)


def _literal_reward(hmap: HeightMap, reward: LinearReward, point: np.ndarray, yaw: float,
                    mirror: bool) -> float:
    """The terrain reward of one foothold, straight from the definitions.

    Least-squares plane and quadric over the patch samples that hold data, the
    std of those samples, and Eq. 4 summed over them (scaled by taps / n_valid).
    """
    h0 = hmap.height_at(point[None])[0]
    terrain_weights = reward.family("terrain")[1]
    templates, template_weights = _templates(reward)
    total = 0.0
    for s, grid in enumerate(reward.config.grids):
        patch = hmap.patches(point[None], yaw, mirror, grid)[0] - h0  # (nu, nv)
        u, v = np.meshgrid(grid.u, grid.v, indexing="ij")
        ok = ~np.isnan(patch)
        z, u, v = patch[ok], u[ok], v[ok]
        one = np.ones_like(u)
        plane = np.linalg.lstsq(np.stack([u, v, one], 1), z, rcond=None)[0]
        quad = np.linalg.lstsq(np.stack([u * u, v * v, u * v, u, v, one], 1), z, rcond=None)[0]
        signed = [plane[0], plane[1], 2 * quad[0], 2 * quad[1]]
        features = []
        for g in signed:
            features += [max(g, 0.0), max(-g, 0.0)]
        features.append(np.std(z))
        total += float(np.dot(terrain_weights[9 * s:9 * (s + 1)], features))
        flat = patch.ravel()
        for t, w in zip(templates.library.templates[s], template_weights[s]):
            d = sum((t[i] - flat[i]) ** 2 for i in range(grid.size) if not np.isnan(flat[i]))
            d *= grid.size / ok.sum()
            total += w * np.exp(-templates.bandwidths[s] * d)
    return total


@pytest.mark.parametrize("yaw", [0.0, np.pi])
@pytest.mark.parametrize("mirror", [False, True])
def test_fast_path_equals_the_interpolating_path(yaw, mirror):
    slow = score_grid(HMAP, REWARD, spacing=SPACING, yaw=yaw, mirror=mirror, fast=False)
    assert slow.valid.any() and not slow.valid.all()  # the borders and the hole cost coverage
    scale = np.abs(slow.reward[slow.valid]).max()
    for dtype, rtol in ((np.float64, 1e-9), (np.float32, 1e-4)):
        fast = score_grid(HMAP, REWARD, spacing=SPACING, yaw=yaw, mirror=mirror, dtype=dtype)
        np.testing.assert_array_equal(fast.x, slow.x)
        np.testing.assert_array_equal(fast.y, slow.y)
        np.testing.assert_array_equal(fast.valid, slow.valid)
        assert np.all(fast.reward[~fast.valid] == -np.inf)
        np.testing.assert_allclose(fast.reward[fast.valid], slow.reward[slow.valid],
                                   rtol=0, atol=rtol * scale)


@pytest.mark.parametrize("yaw, mirror", [(0.0, False), (np.pi, True), (np.pi, False)])
def test_dense_scores_equal_the_per_candidate_definitions(yaw, mirror):
    grid = score_grid(HMAP, REWARD, spacing=SPACING, yaw=yaw, mirror=mirror, dtype=np.float64)
    x, y = grid.x, grid.y
    # Interior points, points by the hole and points whose patches run off the map.
    picks = [(60, 20), (39, 15), (43, 15), (40, 13), (40, 17), (10, 15), (75, 5), (20, 28),
             (3, 15), (80, 28), (0, 16)]
    scale = np.abs(grid.reward[grid.valid]).max()
    for i, j in picks:
        assert grid.valid[i, j]
        expected = _literal_reward(HMAP, REWARD, np.array([x[i], y[j]]), yaw, mirror)
        assert grid.reward[i, j] == pytest.approx(expected, rel=0, abs=1e-9 * scale)


def _one_template_reward(hmap: HeightMap, s: int) -> LinearReward:
    """A reward that is exactly the Eq. 4 feature of one template on scale s."""
    templates, _ = _templates(_reward(hmap))
    weights = np.concatenate([np.eye(n)[0] if k == s else np.zeros(n)
                              for k, n in enumerate(templates.library.counts)])
    return LinearReward((templates,), (weights,), CONFIG)


@pytest.mark.parametrize("s", [0, 1, 2])
def test_masked_template_distance_is_rescaled_over_the_data(s):
    reward = _one_template_reward(HMAP, s)
    grid = score_grid(HMAP, reward, spacing=SPACING, dtype=np.float64)
    cfg = reward.config.grids[s]
    templates, _ = _templates(reward)
    template = templates.library.templates[s][0]
    h = templates.bandwidths[s]
    checked = 0
    for i, j in [(39, 15), (43, 15), (40, 13), (40, 17), (42, 12), (3, 15), (40, 2)]:
        p = np.array([grid.x[i], grid.y[j]])
        c = (HMAP.patches(p[None], 0.0, False, cfg)[0] - HMAP.height_at(p[None])[0]).ravel()
        ok = ~np.isnan(c)
        if ok.all() or not grid.valid[i, j]:
            continue
        d = np.sum((template[ok] - c[ok]) ** 2) * cfg.size / ok.sum()
        assert -np.log(grid.reward[i, j]) / h == pytest.approx(d, rel=1e-9)
        checked += 1
    assert checked >= 3


def test_low_coverage_makes_a_point_invalid():
    h = np.array(HMAP.heights)
    h[:, 100:] = np.nan  # no data for y >= y0 + 0.1 m: coverage falls off towards it
    hmap = HeightMap(h, RES, HMAP.origin)
    grid = score_grid(hmap, REWARD, spacing=SPACING, dtype=np.float64)
    slow = score_grid(hmap, REWARD, spacing=SPACING, fast=False)
    np.testing.assert_array_equal(grid.valid, slow.valid)
    # Coverage of every scale, from the patches themselves.
    pts = grid.positions
    enough = ~np.isnan(hmap.height_at(pts))
    for cfg in CONFIG.grids:
        coverage = 1.0 - np.isnan(hmap.patches(pts, 0.0, False, cfg)).mean(axis=(1, 2))
        enough &= coverage >= CONFIG.min_coverage
    enough = enough.reshape(grid.valid.shape)
    np.testing.assert_array_equal(grid.valid, enough)
    assert (~enough[:, 15:20]).any() and enough[:, 15:20].any()  # the limit is crossed
    assert np.all(grid.reward[~enough] == -np.inf)
    assert np.isfinite(grid.reward[enough]).all()


@pytest.mark.parametrize("mirror", [False, True])
def test_the_generic_dense_form_gathers_the_patches_it_would_interpolate(mirror):
    """A scorer without a matrix form is scored on the lattice from patches gathered by index
    (the samples fall on map cells): the same patches, validity and values as interpolating
    them at every lattice point, holes and the map's border included."""
    from footfall.features.dense import dense_general, dense_values, lattice_points

    terrain = TerrainFeatures(CONFIG)
    w = np.random.default_rng(3).normal(size=len(terrain.columns()))

    def values(c):  # a non-linear function of the features, defined where the foothold is valid
        return np.where(c.patches.valid, np.tanh(np.nan_to_num(terrain.compute(c)) @ w), -np.inf)

    grid = dense_values(HMAP, values, CONFIG, spacing=SPACING, mirror=mirror)
    pts, _, _ = lattice_points(HMAP, SPACING)
    slow, valid = dense_general(HMAP, values, CONFIG, pts, 0.0, mirror)
    slow, valid = slow.reshape(grid.reward.shape), valid.reshape(grid.valid.shape)
    np.testing.assert_array_equal(grid.valid, valid)
    assert (~valid).any() and valid.mean() > 0.5  # the hole and the border are in it
    np.testing.assert_array_equal(np.isfinite(grid.reward), valid)
    np.testing.assert_allclose(grid.reward[valid], slow[valid], rtol=0, atol=1e-10)


@pytest.mark.parametrize("spacing", [SPACING, 0.003, 0.0042])
@pytest.mark.parametrize("mirror", [False, True])
def test_the_validity_grid_counts_what_the_patches_would_show(spacing, mirror):
    """A value that needs the robot's state has a terrain part that is only validity; its grid,
    counted by running sums without a patch, is the generic form's to the last bit -- holes, a
    coverage limit and the map's border included -- and interpolates off the cells."""
    from footfall.features.dense import dense_validity, dense_values

    h = np.array(HMAP.heights)
    h[:, 120:] = np.nan  # coverage falls off towards a strip without data
    h[50:53, 30:90:7] = np.nan  # scattered single cells without data
    hmap = HeightMap(h, RES, HMAP.origin)

    def validity(c):
        return np.where(c.patches.valid, 0.0, -np.inf)

    grid = dense_validity(hmap, CONFIG, spacing=spacing, mirror=mirror)
    slow = dense_values(hmap, validity, CONFIG, spacing=spacing, mirror=mirror)
    for a, b in ((grid.x, slow.x), (grid.y, slow.y), (grid.reward, slow.reward),
                 (grid.valid, slow.valid)):
        np.testing.assert_array_equal(a, b)
    assert (~grid.valid).any() and grid.valid.mean() > 0.3
    turned = dense_validity(hmap, CONFIG, spacing=SPACING, yaw=0.3, mirror=mirror)
    np.testing.assert_array_equal(
        turned.valid, dense_values(hmap, validity, CONFIG, spacing=SPACING, yaw=0.3,
                                   mirror=mirror).valid)


def test_a_learned_function_with_pose_features_scores_only_validity_densely():
    from footfall.features.dense import dense_validity
    from footfall.features.pose_features import PoseFeatures
    from footfall.learning.function import ColumnFunction, ColumnScorer

    class Summed(ColumnFunction):  # the least non-linear function: columns summed
        def __init__(self, families):
            object.__setattr__(self, "families", families)
            object.__setattr__(self, "info", {})

        def predict(self, X):
            return np.nansum(X, axis=1)

        def arrays(self):
            return {}

        @classmethod
        def from_arrays(cls, families, arrays, info, prefix=""):
            return cls(families)

    posed = ColumnScorer(Summed((TerrainFeatures(CONFIG), PoseFeatures())), CONFIG)
    assert posed.has_state_part
    grid = posed.dense(HMAP, spacing=SPACING, mirror=True)
    want = dense_validity(HMAP, CONFIG, spacing=SPACING, mirror=True)
    np.testing.assert_array_equal(grid.reward, want.reward)
    assert set(np.unique(grid.reward)) == {0.0, -np.inf}
    other = ColumnScorer(Summed((PoseFeatures(), TerrainFeatures(CONFIG))), CONFIG)
    assert other.key(state=False) == posed.key(state=False)  # one validity grid for both
    assert other.key(state=True) != posed.key(state=True)
    terrain_only = ColumnScorer(Summed((TerrainFeatures(CONFIG),)), CONFIG)
    assert terrain_only.key(state=False) != posed.key(state=False)
    valued = terrain_only.dense(HMAP, spacing=SPACING)
    assert np.isfinite(valued.reward[valued.valid]).all()
    assert np.unique(valued.reward[valued.valid]).size > 100  # its value, not validity
