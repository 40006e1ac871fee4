"""Scoring footholds with a linear reward: a candidate set, or a whole board at once.

:func:`score_footholds` evaluates the full reward (terrain, templates, pose)
of a candidate set F for a robot state. :func:`score_grid` evaluates the
terrain part (terrain features + templates; pose needs a state) of every
lattice point of a board in one call. Where the lattice, the patch samples
and the map cells line up (heading 0 or pi, spacing and template resolution
whole multiples of the map resolution: the usual case for boards) the
patches are gathered from the map by long contiguous copies and scoring is
one matrix product per scale,

    [2h templates | fit kernels | 1]^T @ [C]   with  sum (t - c)^2 = t.t + c.c - 2 c.t,

in blocks of lattice rows, on all cores. Windows with no-data samples (holes,
or off the map at its border) are fitted over the samples that hold data,
from their masked moments; windows whose coverage is too low are skipped.
Otherwise patches are interpolated, in blocks. Both give the same numbers as
the per-candidate definitions.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from threadpoolctl import ThreadpoolController

from footfall.features.candidates import lattice
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap, PatchGrid
from footfall.features.patches import foothold_patches
from footfall.features.pose_features import pose_features
from footfall.features.reward import LinearReward
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.terrain_features import (QUAD_COLUMNS, fit_kernels, masked_fits, moment_basis,
                                       split_signed)

_BLOCK_FLOATS = 1 << 20  # patch values per block of the interpolating path
_BLOCK_BYTES = 8 << 20  # patches per block of the strided path: two blocks stay in L3


@lru_cache(maxsize=1)
def _blas() -> ThreadpoolController:
    """The BLAS libraries, inspected once: limiting their threads per call is then cheap."""
    return ThreadpoolController()


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
               yaw: float = 0.0, mirror: bool = False, dtype: type = np.float32,
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
        Precision of the fast path's matrix products. The default, float32,
        halves the memory traffic; its rewards agree with float64 to ~1e-5
        relative, far below any difference that changes a foothold choice.
        Pass ``np.float64`` for agreement with the per-candidate path to ~1e-11.
    fast : bool
        Allow the strided matrix-product path; ``False`` forces interpolation.
    """
    if not spacing > 0:
        raise FootfallError(f"candidate spacing must be > 0, got {spacing}")
    x0, x1, y0, y1 = hmap.bounds
    pts = lattice(hmap, (x0, x1 - 1e-12), (y0, y1 - 1e-12), spacing)
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


def _orient(w: np.ndarray, grid, flip_u: bool, flip_v: bool) -> np.ndarray:
    """Per-sample columns (taps, k) in patch order -> the same columns in map order.

    A patch turned to the map is the map's window flipped along u and/or v,
    so a patch dotted with a column equals the map window dotted with the
    flipped column: orient the columns once instead of every patch.
    """
    nu, nv = grid.shape
    w = w.reshape(nu, nv, -1)
    if flip_u:
        w = w[::-1]
    if flip_v:
        w = w[:, ::-1]
    return w.reshape(grid.size, -1)


def _scale_kernel(reward: LinearReward, s: int, flip_u: bool, flip_v: bool) -> np.ndarray:
    """Columns [templates^T | fit kernels | ones] of scale s, oriented to the map, (taps, T+5)."""
    grid = reward.config.grids[s]
    parts = []
    if reward.library is not None:
        parts.append(reward.library.templates[s].T)
    parts.append(fit_kernels(grid))
    k = np.concatenate(parts + [np.ones((grid.size, 1))], axis=1)
    return _orient(k, grid, flip_u, flip_v)


def _window_sums(q: np.ndarray, x0: np.ndarray, y0: np.ndarray, nu: int, nv: int,
                 tap: int) -> np.ndarray:
    """Sums of q[x0[a] + tap * i, y0[b] + tap * j] over i < nu, j < nv, for all (a, b), int64.

    An integral image per phase (x mod tap, y mod tap) of q: four look-ups a window.
    """
    px, py = -(-q.shape[0] // tap) * tap, -(-q.shape[1] // tap) * tap
    qq = np.zeros((px, py), dtype=np.int32)
    qq[:q.shape[0], :q.shape[1]] = q
    integral = np.zeros((px // tap + 1, tap, py // tap + 1, tap), dtype=np.int64)
    integral[1:, :, 1:, :] = qq.reshape(px // tap, tap, py // tap, tap).cumsum(0).cumsum(2)
    ix, fx = np.divmod(x0, tap)
    iy, fy = np.divmod(y0, tap)

    def at(i: np.ndarray, j: np.ndarray) -> np.ndarray:
        return integral[i[:, None], fx[:, None], j[None, :], fy[None, :]]

    return at(ix + nu, iy + nv) - at(ix, iy + nv) - at(ix + nu, iy) + at(ix, iy)


@dataclass(frozen=True)
class _ScalePlan:
    """Everything a block of scale s needs, in the map's orientation and buffer order."""

    s: int
    grid: PatchGrid
    rows: int  # lattice rows per block
    groups: tuple  # per phase group: (first buffer row, view (nq, np, na * width) of its samples)
    kern_t: np.ndarray  # (T + 5, taps) [2 h templates | fit kernels | ones]^T, dtype
    masked_z: np.ndarray  # (T + 6, taps) [templates | quadric terms]^T, dtype
    masked_m: np.ndarray  # (15 + T, taps) [monomials | templates^2]^T, dtype
    hs_tt: np.ndarray  # (T,) h * sum t^2, dtype
    hs: float  # [1/m^2] bandwidth
    n_t: int  # number of templates
    tw: np.ndarray  # (9,) terrain weights
    ttw: np.ndarray  # (T,) template weights, float64
    ttw_d: np.ndarray  # (T,) template weights, dtype
    dirty: np.ndarray  # (na * width,) bool: valid, but the window has no-data samples
    holed: np.ndarray | None  # (na * width,) bool: the window holds holes of the map
    prefix: np.ndarray  # (nu + 1, nv + 1, 15 + T) 2-D prefix sums of masked_m, map order
    span: tuple  # window samples on the map: u from, u to (na,); v from, v to (width,)


def _dense_aligned(hmap: HeightMap, reward: LinearReward, step: int, tap: int, half_turn: bool,
                   mirror: bool, dtype: type) -> tuple[np.ndarray, np.ndarray]:
    """Reward and validity (na, nb) of every lattice point where patches are map cells.

    ``step`` and ``tap`` are the lattice spacing and the patch sample spacing
    in cells. Validity (data at the point, coverage of every scale) is known
    up front from counts of the samples with data; windows with no-data
    samples are "dirty" and take the masked definitions: their moments are
    prefix-sum look-ups where only the map's edge cuts them (a rectangle of
    samples is left), mask products where a hole of the map lies in them.
    """
    config = reward.config
    dtype = np.dtype(dtype)
    h = hmap.heights
    nx, ny = h.shape
    na, nb = -(-nx // step), -(-ny // step)
    grids = config.grids
    mx = max(g.half_counts[0] for g in grids) * tap
    my = max(g.half_counts[1] for g in grids) * tap
    # The padded map in polyphase order: poly[rx, ry, m, n] = padded[step m + rx, step n + ry].
    # One patch sample of the lattice points (a0..a0+k, all b) is then one
    # contiguous run of k * width values of one phase (b >= nb are spare
    # points, computed and dropped), so that gathering a block of patches is
    # a few long copies. Heights relative to a reference keep their digits in float32.
    h0_map = h[::step, ::step]  # (na, nb) view: the lattice points' own heights
    has_data = ~np.isnan(h0_map)
    ref = float(h0_map[has_data].mean()) if has_data.any() else 0.0
    big_x, big_y = -(-(nx + 2 * mx) // step) + 1, -(-(ny + 2 * my) // step)
    padded = np.full((big_x * step, big_y * step), np.nan, dtype=dtype)
    np.subtract(h, ref, out=padded[mx:mx + nx, my:my + ny])
    poly = np.ascontiguousarray(padded.reshape(big_x, step, big_y, step).transpose(1, 3, 0, 2))
    width = big_y  # points per lattice row in a block: nb real, the rest spare
    h0 = np.full((na, width), np.nan, dtype=dtype)
    h0[:, :nb] = padded[mx:mx + nx:step, my:my + ny:step]
    holes = np.isnan(h)
    any_holes = bool(holes.any())
    # At heading pi the patch's u and v axes run against the map's x and y.
    flip_u = half_turn
    flip_v = half_turn != mirror

    plans = []
    valid = has_data.copy()
    ia, jb = np.arange(na), np.arange(nb)
    for s, grid in enumerate(grids):  # three scales
        hu, hv = grid.half_counts
        nu, nv = grid.shape
        # Samples with data in each window: the part on the map less the holes in it.
        x0 = mx - hu * tap + step * ia  # padded index of each window's first sample
        y0 = my - hv * tap + step * jb
        xs = x0[:, None] + tap * np.arange(nu) - mx
        ys = y0[:, None] + tap * np.arange(nv) - my
        on_x, on_y = (xs >= 0) & (xs < nx), (ys >= 0) & (ys < ny)
        count = on_x.sum(1)[:, None] * on_y.sum(1)[None, :]
        # The part of each window on the map: samples lo..hi along u (a) and v (b).
        span_u = (on_x.argmax(1), nu - 1 - on_x[:, ::-1].argmax(1))
        span_v = (on_y.argmax(1), nv - 1 - on_y[:, ::-1].argmax(1))
        holed = None
        if any_holes:
            q = np.zeros(padded.shape, dtype=bool)
            q[mx:mx + nx, my:my + ny] = holes
            in_holes = _window_sums(q, x0, y0, nu, nv, tap)
            count = count - in_holes
            holed = np.pad(in_holes > 0, ((0, 0), (0, width - nb))).ravel()
        # The coverage rule of foothold_patches, in its own arithmetic.
        valid &= 1.0 - (grid.size - count) / grid.size >= config.min_coverage
        plans.append((s, grid, count, span_u, span_v, holed))

    built = []
    item = poly.itemsize
    tq = tap // np.gcd(step, tap)  # phase rows (columns) between neighbouring samples of a group
    for s, grid, count, span_u, span_v, holed in plans:
        hu, hv = grid.half_counts
        nu, nv = grid.shape
        period = step // np.gcd(step, tap)  # samples u, u + period, ... share a phase
        groups, perm, row = [], [], 0
        for su in range(min(period, nu)):
            for sv in range(min(period, nv)):
                us, vs = np.arange(su, nu, period), np.arange(sv, nv, period)
                ex, ey = mx - hu * tap + tap * su, my - hv * tap + tap * sv
                # Sample (q, p) of the group for lattice point (a, b) is phase
                # element (m0 + a + tq q) * width + n0 + b + tq p: a run over (a, b).
                phase = poly[ex % step, ey % step].reshape(-1)
                start = (ex // step) * width + ey // step
                shape = (us.size, vs.size, na * width)
                strides = (tq * width * item, tq * item, item)
                if start + sum((n - 1) * d for n, d in zip(shape, strides)) // item >= phase.size:
                    raise AssertionError("patch gather would read past the padded map")
                groups.append((row, np.lib.stride_tricks.as_strided(
                    phase[start:], shape=shape, strides=strides, writeable=False)))
                perm.append((us[:, None] * nv + vs[None, :]).ravel())
                row += us.size * vs.size
        perm = np.concatenate(perm)
        n_t = reward.library.counts[s] if reward.library is not None else 0
        templates = reward.library.templates[s] if n_t else np.zeros((0, grid.size))
        hs = reward.bandwidths[s] if n_t else 0.0
        kern = _scale_kernel(reward, s, flip_u, flip_v)
        kern[:, :n_t] *= 2.0 * hs
        basis = moment_basis(grid)
        masked_z = _orient(np.concatenate([templates.T, basis[:, QUAD_COLUMNS]], axis=1),
                           grid, flip_u, flip_v)
        masked_m = _orient(np.concatenate([basis, (templates ** 2).T], axis=1),
                           grid, flip_u, flip_v)
        # Windows whose only no-data samples are off the map keep a rectangle
        # of samples: their masked sums are four look-ups in a 2-D prefix sum.
        prefix = np.zeros((nu + 1, nv + 1, masked_m.shape[1]))
        prefix[1:, 1:] = masked_m.reshape(nu, nv, -1).cumsum(0).cumsum(1)
        vlo = np.pad(span_v[0], (0, width - nb))
        vhi = np.pad(span_v[1], (0, width - nb))
        ttw = reward.template_weights[s] if n_t else np.zeros(0)
        built.append(_ScalePlan(
            s=s, grid=grid, rows=max(1, _BLOCK_BYTES // (dtype.itemsize * width * grid.size)),
            groups=tuple(groups),
            kern_t=np.ascontiguousarray(kern[perm].T, dtype=dtype),
            masked_z=np.ascontiguousarray(masked_z[perm].T, dtype=dtype),
            masked_m=np.ascontiguousarray(masked_m[perm].T, dtype=dtype),
            hs_tt=(hs * (templates ** 2).sum(axis=1)).astype(dtype), hs=hs, n_t=n_t,
            tw=reward.terrain_weights[9 * s:9 * (s + 1)], ttw=ttw, ttw_d=ttw.astype(dtype),
            dirty=np.pad(valid & (count < grid.size), ((0, 0), (0, width - nb))).ravel(),
            holed=holed, prefix=prefix, span=(span_u[0], span_u[1] + 1, vlo, vhi + 1)))

    out = np.zeros((len(grids), na, width))
    valid_w = np.pad(valid, ((0, 0), (0, width - nb))).ravel()
    local = threading.local()
    pending = [[] for _ in grids]  # per scale: masked fits of dirty windows, solved at the end

    def block(task: tuple[_ScalePlan, int]) -> None:
        plan, a0 = task
        grid = plan.grid
        k = min(plan.rows, na - a0)
        n = k * width
        buf = getattr(local, "buf", None)
        if buf is None:  # one buffer per thread, reused by every block and scale
            buf = np.empty(max(p.rows * width * p.grid.size for p in built), dtype=dtype)
            local.buf = buf
        c = buf[:grid.size * n].reshape(grid.size, n)  # (taps, points): relative heights
        h0b = h0[a0:a0 + k].reshape(-1)
        for row, src in plan.groups:
            part = src[:, :, a0 * width:a0 * width + n]
            taps = part.shape[0] * part.shape[1]
            np.subtract(part, h0b, out=c[row:row + taps].reshape(part.shape))
        here = slice(a0 * width, (a0 + k) * width)  # the block's points in flat lattice order
        idx = np.flatnonzero(plan.dirty[here])
        n_t = plan.n_t
        r = np.zeros(n)
        whole = 2 * idx.size > np.count_nonzero(valid_w[here])
        if whole:
            # Mostly windows with no-data samples (the map's border): all the
            # block's windows go through the masked definitions, in place.
            idx = np.flatnonzero(valid_w[here])
        else:
            g = plan.kern_t @ c  # (T + 5, n)
            cc = np.einsum("ij,ij->j", c, c)
            if n_t:
                # Eq. 4: -h sum (t - c)^2 = 2h c.t - h t.t - h c.c, never above 0.
                arg = g[:n_t] - plan.hs_tt[:, None]
                arg -= (plan.hs * cc).astype(dtype, copy=False)
                np.minimum(arg, 0.0, out=arg)
                np.exp(arg, out=arg)
                r += plan.ttw_d @ arg
            fits = g[n_t:n_t + 4].astype(np.float64)
            tw = plan.tw
            r += tw[0:8:2] @ np.maximum(fits, 0.0) - tw[1:8:2] @ np.minimum(fits, 0.0)
            mean = g[-1].astype(np.float64) / grid.size
            r += tw[8] * np.sqrt(np.maximum(cc / grid.size - mean * mean, 0.0))
        if idx.size:
            # Windows with no-data samples: the masked definitions, from the
            # masked moments and template sums of those windows only.
            z = c if whole else np.take(c, idx, axis=1)
            nodata = np.isnan(z)
            rect = plan.holed is None or not plan.holed[here][idx].any()
            if not rect:
                mt = plan.masked_m @ np.subtract(1, nodata, dtype=dtype)  # (15 + T, nd)
            np.putmask(z, nodata, 0)
            zt = plan.masked_z @ z  # (T + 6, nd)
            zz = np.einsum("ij,ij->j", z, z)
            if whole:
                zt, zz = zt[:, idx], zz[idx]
                if not rect:
                    mt = mt[:, idx]
            if rect:
                u0, u1, v0, v1 = plan.span
                ia_, jb_ = np.divmod(idx, width)
                ia_ += a0
                u0, u1, v0, v1 = u0[ia_], u1[ia_], v0[jb_], v1[jb_]
                pre = plan.prefix
                mt = (pre[u1, v1] - pre[u0, v1] - pre[u1, v0] + pre[u0, v0]).T  # (15 + T, nd)
            rd = np.zeros(idx.size)
            if n_t:
                cnt = mt[0].astype(np.float64)
                d = mt[15:].astype(np.float64) + zz - 2.0 * zt[:n_t]
                d = np.maximum(d, 0.0) * (grid.size / cnt)
                rd += plan.ttw @ np.exp(-plan.hs * d)
            r[idx] = rd
            pending[plan.s].append((a0, idx, mt[:15].T, zt[n_t:].T, zz))  # list.append: thread-safe
        out[plan.s, a0:a0 + k] = r.reshape(k, width)  # each block owns its rows: no race

    def solve(plan: _ScalePlan) -> None:
        """The masked fits of all dirty windows of a scale: one vectorised solve."""
        if pending[plan.s]:
            parts = list(zip(*pending[plan.s]))
            moments = np.concatenate(parts[2])
            raw = masked_fits(moments, np.concatenate(parts[3]), np.concatenate(parts[4]),
                              plan.grid)
            raw[moments[:, 0] < 6] = np.nan  # a quadric needs 6 samples: no guess
            flat = np.concatenate([a0 * width + i for a0, i in zip(parts[0], parts[1])])
            out[plan.s].reshape(-1)[flat] += split_signed(raw) @ plan.tw

    tasks = [(p, a0) for p in reversed(built) for a0 in range(0, na, p.rows)]
    # NumPy and BLAS release the GIL: blocks run on all cores, BLAS itself on one.
    with _blas().limit(limits=1, user_api="blas"):
        workers = min(_workers(), len(tasks))
        if workers > 1:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                list(pool.map(block, tasks))
                list(pool.map(solve, reversed(built)))
        else:
            for task in tasks:
                block(task)
            for plan in built:
                solve(plan)
    reward_out = out[:, :, :nb].sum(axis=0)
    return np.where(valid, reward_out, -np.inf), valid
