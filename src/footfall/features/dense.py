"""Dense scoring: the terrain part of a scorer at every lattice point of a board, in one call.

:func:`score_grid` asks a scorer for its dense form
(:meth:`FootholdScorer.dense <footfall.features.scorer.FootholdScorer.dense>`).
Linear rewards have a matrix form (:mod:`footfall.features.dense_linear`);
every other scorer has the generic one here, :func:`dense_values`: its
terrain part evaluated at every lattice point, in blocks, from patches
gathered from the map by index where the lattice and the patch samples fall
on map cells, interpolated elsewhere. Both give the same numbers as the
per-candidate definitions.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.features.candidates import lattice
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates, FeatureFamily
from footfall.features.patches import FootholdPatches, foothold_patches
from footfall.features.window_sums import window_sums

_BLOCK_FLOATS = 1 << 20  # patch values per block of the interpolating path


@dataclass(frozen=True)
class ScoreGrid:
    """Terrain reward at every lattice point of a map."""

    x: np.ndarray  # (na,) [m] lattice x coordinates
    y: np.ndarray  # (nb,) [m] lattice y coordinates
    reward: np.ndarray  # (na, nb) terrain reward; -inf where not a valid foothold
    valid: np.ndarray  # (na, nb) bool: data at the foothold and enough patch coverage

    @property
    def positions(self) -> np.ndarray:
        """Lattice points (na * nb, 2) [m] in the order of ``reward.ravel()``."""
        xx, yy = np.meshgrid(self.x, self.y, indexing="ij")
        return np.column_stack([xx.ravel(), yy.ravel()])


def whole_ratio(a: float, b: float) -> int | None:
    """``a / b`` if it is a whole number >= 1 (to 1e-9), else None."""
    k = a / b
    return int(round(k)) if abs(k - round(k)) < 1e-9 and round(k) >= 1 else None


def score_grid(hmap: HeightMap, scorer, **options) -> ScoreGrid:
    """The terrain part of a scorer at every lattice point of the map: ``scorer.dense(hmap, ...)``.

    ``scorer`` is any :class:`~footfall.features.scorer.FootholdScorer`;
    ``options`` are :meth:`~footfall.features.scorer.FootholdScorer.dense`'s
    (``spacing`` [m], ``yaw`` [rad], ``mirror``, ``dtype``, ``fast``).
    """
    return scorer.dense(hmap, **options)


def linear_values(c: Candidates, parts: Sequence[tuple[FeatureFamily, np.ndarray]]) -> np.ndarray:
    """The sum (n,) of ``family.compute(c) @ weights`` over ``parts``, in their order; 0 if none."""
    values = [c.columns(family) @ w for family, w in parts]
    return sum(values[1:], values[0]) if values else np.zeros(c.n)


def lattice_index(x0: float, y0: float, xy: np.ndarray, spacing: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Index (i, j) of the lattice point nearest each position (..., 2) [m] on the lattice of
    ``spacing`` [m] whose point (0, 0) is at (``x0``, ``y0``) [m]; may be off the lattice."""
    xy = np.asarray(xy, dtype=np.float64)
    i = np.floor((xy[..., 0] - x0) / spacing + 0.5).astype(np.int64)
    j = np.floor((xy[..., 1] - y0) / spacing + 0.5).astype(np.int64)
    return i, j


def lattice_points(hmap: HeightMap, spacing: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lattice points (n, 2) [m] every ``spacing`` over the map, and their x (na,), y (nb,) [m]."""
    if not spacing > 0:
        raise FootfallError(f"candidate spacing must be > 0, got {spacing}")
    x0, x1, y0, y1 = hmap.bounds
    pts = lattice(hmap, (x0, x1 - 1e-12), (y0, y1 - 1e-12), spacing)
    return pts, np.unique(pts[:, 0]), np.unique(pts[:, 1])


def dense_values(hmap: HeightMap, values: Callable[[Candidates], np.ndarray],
                 config: FeatureConfig, *, spacing: float = 0.005, yaw: float = 0.0,
                 mirror: bool = False) -> ScoreGrid:
    """Any terrain-only value ``values(candidates) -> (n,)`` at every lattice point of the map.

    The generic dense form, in blocks of lattice points (every ``spacing``
    [m], heading ``yaw`` [rad], mirrored for a right leg). At heading 0 with
    the spacing and the template resolution whole multiples of the map
    resolution -- the planners' usual case -- every patch sample is a cell
    centre and the patches are gathered from the map by index; otherwise
    they are interpolated. Both give :func:`foothold_patches`'s patches.
    """
    pts, xs, ys = lattice_points(hmap, spacing)
    step = whole_ratio(spacing, hmap.resolution)
    tap = whole_ratio(config.template_resolution, hmap.resolution)
    patches = None
    if step is not None and tap is not None and yaw == 0.0:
        cells = np.rint((pts - np.asarray(hmap.origin)) / hmap.resolution).astype(np.intp)
        patches = _aligned(hmap, cells, config, tap, mirror)
    r, valid = dense_general(hmap, values, config, pts, yaw, mirror, patches)
    return ScoreGrid(xs, ys, r.reshape(xs.size, ys.size), valid.reshape(xs.size, ys.size))


def _valid_only(c: Candidates) -> np.ndarray:
    """0 where a candidate is a valid foothold, -inf elsewhere (n,)."""
    return np.where(c.patches.valid, 0.0, -np.inf)


def dense_validity(hmap: HeightMap, config: FeatureConfig, *, spacing: float = 0.005,
                   yaw: float = 0.0, mirror: bool = False) -> ScoreGrid:
    """Where every lattice point is a valid foothold: reward 0 there, -inf elsewhere.

    The dense form of a terrain part that is nothing but validity -- that of
    a value that needs the robot's state (a learned function with pose
    features) --: data under the point, and every scale's patch covered at
    least ``config.min_coverage``. Where the lattice and the patch samples
    fall on map cells (heading 0, whole ratios) the samples with data of each
    window are counted by running sums (:func:`window_sums` of the data mask,
    whole numbers, exact) instead of gathering every patch, and the coverage
    rule is :func:`foothold_patches`'s in its arithmetic: the same grid as
    :func:`dense_values` of the validity, bit for bit. Elsewhere it is that.
    """
    step = whole_ratio(spacing, hmap.resolution)
    tap = whole_ratio(config.template_resolution, hmap.resolution)
    if step is None or tap is None or yaw != 0.0:
        return dense_values(hmap, _valid_only, config, spacing=spacing, yaw=yaw, mirror=mirror)
    _, xs, ys = lattice_points(hmap, spacing)
    ox, oy = hmap.origin
    ci = np.rint((xs - ox) / hmap.resolution).astype(np.intp)  # the lattice's map cells
    cj = np.rint((ys - oy) / hmap.resolution).astype(np.intp)
    data = ~np.isnan(hmap.heights)
    valid = data[np.ix_(ci, cj)]
    mx = max(g.half_counts[0] for g in config.grids) * tap
    my = max(g.half_counts[1] for g in config.grids) * tap
    padded = np.zeros((data.shape[0] + 2 * mx, data.shape[1] + 2 * my))  # off the map: no data
    padded[mx:mx + data.shape[0], my:my + data.shape[1]] = data
    for grid in config.grids:  # the windows are symmetric: mirroring changes no count
        hu, hv = grid.half_counts
        nu, nv = grid.shape
        count, _ = window_sums(padded, tap, ci + mx - hu * tap, cj + my - hv * tap, nu, nv)
        valid &= 1.0 - (grid.size - count) / grid.size >= config.min_coverage
    return ScoreGrid(xs, ys, np.where(valid, 0.0, -np.inf), valid)


def _aligned(hmap: HeightMap, cells: np.ndarray, config: FeatureConfig, tap: int, mirror: bool
             ) -> Callable[[slice], FootholdPatches]:
    """Patches of the points at map cells ``cells`` (n, 2), whose samples lie ``tap`` cells
    apart: gathered from the map, padded with no data, by index (a block of points at a time)."""
    margin = np.array([max(g.half_counts[k] for g in config.grids) * tap for k in (0, 1)])
    padded = np.pad(hmap.heights, ((margin[0],) * 2, (margin[1],) * 2), constant_values=np.nan)
    width = padded.shape[1]
    flat_map = padded.ravel()
    offsets = []  # per scale: the sample offsets in the flat padded map, in patch order
    for grid in config.grids:  # three scales
        hu, hv = grid.half_counts
        du = (np.arange(grid.shape[0]) - hu) * tap
        dv = (np.arange(grid.shape[1]) - hv) * tap * (-1 if mirror else 1)
        offsets.append((du[:, None] * width + dv[None, :]).ravel())
    centres = (cells[:, 0] + margin[0]) * width + cells[:, 1] + margin[1]

    def block(sl: slice) -> FootholdPatches:
        at = centres[sl]
        h0 = flat_map[at]
        rel = tuple(np.take(flat_map, at[:, None] + o) - h0[:, None] for o in offsets)
        cov = (np.stack([1.0 - np.isnan(r).mean(axis=1) for r in rel], axis=1) if at.size
               else np.zeros((0, len(rel))))
        valid = ~np.isnan(h0) & np.all(cov >= config.min_coverage, axis=1)
        return FootholdPatches(h0, rel, cov, valid)

    return block


def dense_general(hmap: HeightMap, values: Callable[[Candidates], np.ndarray],
                   config: FeatureConfig, pts: np.ndarray, yaw: float, mirror: bool,
                   patches: Callable[[slice], FootholdPatches] | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Values and validity of points (n, 2) [m], in blocks: patches from ``patches(block)``, or
    interpolated."""
    block = max(1, _BLOCK_FLOATS // sum(g.size for g in config.grids))
    out = np.empty(pts.shape[0])
    valid = np.empty(pts.shape[0], dtype=bool)
    for start in range(0, pts.shape[0], block):  # blocks of candidates, each vectorised
        sl = slice(start, start + block)
        fp = (foothold_patches(hmap, pts[sl], yaw, mirror, config) if patches is None
              else patches(sl))
        footholds = np.column_stack([pts[sl], fp.heights])  # contact points: x, y, map height
        c = Candidates(hmap, footholds, yaw, mirror, config, given_patches=fp)
        out[sl] = values(c)
        valid[sl] = fp.valid
    return out, valid


