"""Terrain templates: Eq. 4, NaN rules, the library and its file."""

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.features.config import FeatureConfig
from footfall.features.reward import analytic_templates
from footfall.features.template_library import (
    TemplateLibrary,
    extract_templates,
    merge_libraries,
    rbf_features,
    squared_distances,
)
from footfall.features.templates import bandwidth_for_rms

CONFIG = FeatureConfig()


def test_rbf_matches_equation_4_computed_directly():
    rng = np.random.default_rng(0)
    c = rng.normal(size=(7, 81)) * 0.01
    t = rng.normal(size=(5, 81)) * 0.01
    h = 300.0
    direct = np.array([[np.exp(-h * np.sum([(t[j, i] - c[k, i]) ** 2 for i in range(81)]))
                        for j in range(5)] for k in range(7)])
    np.testing.assert_allclose(rbf_features(c, t, h), direct, rtol=1e-10)
    assert rbf_features(t[:1], t[:1], h)[0, 0] == pytest.approx(1.0)  # identical patch


def test_holes_are_left_out_and_the_sum_rescaled():
    rng = np.random.default_rng(1)
    t = rng.normal(size=(3, 50))
    c = rng.normal(size=(2, 50))
    c[1, :10] = np.nan
    d = squared_distances(c, t)
    np.testing.assert_allclose(d[1], ((t[:, 10:] - c[1, 10:]) ** 2).sum(axis=1) * 50 / 40)
    np.testing.assert_allclose(d[0], ((t - c[0]) ** 2).sum(axis=1))
    assert np.isfinite(rbf_features(c, t, 0.1)).all()
    assert np.isnan(squared_distances(np.full((1, 50), np.nan), t)).all()


def test_bandwidth_for_rms():
    grid = CONFIG.grids[0]
    h = bandwidth_for_rms(0.004, grid)
    assert np.exp(-h * grid.size * 0.004 ** 2) == pytest.approx(np.exp(-1))
    with pytest.raises(FootfallError):
        bandwidth_for_rms(0.0, grid)


def _bumpy_map():
    rng = np.random.default_rng(2)
    from scipy.ndimage import gaussian_filter
    return HeightMap(gaussian_filter(rng.normal(size=(400, 300)), 5) * 0.05 + 0.1, 0.001,
                     (0.0, -0.15))


def test_extracted_templates_are_relative_patches_of_the_footholds():
    hm = _bumpy_map()
    pos = np.array([[0.1, 0.0], [0.2, 0.05], [0.385, 0.0]])  # the last runs off the map
    lib = extract_templates(hm, pos, 0.0, False, CONFIG)
    assert lib.counts == (3, 2, 2)  # only the small patch still fits at x = 0.385
    # A template compared with its own foothold gives exactly 1.
    from footfall.features.patches import foothold_patches
    fp = foothold_patches(hm, pos[:2], 0.0, False, CONFIG)
    x = lib.features(fp.relative, (50.0, 50.0, 50.0))
    np.testing.assert_allclose(x[[0, 1], [0, 1]], 1.0)
    # Relative heights: the foothold's own sample is zero.
    for t, g in zip(lib.templates, CONFIG.grids):
        np.testing.assert_allclose(t[:, g.size // 2], 0.0, atol=1e-12)
    assert lib.terrain_hashes == (hm.content_hash(),)


def test_library_save_load_round_trip_and_merge(tmp_path):
    hm = _bumpy_map()
    lib = extract_templates(hm, np.array([[0.1, 0.0], [0.2, 0.05]]), 0.3, True, CONFIG)
    path = tmp_path / "lib.npz"
    lib.save(path)
    back = TemplateLibrary.load(path)
    assert back.config == lib.config and back.terrain_hashes == lib.terrain_hashes
    for a, b in zip(back.templates + back.sources, lib.templates + lib.sources):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(back.sources[0][:, 2:], [[0.3, 1.0], [0.3, 1.0]])
    analytic, names = analytic_templates(CONFIG)
    merged = merge_libraries([lib, analytic])
    assert merged.counts == (5, 5, 5)
    assert merged.names()[:2] == ("small.template_0", "small.template_1")
    sub = merged.subset(tuple(np.array([0, 4]) for _ in range(3)))
    np.testing.assert_array_equal(sub.templates[1][1], analytic.templates[1][2])


def test_incomplete_or_misshapen_templates_are_rejected():
    analytic, _ = analytic_templates(CONFIG)
    bad = list(analytic.templates)
    bad[0] = bad[0].copy()
    bad[0][0, 0] = np.nan
    with pytest.raises(FootfallError, match="complete"):
        TemplateLibrary(CONFIG, tuple(bad), analytic.sources)
    with pytest.raises(FootfallError, match="shape"):
        TemplateLibrary(CONFIG, (analytic.templates[1],) + analytic.templates[1:], analytic.sources)
    other = FeatureConfig(template_resolution=0.002)
    with pytest.raises(FootfallError, match="different feature configurations"):
        merge_libraries([analytic, analytic_templates(other)[0]])


def test_families_with_the_same_library_share_their_columns_once_per_candidate_set():
    from footfall.features.family import Candidates
    from footfall.features.templates import TemplateFeatures

    library, _ = analytic_templates(CONFIG)
    a = TemplateFeatures(CONFIG, library).with_rms((0.004,) * 3)
    b = TemplateFeatures(CONFIG, TemplateLibrary(CONFIG, tuple(t.copy() for t in library.templates),
                                                 library.sources)).with_rms((0.004,) * 3)
    other_rms = TemplateFeatures(CONFIG, library).with_rms((0.006,) * 3)
    fewer = TemplateFeatures(CONFIG, library.subset(tuple(np.arange(2) for _ in library.templates))
                             ).with_rms((0.004,) * 3)
    assert TemplateFeatures(CONFIG).memo_key() is None  # not fitted: nothing to share
    assert a.memo_key() == b.memo_key()  # equal contents, other arrays
    assert len({a.memo_key(), other_rms.memo_key(), fewer.memo_key()}) == 3
    c = Candidates(_bumpy_map(), np.array([[0.1, 0.0, 0.1], [0.2, 0.02, 0.1]]), 0.0, False, CONFIG)
    assert c.columns(a) is c.columns(b)  # computed once, shared
    np.testing.assert_array_equal(c.columns(other_rms), other_rms.compute(c))
    assert c.columns(other_rms) is not c.columns(a)


def _demonstrations(n: int, rng: np.random.Generator):
    """``n`` left-fore-leg decisions on one bumpy map: 5 candidates each, all inside it."""
    from footfall.core.state import RobotState

    hm = _bumpy_map()
    states, candidates, chosen = [], [], []
    for _ in range(n):
        xy = np.column_stack([rng.uniform(0.15, 0.25, 5), rng.uniform(-0.05, 0.05, 5)])
        candidates.append(np.column_stack([xy, np.full(5, 0.1)]))
        states.append(RobotState(np.zeros((4, 3)), np.array([0.2, 0.0, 0.2]), np.zeros(3), "LF"))
        chosen.append(int(rng.integers(5)))
    return [hm] * n, states, candidates, chosen


def test_a_capped_library_holds_a_sample_of_the_demonstrated_footholds_and_no_more():
    from footfall.features.template_library import library_from_demonstrations

    maps, states, candidates, chosen = _demonstrations(40, np.random.default_rng(0))

    def lib(n, capped, seed=1):
        return library_from_demonstrations(maps[:n], states[:n], candidates[:n], chosen[:n],
                                           CONFIG, np.random.default_rng(seed), size=30,
                                           capped=capped)

    # Up to a third of the size a scale the cap changes nothing, the random draws included.
    for a, b in zip(lib(10, True).templates, lib(10, False).templates):
        np.testing.assert_array_equal(a, b)
    uncapped, capped = lib(40, False), lib(40, True)
    assert uncapped.counts == (40, 40, 40)  # every demonstrated foothold, as the paper
    assert capped.counts == (10, 10, 10)
    for t_cap, t_all in zip(capped.templates, uncapped.templates):  # a subset, no repeats
        same = (t_cap[:, None, :] == t_all[None, :, :]).all(axis=2)
        assert (same.sum(axis=1) == 1).all() and (same.sum(axis=0) <= 1).all()
    for a, b in zip(capped.templates, lib(40, True).templates):  # seeded
        np.testing.assert_array_equal(a, b)
    assert any(not np.array_equal(a, b) for a, b in zip(capped.templates,
                                                          lib(40, True, seed=2).templates))
