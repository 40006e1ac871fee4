"""Foothold patches: the terrain around candidate footholds on every scale.

The one place where candidate positions become height patches. Templates
and terrain features are both computed from these patches, with heights taken
relative to the foothold's own height so that they describe shape, not
altitude.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.features.config import FeatureConfig

_CHUNK = 4096  # candidates per block: bounds the memory of the sample-point arrays


@dataclass(frozen=True)
class FootholdPatches:
    """Patches around n footholds on each scale."""

    heights: np.ndarray  # (n,) [m] terrain height at each foothold (NaN: no data)
    relative: tuple[np.ndarray, ...]  # per scale (n, taps) [m], height minus foothold height
    coverage: np.ndarray  # (n, n_scales) [-] fraction of samples that hold data
    valid: np.ndarray  # (n,) bool: foothold has data and every coverage >= min_coverage


def patch_coverage(hmap: HeightMap, positions: Any, yaw: Any, mirror: Any,
                   config: FeatureConfig) -> np.ndarray:
    """Fraction of each scale's patch samples that hold data, (n, n_scales).

    The same numbers as ``foothold_patches(...).coverage`` without
    interpolating a single height: a sample has data exactly when it is on
    the map and its nearest cell has data. On a map without holes, a patch
    whose four corners are on the map is complete.
    """
    p = np.asarray(positions, dtype=np.float64).reshape(-1, np.shape(positions)[-1])[:, :2]
    n = p.shape[0]
    yaw = np.broadcast_to(np.asarray(yaw, dtype=np.float64), (n,))
    mirror = np.broadcast_to(np.asarray(mirror, dtype=bool), (n,))
    holes = bool(np.isnan(hmap.heights).any())
    cov = np.ones((n, len(config.scales)))
    for s, grid in enumerate(config.grids):  # three scales
        # The patch's four corners (mirroring only swaps them).
        uu, vv = np.meshgrid(grid.u[[0, -1]], grid.v[[0, -1]], indexing="ij")
        cy, sy = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
        corners = np.stack([p[:, 0, None] + cy * uu.ravel() - sy * vv.ravel(),
                            p[:, 1, None] + sy * uu.ravel() + cy * vv.ravel()], axis=-1)
        inside = hmap.is_inside(corners).all(axis=1)
        todo = np.flatnonzero(~inside) if not holes else np.arange(n)
        for start in range(0, todo.size, _CHUNK):  # memory blocks, each fully vectorised
            idx = todo[start:start + _CHUNK]
            pts = hmap.sample_points(p[idx], yaw[idx], mirror[idx], grid)
            ok = hmap.is_inside(pts)
            ij = np.clip(hmap.position_to_index(pts), 0, np.array(hmap.shape) - 1)
            ok &= ~np.isnan(hmap.heights[ij[..., 0], ij[..., 1]])
            cov[idx, s] = ok.reshape(idx.size, -1).mean(axis=1)
    # Heights are relative to the foothold's: without data there, no sample counts.
    centre = hmap.is_inside(p)
    ij = np.clip(hmap.position_to_index(p), 0, np.array(hmap.shape) - 1)
    centre &= ~np.isnan(hmap.heights[ij[:, 0], ij[:, 1]])
    cov[~centre] = 0.0
    return cov


def foothold_patches(hmap: HeightMap, positions: Any, yaw: Any, mirror: Any,
                     config: FeatureConfig) -> FootholdPatches:
    """Extract relative patches of every scale around footholds.

    Parameters
    ----------
    positions : array of shape (n, 2) or (n, 3)
        Foothold positions [m] (z, if given, is ignored: the map's height is used).
    yaw : float or array of shape (n,)
        Heading [rad] of the body, which orients the patches.
    mirror : bool or array of shape (n,)
        Mirror the patches in y (right legs).
    """
    p = np.asarray(positions, dtype=np.float64).reshape(-1, np.shape(positions)[-1])[:, :2]
    n = p.shape[0]
    yaw = np.broadcast_to(np.asarray(yaw, dtype=np.float64), (n,))
    mirror = np.broadcast_to(np.asarray(mirror, dtype=bool), (n,))
    h0 = hmap.height_at(p)
    rel = []
    cov = np.empty((n, len(config.scales)))
    for s, grid in enumerate(config.grids):  # three scales
        out = np.empty((n, grid.size))
        for start in range(0, n, _CHUNK):  # memory blocks, each fully vectorised
            sl = slice(start, start + _CHUNK)
            patch = hmap.patches(p[sl], yaw[sl], mirror[sl], grid).reshape(-1, grid.size)
            out[sl] = patch - h0[sl, None]
        cov[:, s] = 1.0 - np.isnan(out).mean(axis=1) if n else 0.0
        rel.append(out)
    valid = ~np.isnan(h0) & np.all(cov >= config.min_coverage, axis=1)
    return FootholdPatches(h0, tuple(rel), cov, valid)
