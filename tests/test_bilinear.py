"""The compiled bilinear samplers give the bits of the vectorised NumPy rules they replace.

The references (:mod:`footfall.experiments.bench.sampling`, the benchmark's baseline) are the
rules written as whole-array NumPy: a height map's (NaN off the map and where the nearest cell
has no data; elsewhere the corners with data renormalised; border cells held for half a cell)
and a sphere surface's (NaN outside its window; renormalised unless the window is complete).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from cli_helpers import run
from footfall.core.heightmap import HeightMap
from footfall.core.sphere_surface import sphere_surface
from footfall.experiments.bench.sampling import map_reference, surface_reference
from footfall.features.config import FeatureConfig


def gappy_map(seed: int, holes: float) -> HeightMap:
    rng = np.random.default_rng(seed)
    h = rng.normal(0.0, 0.02, (70, 45))
    h[rng.random(h.shape) < holes] = np.nan
    if holes:
        h[20:34, 12:22] = np.nan  # a hole wider than a foot, which a sphere surface keeps
    return HeightMap(h, 0.005, (-0.1, 0.03))


def points_over(hmap: HeightMap, n: int, seed: int) -> np.ndarray:
    """Points over the map and up to 3 cm beyond it, every 97th NaN, some on cell centres."""
    rng = np.random.default_rng(seed)
    x0, x1, y0, y1 = hmap.bounds
    p = rng.uniform([x0 - 0.03, y0 - 0.03], [x1 + 0.03, y1 + 0.03], (n, 2))
    p[::97] = np.nan
    p[1::50] = hmap.index_to_position(rng.integers(0, 45, (p[1::50].shape[0], 2)))
    return p


@pytest.mark.parametrize("holes", [0.0, 0.15])
def test_the_map_sampler_equals_the_vectorised_rule_bit_for_bit(holes):
    hmap = gappy_map(1, holes)
    p = points_over(hmap, 20_000, 2)
    got = hmap.height_at(p)
    assert np.array_equal(got, map_reference(hmap, p), equal_nan=True)
    assert np.isnan(got).any() and np.isfinite(got).any()
    grid = p[:600].reshape(20, 30, 2)  # any leading shape
    assert np.array_equal(hmap.height_at(grid), map_reference(hmap, grid), equal_nan=True)
    assert hmap.height_at(p[1]).shape == ()


@pytest.mark.parametrize("holes", [0.0, 0.15])
def test_patches_equal_the_map_at_their_sample_points(holes):
    hmap = gappy_map(3, holes)
    rng = np.random.default_rng(4)
    centres = points_over(hmap, 300, 5)
    yaw, mirror = rng.uniform(-np.pi, np.pi, 300), rng.random(300) < 0.5
    for grid in FeatureConfig().grids:
        got = hmap.patches(centres, yaw, mirror, grid)
        want = map_reference(hmap, hmap.sample_points(centres, yaw, mirror, grid))
        assert got.shape == (300, *grid.shape)
        assert np.array_equal(got, want, equal_nan=True)
        one = hmap.patches(centres[1], 0.4, True, grid)  # a scalar heading and mirror
        assert np.array_equal(one, map_reference(hmap, hmap.sample_points(centres[1], 0.4, True,
                                                                           grid)), equal_nan=True)


@pytest.mark.parametrize("holes", [0.0, 0.15])
def test_the_sphere_surface_sampler_and_its_rays_equal_the_vectorised_rule(holes):
    hmap = gappy_map(6, holes)
    surface = sphere_surface(hmap, np.array([-0.05, 0.06]), np.array([0.15, 0.2]), 0.01)
    assert surface.complete == (holes == 0.0)
    p = points_over(hmap, 20_000, 7)
    assert np.array_equal(surface.at(p), surface_reference(surface, p), equal_nan=True)
    xy = p[:200]
    angles = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])
    s = np.linspace(0.002, 0.04, 9)
    rays = xy[:, None, None, :] + s[None, None, :, None] * dirs[None, :, None, :]
    assert np.array_equal(surface.along_rays(xy, dirs, s), surface_reference(surface, rays),
                          equal_nan=True)


def test_the_sampling_benchmark_compares_equal_results(capsys):
    code, out, _ = run(capsys, "bench", "sampling", "--states", "1", "--json")
    assert code == 0
    result = json.loads(out)
    assert result["equal"] is True and result["candidates_median"] > 100
    assert result["patches"]["numpy_ms"] > 0 and result["rays"]["compiled_ms"] > 0
