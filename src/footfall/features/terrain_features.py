"""Multi-scale terrain features of a foothold (paper §V).

On each scale, from the heights of the patch around the foothold in the
body's heading frame: the slope along x and y (gradient of a least-squares
plane, dz/dx and dz/dy [-]), the curvature along x and y (second derivatives
2a and 2b of a least-squares quadric z = a x^2 + b y^2 + c xy + d x + e y + f
[1/m]; positive = curving up, a hollow), each split into its positive part and
the magnitude of its negative part, and the standard deviation of the heights
[m]: 9 per scale, 27 in all.

All fits are linear in the heights, so on a patch with data everywhere each
raw quantity is a fixed kernel dotted with the patch: a whole candidate set
is one matrix product. Patches with holes (NaN) are fitted by least squares
over the samples that have data only.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache
from typing import ClassVar

import numpy as np

from footfall.core.heightmap import PatchGrid
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.features.family import (
    Candidates,
    DenseTerms,
    FeatureFamily,
    register_family,
    require_no_params,
)

RAW_NAMES = ("slope_x", "slope_y", "curv_x", "curv_y")  # linear in the heights
QUANTITIES = ("slope_x_pos", "slope_x_neg", "slope_y_pos", "slope_y_neg",
              "curv_x_pos", "curv_x_neg", "curv_y_pos", "curv_y_neg", "std")
_POS = [QUANTITIES.index(f"{r}_pos") for r in RAW_NAMES]  # each raw fit's positive part
_NEG = [QUANTITIES.index(f"{r}_neg") for r in RAW_NAMES]  # and its negative part
_STD = QUANTITIES.index("std")


def feature_names(config: FeatureConfig | None = None) -> tuple[str, ...]:
    """The 27 terrain feature names, ``scale.quantity``, in column order."""
    config = config or FeatureConfig()
    return tuple(f"{s}.{q}" for s in config.scale_names for q in QUANTITIES)


TERRAIN_FEATURE_NAMES = feature_names()


def _designs(grid: PatchGrid) -> tuple[np.ndarray, np.ndarray]:
    """Plane and quadric design matrices over the patch samples, (taps, 3) and (taps, 6)."""
    u, v = np.meshgrid(grid.u, grid.v, indexing="ij")
    u, v = u.ravel(), v.ravel()
    one = np.ones_like(u)
    plane = np.stack([u, v, one], axis=1)
    quad = np.stack([u * u, v * v, u * v, u, v, one], axis=1)
    return plane, quad


@lru_cache(maxsize=32)
def _kernels_cached(length_x: float, length_y: float, resolution: float) -> np.ndarray:
    plane, quad = _designs(PatchGrid(length_x, length_y, resolution))
    pp = np.linalg.pinv(plane)  # (3, taps)
    pq = np.linalg.pinv(quad)  # (6, taps)
    k = np.stack([pp[0], pp[1], 2 * pq[0], 2 * pq[1]], axis=1)
    k.setflags(write=False)
    return k


def fit_kernels(grid: PatchGrid) -> np.ndarray:
    """Kernels (taps, 4) giving slope_x, slope_y, curv_x, curv_y of a full patch.

    ``patch.ravel() @ fit_kernels(grid)`` equals the least-squares fits; each
    kernel sums to zero, so adding a constant height changes nothing.
    """
    return _kernels_cached(grid.length_x, grid.length_y, grid.resolution)


def coordinate_scales(grid: PatchGrid) -> tuple[float, float]:
    """Half-extents (su, sv) [m] of a patch; masked fits work in u / su and v / sv.

    On normalised coordinates (within [-1, 1]) the normal equations of the
    quadric are well conditioned on every scale, also in float32.
    """
    hu, hv = grid.half_counts
    return (hu * grid.resolution or 1.0), (hv * grid.resolution or 1.0)


@lru_cache(maxsize=32)
def _moment_basis(length_x: float, length_y: float, resolution: float) -> np.ndarray:
    """Monomials u^i v^j (i + j <= 4) of normalised coordinates, (taps, 15), in _MONOMIALS order."""
    grid = PatchGrid(length_x, length_y, resolution)
    su, sv = coordinate_scales(grid)
    u, v = np.meshgrid(grid.u / su, grid.v / sv, indexing="ij")
    u, v = u.ravel(), v.ravel()
    basis = np.stack([u ** i * v ** j for i, j in _MONOMIALS], axis=1)
    basis.setflags(write=False)
    return basis


def moment_basis(grid: PatchGrid) -> np.ndarray:
    """Monomials (u/su)^i (v/sv)^j, i + j <= 4, over the patch samples, (taps, 15).

    Column k is the monomial ``MONOMIALS[k]``; the quadric's own terms are
    columns ``QUAD_COLUMNS``. ``mask @ basis`` are the moments of the masked
    normal equations, ``z @ basis[:, QUAD_COLUMNS]`` their right-hand sides.
    """
    return _moment_basis(grid.length_x, grid.length_y, grid.resolution)


# Exponents (i, j) of the monomials u^i v^j that the normal equations of the
# quadric fit are made of; the quadric's own terms are u^2, v^2, uv, u, v, 1.
_MONOMIALS = tuple((i, d - i) for d in range(5) for i in range(d, -1, -1))
MONOMIALS = _MONOMIALS
_QUAD_TERMS = ((2, 0), (0, 2), (1, 1), (1, 0), (0, 1), (0, 0))
_PLANE_TERMS = ((1, 0), (0, 1), (0, 0))
_INDEX = {m: k for k, m in enumerate(_MONOMIALS)}
QUAD_COLUMNS = tuple(_INDEX[t] for t in _QUAD_TERMS)  # basis columns of u^2, v^2, uv, u, v, 1


@lru_cache(maxsize=32)
def _quad_to_fits_cached(length_x: float, length_y: float, resolution: float) -> np.ndarray:
    grid = PatchGrid(length_x, length_y, resolution)
    quad = moment_basis(grid)[:, QUAD_COLUMNS]
    kernels = fit_kernels(grid)
    # The fit kernels are rows of the designs' pseudo-inverses, so they lie in the span of the
    # quadric's monomials: kernels = quad @ m exactly (to rounding).
    m = np.linalg.lstsq(quad, kernels, rcond=None)[0]
    m = np.ascontiguousarray(m.T)
    m.setflags(write=False)
    return m


def quad_to_fits(grid: PatchGrid) -> np.ndarray:
    """The matrix (4, 6) taking a full patch's sums ``z @ moment_basis(grid)[:, QUAD_COLUMNS]``
    to its slope_x, slope_y, curv_x, curv_y (those of :func:`fit_kernels`)."""
    return _quad_to_fits_cached(grid.length_x, grid.length_y, grid.resolution)


def _solve_spd(normal: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve symmetric positive definite systems (n, p, p) x = (n, p) by Cholesky.

    Vectorised over the n systems (loops over the p <= 6 unknowns only): far
    faster than a LAPACK call per system for thousands of tiny ones.
    """
    n, p = rhs.shape
    a = np.ascontiguousarray(np.moveaxis(normal, 0, -1))  # (p, p, n): rows of entries
    low = [[None] * p for _ in range(p)]
    tiny = np.finfo(np.float64).tiny
    for j in range(p):
        d = a[j, j].copy()
        for k in range(j):
            d -= low[j][k] * low[j][k]
        # Guard against rounding on (near) singular masks: no NaN, no warning.
        low[j][j] = np.sqrt(np.maximum(d, tiny))
        for i in range(j + 1, p):
            e = a[i, j].copy()
            for k in range(j):
                e -= low[i][k] * low[j][k]
            low[i][j] = e / low[j][j]
    b = np.asarray(rhs, dtype=np.float64)
    y = [None] * p
    for i in range(p):  # forward substitution: L y = b
        e = b[:, i].copy()
        for k in range(i):
            e -= low[i][k] * y[k]
        y[i] = e / low[i][i]
    x = [None] * p
    for i in range(p - 1, -1, -1):  # back substitution: L^T x = y
        e = y[i].copy()
        for k in range(i + 1, p):
            e -= low[k][i] * x[k]
        x[i] = e / low[i][i]
    return np.stack(x, axis=1)


def _solve_fit(moments: np.ndarray, rhs: np.ndarray, terms: tuple) -> np.ndarray:
    """Solve the masked normal equations of a fit with the given monomial terms."""
    pick = np.array([[_INDEX[(a[0] + b[0], a[1] + b[1])] for b in terms] for a in terms])
    normal = moments[:, pick]  # (n, p, p)
    p = len(terms)
    # A tiny ridge keeps degenerate masks (all samples on one line) solvable;
    # on normalised coordinates it moves a well-posed fit by ~1e-12 relative.
    ridge = 1e-12 * np.trace(normal, axis1=1, axis2=2)[:, None, None] * np.eye(p)
    return _solve_spd(normal + ridge, rhs)


def masked_fits(moments: np.ndarray, zq: np.ndarray, zz: np.ndarray, grid: PatchGrid
                ) -> np.ndarray:
    """Raw features of patches from their masked moments, (n, 5) [see raw_features].

    Parameters
    ----------
    moments : array of shape (n, 15)
        ``mask @ moment_basis(grid)``: sums of the monomials over the samples with data.
    zq : array of shape (n, 6)
        ``z @ moment_basis(grid)[:, QUAD_COLUMNS]`` with z the relative heights [m], 0 where
        no data.
    zz : array of shape (n,)
        Sums of z^2 [m^2].
    """
    moments = np.asarray(moments, dtype=np.float64)
    zq = np.asarray(zq, dtype=np.float64)
    su, sv = coordinate_scales(grid)
    plane = _solve_fit(moments, zq[:, 3:], _PLANE_TERMS)
    quad = _solve_fit(moments, zq, _QUAD_TERMS)
    count = moments[:, _INDEX[(0, 0)]]
    mean = zq[:, 5] / count
    var = np.maximum(np.asarray(zz, dtype=np.float64) / count - mean * mean, 0.0)
    return np.column_stack([plane[:, 0] / su, plane[:, 1] / sv, 2 * quad[:, 0] / (su * su),
                            2 * quad[:, 1] / (sv * sv), np.sqrt(var)])


def _masked_stats(rel: np.ndarray, grid: PatchGrid) -> np.ndarray:
    """Slope, curvature and std over the samples with data only, (n, taps) -> (n, 5).

    The least-squares normal equations of every patch are assembled from the
    15 moments sum(mask * u^i v^j) (normalised coordinates): one matrix
    product for the whole set.
    """
    basis = moment_basis(grid)
    mask = ~np.isnan(rel)
    z = np.where(mask, rel, 0.0)
    moments = mask.astype(np.float64) @ basis  # (n, 15)
    zq = z @ basis[:, QUAD_COLUMNS]  # (n, 6): sums of z * term
    return masked_fits(moments, zq, np.einsum("ij,ij->i", z, z), grid)


def raw_features(rel: np.ndarray, grid: PatchGrid) -> np.ndarray:
    """Raw fits of patches: slope_x, slope_y [-], curv_x, curv_y [1/m], std [m].

    Parameters
    ----------
    rel : array of shape (n, taps)
        Patch heights [m] (flattened ``(nu, nv)`` in C order), NaN where no data.

    Returns
    -------
    array of shape (n, 5). Complete patches use the fixed kernels of
    :func:`fit_kernels`; patches with holes are fitted over the samples that
    hold data; patches with fewer than 6 such samples (a quadric needs 6) are NaN.
    """
    rel = np.asarray(rel, dtype=np.float64)
    out = np.full((rel.shape[0], 5), np.nan)
    count = rel.shape[1] - np.isnan(rel).sum(axis=1)
    full = count == rel.shape[1]
    if full.any():
        zf = rel[full]
        out[full, :4] = zf @ fit_kernels(grid)
        out[full, 4] = zf.std(axis=1)
    part = ~full & (count >= 6)
    if part.any():
        out[part] = _masked_stats(rel[part], grid)
    return out


def split_signed(raw: np.ndarray) -> np.ndarray:
    """Raw (n, 5) -> the 9 per-scale features: each signed fit as (max(g,0), max(-g,0)), then std."""
    signed = raw[:, :4]
    pos = np.maximum(signed, 0.0)
    neg = np.maximum(-signed, 0.0)
    parts = np.stack([pos, neg], axis=2).reshape(raw.shape[0], 8)
    return np.concatenate([parts, raw[:, 4:5]], axis=1)


def terrain_features_from_patches(rel_patches: tuple[np.ndarray, ...],
                                  config: FeatureConfig) -> np.ndarray:
    """The 27 features from per-scale patches ((n, taps_s) each) -> (n, 27)."""
    return np.concatenate([split_signed(raw_features(p, g))
                           for p, g in zip(rel_patches, config.grids)], axis=1)


@register_family
@dataclass(frozen=True, eq=False)
class TerrainFeatures(FeatureFamily):
    """The multi-scale terrain features as a feature family: 9 per scale (see the module).

    Linear in the patch heights up to the sign split and the square root of
    the variance, so the dense scorer evaluates them from a handful of matrix
    products (:meth:`dense`).
    """

    name: ClassVar[str] = "terrain"
    config: FeatureConfig = field(default_factory=FeatureConfig)

    @classmethod
    def create(cls, config: FeatureConfig, robot: RobotDescription = LITTLEDOG) -> TerrainFeatures:
        return cls(config)

    @classmethod
    def from_params(cls, config: FeatureConfig, robot: RobotDescription, arrays, meta
                    ) -> TerrainFeatures:
        require_no_params(arrays, meta)
        return cls(config)

    def columns(self) -> tuple[str, ...]:
        return feature_names(self.config)

    def compute(self, c: Candidates) -> np.ndarray:
        return terrain_features_from_patches(c.patches.relative, self.config)

    def memo_key(self) -> tuple[str, str]:
        """No learned parameters: the name and the feature settings identify the columns."""
        return self.name, repr(self.config.to_dict())

    def dense(self, scale: int, weights: np.ndarray, dtype: np.dtype) -> DenseTerms:
        grid = self.config.grids[scale]
        k = len(QUANTITIES)
        tw = np.asarray(weights, dtype=np.float64)[k * scale:k * (scale + 1)]
        basis = moment_basis(grid)
        quad = basis[:, QUAD_COLUMNS]
        from_quad = quad_to_fits(grid)

        def add_full(zt: np.ndarray, zz: np.ndarray, total: np.ndarray, r: np.ndarray) -> None:
            fits = from_quad @ zt.astype(np.float64)  # slope_x, slope_y, curv_x, curv_y
            r += tw[_POS] @ np.maximum(fits, 0.0) - tw[_NEG] @ np.minimum(fits, 0.0)
            mean = total / grid.size
            r += tw[_STD] * np.sqrt(np.maximum(zz / grid.size - mean * mean, 0.0))

        def masked(zt: np.ndarray, mt: np.ndarray, zz: np.ndarray, count: np.ndarray) -> np.ndarray:
            moments = np.asarray(mt).T
            raw = masked_fits(moments, np.asarray(zt).T, zz, grid)
            raw[np.asarray(count) < 6] = np.nan  # a quadric needs 6 samples: no guess
            return split_signed(raw) @ tw

        return DenseTerms(z_columns=quad, m_columns=basis, add_full=add_full, masked=masked)
