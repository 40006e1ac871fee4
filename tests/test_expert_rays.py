"""The expert's compiled ray terms give the bits of the whole-array NumPy rules they replace.

The reference (:func:`footfall.experiments.bench.expert.ray_terms_reference`, the benchmark's
baseline) samples every ray into (n, K, J) arrays and reduces them; the compiled form reads
each sample once. Maps with scattered and wide holes, footholds over the map, at its border,
beyond it and on cell centres.
"""

from __future__ import annotations

import numpy as np
import pytest

from footfall.core.heightmap import HeightMap
from footfall.core.sphere_surface import sample_surface, sphere_surface
from footfall.experiments.bench.expert import ray_terms_reference
from footfall.expert.rays import RaySamples, no_data_share, ray_terms
from footfall.expert.synthetic import ExpertConfig, walking_expert


def _map(seed: int, holes: float) -> HeightMap:
    rng = np.random.default_rng(seed)
    h = rng.normal(0.0, 0.01, (90, 60)).cumsum(axis=0) * 0.3
    h[rng.random(h.shape) < holes] = np.nan
    if holes:
        h[30:45, 20:32] = np.nan  # wider than the ball: no surface inside it
    return HeightMap(h, 0.002, (0.05, -0.04))


def _points(hmap: HeightMap, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x0, x1, y0, y1 = hmap.bounds
    p = rng.uniform([x0 - 0.02, y0 - 0.02], [x1 + 0.02, y1 + 0.02], (n, 2))
    p[::7] = hmap.index_to_position(rng.integers(0, 60, (p[::7].shape[0], 2)))
    return p


def _compare(hmap: HeightMap, xy: np.ndarray, cfg: ExpertConfig) -> None:
    k = int(cfg.directions)
    angles = 2 * np.pi * np.arange(k) / k
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])
    rays = RaySamples.of(cfg)
    reach = max(rays.s[-1], cfg.unknown_radius)
    ball = sphere_surface(hmap, xy.min(axis=0) - reach, xy.max(axis=0) + reach, 0.011)
    seat = sample_surface(ball, xy)
    seat = np.where(np.isnan(seat), 0.011, seat)
    want = ray_terms_reference(hmap, ball, xy, seat, dirs, rays)
    got = (*ray_terms(ball, xy, seat, dirs, rays),
           no_data_share(hmap.heights, hmap.origin[0], hmap.origin[1], hmap.resolution, xy,
                         dirs, rays.unknown))
    for name, a, b in zip(("hold", "pinch", "trap", "drop", "unknown"), want, got):
        assert np.array_equal(a, b), name


@pytest.mark.parametrize("holes", [0.0, 0.05])
@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_ray_terms_are_the_numpy_rules_bit_for_bit(seed: int, holes: float) -> None:
    hmap = _map(seed, holes)
    _compare(hmap, _points(hmap, 400, seed + 10), walking_expert(0.02))


def test_other_ray_settings_and_a_window_without_surface() -> None:
    hmap = _map(3, 0.02)
    cfg = ExpertConfig(directions=6, ray_step=0.0015, far_step=0.003, slip_distance=0.004,
                       pinch_distance=0.002, trap_radius=0.006, edge_radius=0.01,
                       unknown_radius=0.0)
    _compare(hmap, _points(hmap, 200, 4), cfg)
    # Far off the map: no surface at all; every rise counts as 0 and every probe as no data.
    far = np.array([[5.0, 5.0], [5.01, 5.0]])
    rays = RaySamples.of(cfg)
    dirs = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    hold, pinch, trap, drop = ray_terms(None, far, np.zeros(2), dirs, rays)
    assert np.array_equal(hold, np.zeros(2)) and np.array_equal(pinch, np.zeros(2))
    assert np.array_equal(trap, np.zeros(2))
    assert np.array_equal(drop, (-rays.edge_offset * rays.edge_weight).max() * np.ones(2))
    assert np.array_equal(no_data_share(hmap.heights, hmap.origin[0], hmap.origin[1],
                                        hmap.resolution, far, dirs, rays.unknown), np.ones(2))
