"""Scoring footholds with a linear reward: a candidate set, or a whole board at once.

:func:`score_footholds` evaluates the full reward (terrain, templates, pose)
of a candidate set F for a robot state. :func:`score_grid` evaluates the
terrain part (terrain features + templates; pose needs a state) of every
lattice point of a board in one call. Where the lattice, the patch samples
and the map cells line up (heading 0 or pi, spacing and template resolution
whole multiples of the map resolution: the usual case for boards) the
patches are strided views of the map and scoring is one matrix product per
scale,

    [C] @ [templates^T | fit kernels | 1]   with  sum (t - c)^2 = t.t + c.c - 2 c.t,

in blocks that fit in cache. Otherwise patches are interpolated, in blocks.
Both give the same numbers as the per-candidate definitions.
"""

from __future__ import annotations

from dataclasses import dataclass

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from threadpoolctl import threadpool_limits

from footfall.candidates import lattice
from footfall.errors import FootfallError
from footfall.heightmap import HeightMap
from footfall.patches import foothold_patches
from footfall.pose_features import pose_features
from footfall.reward import LinearReward
from footfall.robot import LITTLEDOG, RobotDescription
from footfall.state import RobotState
from footfall.terrain_features import fit_kernels, raw_features, split_signed
from footfall.templates import rbf_features

_BLOCK_FLOATS = 1 << 20  # patch values per block (8 MiB of float64): stays in cache


def _workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


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


def score_footholds(hmap: HeightMap, state: RobotState, footholds: np.ndarray,
                    reward: LinearReward, robot: RobotDescription = LITTLEDOG) -> np.ndarray:
    """Full reward (terrain + templates + pose) of candidate footholds (n, 3) -> (n,).

    Footholds that are not valid (no data, too little patch coverage) get -inf.
    """
    leg = robot.leg(state.swing_leg)
    f = np.asarray(footholds, dtype=np.float64).reshape(-1, 3)
    patches = foothold_patches(hmap, f, state.yaw, leg.mirrored, reward.config)
    r = reward.terrain_reward(patches)
    if np.any(reward.pose_weights != 0):
        r = r + pose_features(hmap, state, f, robot) @ reward.pose_weights
    return r


def _ratio(a: float, b: float) -> int | None:
    k = a / b
    return int(round(k)) if abs(k - round(k)) < 1e-9 and round(k) >= 1 else None


def score_grid(hmap: HeightMap, reward: LinearReward, *, spacing: float = 0.005,
               yaw: float = 0.0, mirror: bool = False, dtype: type = np.float64,
               fast: bool = True) -> ScoreGrid:
    """Terrain reward of every lattice point of the map (every ``spacing`` metres).

    Parameters
    ----------
    spacing : float
        Lattice spacing [m], measured from the centre of cell (0, 0).
    yaw : float
        Body heading [rad] that orients the patches.
    mirror : bool
        Score for a right leg (patches mirrored in y).
    dtype : numpy float type
        Precision of the fast path's matrix products (float32 halves the memory
        traffic; rewards then agree with float64 to ~1e-5 relative).
    fast : bool
        Allow the strided matrix-product path; ``False`` forces interpolation.
    """
    if not spacing > 0:
        raise FootfallError(f"candidate spacing must be > 0, got {spacing}")
    x0, x1, y0, y1 = hmap.bounds
    pts = lattice(hmap, (x0, x1 - 1e-12), (y0, y1 - 1e-12), spacing)
    ox, oy = hmap.origin
    xs = np.unique(pts[:, 0])
    ys = np.unique(pts[:, 1])
    step = _ratio(spacing, hmap.resolution)
    tap = _ratio(reward.config.template_resolution, hmap.resolution)
    quarter = np.round(yaw / (np.pi / 2))
    flip = None
    if abs(yaw - quarter * np.pi / 2) < 1e-12 and int(quarter) % 2 == 0:
        flip = int(quarter) % 4 == 2  # heading pi: the patch is the map turned half a turn
    if fast and step is not None and tap is not None and flip is not None:
        r, valid = _dense_aligned(hmap, reward, step, tap, flip, mirror, dtype)
    else:
        r, valid = _dense_general(hmap, reward, pts, yaw, mirror)
        r, valid = r.reshape(xs.size, ys.size), valid.reshape(xs.size, ys.size)
    del ox, oy
    return ScoreGrid(xs, ys, r, valid)


def _dense_general(hmap: HeightMap, reward: LinearReward, pts: np.ndarray, yaw: float,
                   mirror: bool) -> tuple[np.ndarray, np.ndarray]:
    block = max(1, _BLOCK_FLOATS // sum(g.size for g in reward.config.grids))
    out = np.empty(pts.shape[0])
    valid = np.empty(pts.shape[0], dtype=bool)
    for start in range(0, pts.shape[0], block):  # blocks of candidates, each vectorised
        sl = slice(start, start + block)
        fp = foothold_patches(hmap, pts[sl], yaw, mirror, reward.config)
        out[sl] = reward.terrain_reward(fp)
        valid[sl] = fp.valid
    return out, valid


def _scale_kernel(reward: LinearReward, s: int, flip_u: bool, flip_v: bool) -> np.ndarray:
    """Columns [templates^T | fit kernels | ones] of scale s, oriented to the map, (taps, T+5)."""
    grid = reward.config.grids[s]
    nu, nv = grid.shape
    parts = []
    if reward.library is not None:
        parts.append(reward.library.templates[s].T)
    parts.append(fit_kernels(grid))
    k = np.concatenate(parts + [np.ones((grid.size, 1))], axis=1).reshape(nu, nv, -1).copy()
    n_t = k.shape[2] - 5
    # Orient the kernels instead of the patches: a flipped patch dotted with a
    # kernel equals the patch dotted with the flipped kernel. The fitted slopes
    # change sign with the flip of their own axis.
    if flip_u:
        k = k[::-1]
        k[:, :, n_t + 0] *= -1  # slope_x
    if flip_v:
        k = k[:, ::-1]
        k[:, :, n_t + 1] *= -1  # slope_y
    return k.reshape(grid.size, -1)


def _dense_aligned(hmap: HeightMap, reward: LinearReward, step: int, tap: int, half_turn: bool,
                   mirror: bool, dtype: type) -> tuple[np.ndarray, np.ndarray]:
    config = reward.config
    h = hmap.heights
    nx, ny = h.shape
    ia = np.arange(0, nx, step)
    jb = np.arange(0, ny, step)
    na, nb = ia.size, jb.size
    grids = config.grids
    mx = max(g.half_counts[0] for g in grids) * tap
    my = max(g.half_counts[1] for g in grids) * tap
    padded = np.full((nx + 2 * mx, ny + 2 * my), np.nan, dtype=dtype)
    padded[mx:mx + nx, my:my + ny] = h
    h0 = h[np.ix_(ia, jb)].astype(dtype)
    reward_out = np.zeros((na, nb))
    valid = ~np.isnan(h0)  # (na, nb), contiguous: blocks of it are views
    # At heading pi the patch's u and v axes run against the map's x and y.
    flip_u = half_turn
    flip_v = half_turn != mirror
    s0, s1 = padded.strides
    local = threading.local()
    for s, grid in enumerate(grids):  # three scales
        hu, hv = grid.half_counts
        nu, nv = grid.shape
        kern = _scale_kernel(reward, s, flip_u, flip_v).astype(dtype)
        n_t = kern.shape[1] - 5
        templates = reward.library.templates[s] if n_t else np.zeros((0, grid.size))
        tt = (templates ** 2).sum(axis=1)
        base = padded[mx - hu * tap:, my - hv * tap:]
        view = np.lib.stride_tricks.as_strided(
            base, shape=(na, nb, nu, nv), strides=(step * s0, step * s1, tap * s0, tap * s1),
            writeable=False)
        rows = max(1, _BLOCK_FLOATS // (nb * grid.size))
        tw = reward.terrain_weights[9 * s:9 * (s + 1)]
        ttw = reward.template_weights[s] if n_t else np.zeros(0)
        hs = reward.bandwidths[s] if n_t else 0.0

        def block(a: int, s=s, grid=grid, nu=nu, nv=nv, kern=kern, n_t=n_t, templates=templates,
                  tt=tt, view=view, rows=rows, tw=tw, ttw=ttw, hs=hs) -> None:
            sl = slice(a, a + rows)
            k = min(rows, na - a)
            buf = getattr(local, f"buf{s}", None)
            if buf is None:  # one buffer per thread and scale: no page faults per block
                buf = np.empty((rows, nb, nu, nv), dtype=dtype)
                setattr(local, f"buf{s}", buf)
            c = np.subtract(view[sl], h0[sl, :, None, None], out=buf[:k]).reshape(-1, grid.size)
            g = (c @ kern).astype(np.float64)
            cc = np.einsum("ij,ij->i", c, c).astype(np.float64)
            mean = g[:, -1] / grid.size
            raw = np.empty((c.shape[0], 5))
            raw[:, :4] = g[:, n_t:n_t + 4]
            raw[:, 4] = np.sqrt(np.maximum(cc / grid.size - mean * mean, 0.0))
            x = np.exp(-hs * np.maximum(tt[None, :] + cc[:, None] - 2.0 * g[:, :n_t], 0.0))
            holes = np.flatnonzero(np.isnan(cc))
            if holes.size:
                # Patches with holes or off the map: the masked definitions, in
                # the patch's own orientation.
                part = c[holes].reshape(-1, nu, nv)[:, ::-1 if flip_u else 1, ::-1 if flip_v else 1]
                part = part.reshape(-1, grid.size).astype(np.float64)
                coverage = 1.0 - np.isnan(part).mean(axis=1)
                raw[holes] = raw_features(part, grid)
                if n_t:
                    x[holes] = rbf_features(part, templates, hs)
                block_valid = valid[sl].reshape(-1)  # a view: updated in place
                block_valid[holes] &= coverage >= config.min_coverage
            r = split_signed(raw) @ tw
            if n_t:
                r = r + x @ ttw
            reward_out[sl] += r.reshape(-1, nb)  # each block owns its rows: no race

        # NumPy and BLAS release the GIL: blocks run on all cores, BLAS itself on one.
        with threadpool_limits(limits=1, user_api="blas"):
            with ThreadPoolExecutor(max_workers=_workers()) as pool:
                list(pool.map(block, range(0, na, rows)))
    return np.where(valid, reward_out, -np.inf), valid
