"""The compiled bilinear samplers give the bits of the vectorised NumPy rules they replace.

The references below are the rules written as whole-array NumPy (as footfall evaluated them
before the samplers were compiled): a height map's (NaN off the map and where the nearest cell
has no data; elsewhere the corners with data renormalised; border cells held for half a cell)
and a sphere surface's (NaN outside its window; renormalised unless the window is complete).
"""

from __future__ import annotations

import numpy as np
import pytest

from footfall.core.heightmap import HeightMap
from footfall.expert.surface import sphere_surface
from footfall.features.config import FeatureConfig


def map_reference(hmap: HeightMap, points: np.ndarray) -> np.ndarray:
    f = hmap.continuous_index(points)
    nx, ny = hmap.shape
    fi, fj = f[..., 0], f[..., 1]
    inside = (fi >= -0.5) & (fi < nx - 0.5) & (fj >= -0.5) & (fj < ny - 0.5)
    fi = np.clip(np.where(inside, fi, 0.0), 0.0, nx - 1.0)
    fj = np.clip(np.where(inside, fj, 0.0), 0.0, ny - 1.0)
    i0 = np.minimum(np.floor(fi).astype(np.intp), nx - 2)
    j0 = np.minimum(np.floor(fj).astype(np.intp), ny - 2)
    ti, tj = fi - i0, fj - j0
    h = hmap.heights
    corners = (h[i0, j0], h[i0 + 1, j0], h[i0, j0 + 1], h[i0 + 1, j0 + 1])
    weights = ((1 - ti) * (1 - tj), ti * (1 - tj), (1 - ti) * tj, ti * tj)
    num, den = np.zeros(fi.shape), np.zeros(fi.shape)
    for c, w in zip(corners, weights):
        ok = ~np.isnan(c)
        num += np.where(ok, c, 0.0) * w
        den += ok * w
    nearest = h[np.floor(fi + 0.5).astype(np.intp), np.floor(fj + 0.5).astype(np.intp)]
    out = np.full(fi.shape, np.nan)
    np.divide(num, den, out=out, where=inside & ~np.isnan(nearest) & (den > 0))
    return out


def surface_reference(surface, points: np.ndarray) -> np.ndarray:
    f = (points - surface.origin) / surface.resolution
    wx, wy = surface.filled.shape
    fi, fj = f[..., 0], f[..., 1]
    inside = (fi >= 0) & (fi <= wx - 1) & (fj >= 0) & (fj <= wy - 1)
    fi, fj = np.where(inside, fi, 0.0), np.where(inside, fj, 0.0)
    i0 = np.minimum(fi.astype(np.intp), wx - 2)
    j0 = np.minimum(fj.astype(np.intp), wy - 2)
    ti, tj = fi - i0, fj - j0
    flat = i0 * wy + j0
    corners = ((0, (1 - ti) * (1 - tj)), (wy, ti * (1 - tj)), (1, (1 - ti) * tj),
               (wy + 1, ti * tj))
    num, den = np.zeros(fi.shape), np.zeros(fi.shape)
    for step, w in corners:
        num += w * np.take(surface.filled, flat + step)
        den += w * np.take(surface.known, flat + step)
    out = np.full(fi.shape, np.nan)
    if surface.complete:
        return np.where(inside, num, out)
    nearest = np.take(surface.known, np.rint(fi).astype(np.intp) * wy + np.rint(fj).astype(np.intp))
    np.divide(num, den, out=out, where=inside & (nearest > 0) & (den > 0))
    return out


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
