"""Dense scoring of a linear reward: one matrix product per scale over a whole board.

Where the lattice, the patch samples and the map cells line up (heading 0 or
pi, spacing and template resolution whole multiples of the map resolution:
the usual case for boards) the patches are gathered from the map by long
contiguous copies, and every feature family that is linear in the patch
heights (:meth:`FeatureFamily.dense <footfall.features.family.FeatureFamily.dense>`)
is scored by one matrix product per scale,

    [family columns ... | 1]^T @ [C]      (e.g. sum (t - c)^2 = t.t + c.c - 2 c.t),

in blocks of lattice rows, on all cores. Windows with no-data samples (holes,
or off the map at its border) are scored from their masked sums, collected
over all blocks and finished once per scale; windows whose coverage is too
low are not valid footholds. Families without a dense form, and headings or
spacings that do not line up, are scored by the generic form
(:func:`footfall.features.dense.dense_values`'s interpolated patches). Both
give the same numbers as the per-candidate definitions.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from threadpoolctl import ThreadpoolController

from footfall.core.compute import usable_cores
from footfall.core.heightmap import HeightMap, PatchGrid
from footfall.features.config import FeatureConfig
from footfall.features.dense import (
    ScoreGrid,
    dense_general,
    lattice_points,
    linear_values,
    whole_ratio,
)
from footfall.features.family import Candidates, DenseTerms, FeatureFamily

_BLOCK_BYTES = 8 << 20  # patches per block of the strided path: two blocks stay in L3


@lru_cache(maxsize=1)
def _blas() -> ThreadpoolController:
    """The BLAS libraries, inspected once: limiting their threads per call is then cheap."""
    return ThreadpoolController()


def dense_linear(hmap: HeightMap, parts: Sequence[tuple[FeatureFamily, np.ndarray]],
                 config: FeatureConfig, *, spacing: float = 0.005, yaw: float = 0.0,
                 mirror: bool = False, dtype: type = np.float32, fast: bool = True) -> ScoreGrid:
    """A linear terrain reward -- ``family.compute @ weights`` summed over ``parts`` -- at every
    lattice point of the map (every ``spacing`` metres).

    Parameters
    ----------
    parts : sequence of (FeatureFamily, array of shape (k_f,))
        Families that read only the terrain, with their weights.
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
    pts, xs, ys = lattice_points(hmap, spacing)
    step = whole_ratio(spacing, hmap.resolution)
    tap = whole_ratio(config.template_resolution, hmap.resolution)
    quarter = np.round(yaw / (np.pi / 2))
    flip = None
    if abs(yaw - quarter * np.pi / 2) < 1e-12 and int(quarter) % 2 == 0:
        flip = int(quarter) % 4 == 2  # heading pi: the patch is the map turned half a turn
    if not (fast and step is not None and tap is not None and flip is not None):
        r, valid = dense_general(hmap, _valid_sum(parts), config, pts, yaw, mirror)
        return ScoreGrid(xs, ys, r.reshape(xs.size, ys.size), valid.reshape(xs.size, ys.size))
    dtype = np.dtype(dtype)
    terms, rest = _dense_terms(parts, len(config.scales), dtype)
    r, valid = _dense_aligned(hmap, config, terms, step, tap, flip, mirror, dtype)
    if rest:  # families without a dense form: their exact values at the valid points
        extra, _ = dense_general(hmap, _valid_sum(rest), config, pts[valid.ravel()], yaw, mirror)
        r[valid] += extra
    return ScoreGrid(xs, ys, r, valid)


def _valid_sum(parts: Sequence[tuple[FeatureFamily, np.ndarray]]
               ) -> Callable[[Candidates], np.ndarray]:
    """The linear sum of ``parts`` where a foothold is valid, -inf elsewhere."""
    return lambda c: np.where(c.patches.valid, linear_values(c, parts), -np.inf)


def _dense_terms(parts: Sequence[tuple[FeatureFamily, np.ndarray]], n_scales: int,
                 dtype: np.dtype
                 ) -> tuple[list[list[DenseTerms]], list[tuple[FeatureFamily, np.ndarray]]]:
    """Per scale, the dense terms of the families; the families without them."""
    per_scale: list[list[DenseTerms]] = [[] for _ in range(n_scales)]
    rest = []
    for family, w in parts:
        terms = [family.dense(s, w, dtype) for s in range(n_scales)]
        if any(t is None for t in terms):
            rest.append((family, w))
            continue
        for s, t in enumerate(terms):
            per_scale[s].append(t)
    return per_scale, rest


# ----------------------------------------------------------------- the aligned path
def _orient(w: np.ndarray, grid: PatchGrid, flip_u: bool, flip_v: bool) -> np.ndarray:
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


@dataclass(frozen=True, eq=False)
class _Board:
    """The map padded and laid out in polyphase order, with the lattice's geometry [cells]."""

    poly: np.ndarray  # (step, step, big_x, big_y): poly[rx, ry, m, n] = padded[step m + rx, step n + ry]
    h0: np.ndarray  # (na, width) heights of the lattice points, relative to a reference; NaN: none
    holes: np.ndarray | None  # (padded shape) bool: no-data cells of the map inside the padding
    shape: tuple[int, int]  # (nx, ny) cells of the map
    margin: tuple[int, int]  # (mx, my) cells of padding on each side
    step: int  # lattice spacing [cells]
    tap: int  # patch sample spacing [cells]
    na: int  # lattice points along x
    nb: int  # lattice points along y
    width: int  # points per lattice row in a block: nb real, the rest spare
    has_data: np.ndarray  # (na, nb) bool: the map has data at the lattice point


def _board(hmap: HeightMap, grids: tuple[PatchGrid, ...], step: int, tap: int,
           dtype: np.dtype) -> _Board:
    """The padded map in polyphase order: one patch sample of a row of lattice points is then one
    contiguous run of values, so that gathering a block of patches is a few long copies.
    Heights relative to a reference keep their digits in float32."""
    h = hmap.heights
    nx, ny = h.shape
    na, nb = -(-nx // step), -(-ny // step)
    mx = max(g.half_counts[0] for g in grids) * tap
    my = max(g.half_counts[1] for g in grids) * tap
    h0_map = h[::step, ::step]  # (na, nb) view: the lattice points' own heights
    has_data = ~np.isnan(h0_map)
    ref = float(h0_map[has_data].mean()) if has_data.any() else 0.0
    big_x, big_y = -(-(nx + 2 * mx) // step) + 1, -(-(ny + 2 * my) // step)
    padded = np.full((big_x * step, big_y * step), np.nan, dtype=dtype)
    np.subtract(h, ref, out=padded[mx:mx + nx, my:my + ny])
    poly = np.ascontiguousarray(padded.reshape(big_x, step, big_y, step).transpose(1, 3, 0, 2))
    width = big_y
    h0 = np.full((na, width), np.nan, dtype=dtype)
    h0[:, :nb] = padded[mx:mx + nx:step, my:my + ny:step]
    holes = None
    if np.isnan(h).any():
        holes = np.zeros(padded.shape, dtype=bool)
        holes[mx:mx + nx, my:my + ny] = np.isnan(h)
    return _Board(poly, h0, holes, (nx, ny), (mx, my), step, tap, na, nb, width, has_data)


@dataclass(frozen=True, eq=False)
class _Windows:
    """The patch windows of one scale at every lattice point: how much of each holds data."""

    count: np.ndarray  # (na, nb) samples with data
    span_u: tuple[np.ndarray, np.ndarray]  # (na,) first and last sample on the map along u
    span_v: tuple[np.ndarray, np.ndarray]  # (nb,) the same along v
    holed: np.ndarray | None  # (na * width,) bool: the window holds holes of the map


def _windows(board: _Board, grid: PatchGrid) -> _Windows:
    """Samples with data in each window of a scale: the part on the map less the holes in it."""
    (nx, ny), (mx, my), tap = board.shape, board.margin, board.tap
    hu, hv = grid.half_counts
    nu, nv = grid.shape
    x0 = mx - hu * tap + board.step * np.arange(board.na)  # padded index of each window's first sample
    y0 = my - hv * tap + board.step * np.arange(board.nb)
    xs = x0[:, None] + tap * np.arange(nu) - mx
    ys = y0[:, None] + tap * np.arange(nv) - my
    on_x, on_y = (xs >= 0) & (xs < nx), (ys >= 0) & (ys < ny)
    count = on_x.sum(1)[:, None] * on_y.sum(1)[None, :]
    span_u = (on_x.argmax(1), nu - 1 - on_x[:, ::-1].argmax(1))
    span_v = (on_y.argmax(1), nv - 1 - on_y[:, ::-1].argmax(1))
    holed = None
    if board.holes is not None:
        in_holes = _window_sums(board.holes, x0, y0, nu, nv, tap)
        count = count - in_holes
        holed = np.pad(in_holes > 0, ((0, 0), (0, board.width - board.nb))).ravel()
    return _Windows(count, span_u, span_v, holed)


@dataclass(frozen=True, eq=False)
class _ScalePlan:
    """Everything a block of scale s needs, in the map's orientation and buffer order."""

    s: int
    grid: PatchGrid
    rows: int  # lattice rows per block
    groups: tuple  # per phase group: (first buffer row, view (nq, np, na * width) of its samples)
    terms: tuple[DenseTerms, ...]  # the families' dense terms on this scale
    kern_t: np.ndarray  # (sum a_k + 1, taps) [family columns | ones]^T, dtype
    masked_z: np.ndarray  # (sum b_k, taps) the families' masked height columns^T, dtype
    masked_m: np.ndarray  # (1 + sum e_k, taps) [ones | the families' mask columns]^T, dtype
    full_rows: tuple[slice, ...]  # per family: its rows of kern_t
    z_rows: tuple[slice, ...]  # per family: its rows of masked_z
    m_rows: tuple[slice, ...]  # per family: its rows of masked_m
    dirty: np.ndarray  # (na * width,) bool: valid, but the window has no-data samples
    holed: np.ndarray | None  # (na * width,) bool: the window holds holes of the map
    prefix: np.ndarray  # (nu + 1, nv + 1, 1 + sum e_k) 2-D prefix sums of masked_m, map order
    span: tuple  # window samples on the map: u from, u to (na,); v from, v to (width,)
    pending: list = field(default_factory=list)  # masked sums of dirty windows, from every block


def _row_slices(widths: list[int], start: int = 0) -> tuple[slice, ...]:
    bounds = np.cumsum([start] + widths)
    return tuple(slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:]))


def _phase_groups(board: _Board, grid: PatchGrid) -> tuple[tuple, np.ndarray]:
    """Strided views of the polyphase map, one per group of samples sharing a phase.

    Sample (q, p) of a group for lattice point (a, b) is phase element
    (m0 + a + tq q) * width + n0 + b + tq p: a run over (a, b). Returns the
    groups and the permutation of the patch samples into buffer order.
    """
    step, tap, width = board.step, board.tap, board.width
    mx, my = board.margin
    hu, hv = grid.half_counts
    nu, nv = grid.shape
    item = board.poly.itemsize
    tq = tap // np.gcd(step, tap)  # phase rows (columns) between neighbouring samples of a group
    period = step // np.gcd(step, tap)  # samples u, u + period, ... share a phase
    groups, perm, row = [], [], 0
    for su in range(min(period, nu)):
        for sv in range(min(period, nv)):
            us, vs = np.arange(su, nu, period), np.arange(sv, nv, period)
            ex, ey = mx - hu * tap + tap * su, my - hv * tap + tap * sv
            phase = board.poly[ex % step, ey % step].reshape(-1)
            start = (ex // step) * width + ey // step
            shape = (us.size, vs.size, board.na * width)
            strides = (tq * width * item, tq * item, item)
            if start + sum((n - 1) * d for n, d in zip(shape, strides)) // item >= phase.size:
                raise AssertionError("patch gather would read past the padded map")
            groups.append((row, np.lib.stride_tricks.as_strided(
                phase[start:], shape=shape, strides=strides, writeable=False)))
            perm.append((us[:, None] * nv + vs[None, :]).ravel())
            row += us.size * vs.size
    return tuple(groups), np.concatenate(perm)


def _scale_plan(board: _Board, s: int, grid: PatchGrid, windows: _Windows, valid: np.ndarray,
                terms: list[DenseTerms], flip_u: bool, flip_v: bool, dtype: np.dtype
                ) -> _ScalePlan:
    """The columns of every family on scale s, oriented to the map and in buffer order."""
    nu, nv = grid.shape
    width, nb = board.width, board.nb
    groups, perm = _phase_groups(board, grid)
    ones = np.ones((grid.size, 1))
    kern = _orient(np.concatenate([t.full_columns for t in terms] + [ones], axis=1),
                   grid, flip_u, flip_v)
    masked_z = _orient(np.concatenate([t.masked_z for t in terms] + [np.zeros((grid.size, 0))],
                                      axis=1), grid, flip_u, flip_v)
    masked_m = _orient(np.concatenate([ones] + [t.masked_m for t in terms], axis=1),
                       grid, flip_u, flip_v)
    # Windows whose only no-data samples are off the map keep a rectangle
    # of samples: their masked sums are four look-ups in a 2-D prefix sum.
    prefix = np.zeros((nu + 1, nv + 1, masked_m.shape[1]))
    prefix[1:, 1:] = masked_m.reshape(nu, nv, -1).cumsum(0).cumsum(1)
    vlo = np.pad(windows.span_v[0], (0, width - nb))
    vhi = np.pad(windows.span_v[1], (0, width - nb))
    return _ScalePlan(
        s=s, grid=grid, rows=max(1, _BLOCK_BYTES // (dtype.itemsize * width * grid.size)),
        groups=groups, terms=tuple(terms),
        kern_t=np.ascontiguousarray(kern[perm].T, dtype=dtype),
        masked_z=np.ascontiguousarray(masked_z[perm].T, dtype=dtype),
        masked_m=np.ascontiguousarray(masked_m[perm].T, dtype=dtype),
        full_rows=_row_slices([t.full_columns.shape[1] for t in terms]),
        z_rows=_row_slices([t.masked_z.shape[1] for t in terms]),
        m_rows=_row_slices([t.masked_m.shape[1] for t in terms], start=1),
        dirty=np.pad(valid & (windows.count < grid.size), ((0, 0), (0, width - nb))).ravel(),
        holed=windows.holed, prefix=prefix,
        span=(windows.span_u[0], windows.span_u[1] + 1, vlo, vhi + 1))


def _gather(plan: _ScalePlan, board: _Board, a0: int, k: int, buf: np.ndarray) -> np.ndarray:
    """The relative heights (taps, k * width) of the windows of lattice rows a0 .. a0 + k."""
    n = k * board.width
    c = buf[:plan.grid.size * n].reshape(plan.grid.size, n)
    h0b = board.h0[a0:a0 + k].reshape(-1)
    for row, src in plan.groups:
        part = src[:, :, a0 * board.width:a0 * board.width + n]
        taps = part.shape[0] * part.shape[1]
        np.subtract(part, h0b, out=c[row:row + taps].reshape(part.shape))
    return c


def _masked_sums(plan: _ScalePlan, c: np.ndarray, idx: np.ndarray, whole: bool, a0: int,
                 width: int, here: slice) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masked sums (zt, mt, zz) of the windows ``idx`` of a block whose samples lack data.

    Their mask sums are prefix-sum look-ups where only the map's edge cuts
    them (a rectangle of samples is left), mask products where a hole of the
    map lies in them.
    """
    z = c if whole else np.take(c, idx, axis=1)
    nodata = np.isnan(z)
    rect = plan.holed is None or not plan.holed[here][idx].any()
    if not rect:
        mt = plan.masked_m @ np.subtract(1, nodata, dtype=z.dtype)  # (1 + sum e_k, nd)
    np.putmask(z, nodata, 0)
    zt = plan.masked_z @ z  # (sum b_k, nd)
    zz = np.einsum("ij,ij->j", z, z)
    if whole:
        zt, zz = zt[:, idx], zz[idx]
        if not rect:
            mt = mt[:, idx]
    if rect:
        u0, u1, v0, v1 = plan.span
        ia, jb = np.divmod(idx, width)
        ia += a0
        u0, u1, v0, v1 = u0[ia], u1[ia], v0[jb], v1[jb]
        pre = plan.prefix
        mt = (pre[u1, v1] - pre[u0, v1] - pre[u1, v0] + pre[u0, v0]).T  # (1 + sum e_k, nd)
    return zt, mt, zz


def _score_block(plan: _ScalePlan, a0: int, board: _Board, valid_w: np.ndarray, out: np.ndarray,
                 buf: np.ndarray) -> None:
    """Score the complete windows of lattice rows a0 ..; keep the masked sums of the others."""
    width = board.width
    k = min(plan.rows, board.na - a0)
    c = _gather(plan, board, a0, k, buf)
    here = slice(a0 * width, (a0 + k) * width)  # the block's points in flat lattice order
    idx = np.flatnonzero(plan.dirty[here])
    r = np.zeros(k * width)
    # Mostly windows with no-data samples (the map's border): all the block's valid windows
    # go through the masked definitions, in place.
    whole = 2 * idx.size > np.count_nonzero(valid_w[here])
    if whole:
        idx = np.flatnonzero(valid_w[here])
    else:
        g = plan.kern_t @ c  # (sum a_k + 1, n)
        cc = np.einsum("ij,ij->j", c, c)
        for terms, rows in zip(plan.terms, plan.full_rows):
            terms.add_full(g[rows], cc, g[-1], r)
        r[idx] = 0.0  # the masked definitions add theirs at the end
    if idx.size:
        zt, mt, zz = _masked_sums(plan, c, idx, whole, a0, width, here)
        plan.pending.append((a0 * width + idx, zt, mt, zz))  # list.append: thread-safe
    out[plan.s, a0:a0 + k] = r.reshape(k, width)  # each block owns its rows: no race


def _finish_masked(plan: _ScalePlan, out: np.ndarray) -> None:
    """The families' rewards of every dirty window of a scale: one call per family."""
    if not plan.pending:
        return
    flat, zt, mt, zz = (np.concatenate(p, axis=-1) for p in zip(*plan.pending))
    count = mt[0]
    target = out[plan.s].reshape(-1)
    for terms, zr, mr in zip(plan.terms, plan.z_rows, plan.m_rows):
        target[flat] += terms.masked(zt[zr], mt[mr], zz, count)


def _dense_aligned(hmap: HeightMap, config: FeatureConfig, terms: list[list[DenseTerms]],
                   step: int, tap: int, half_turn: bool, mirror: bool, dtype: np.dtype
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Reward and validity (na, nb) of every lattice point where patches are map cells.

    ``step`` and ``tap`` are the lattice spacing and the patch sample spacing
    in cells. Validity (data at the point, coverage of every scale) is known
    up front from counts of the samples with data.
    """
    grids = config.grids
    board = _board(hmap, grids, step, tap, dtype)
    # At heading pi the patch's u and v axes run against the map's x and y.
    flip_u, flip_v = half_turn, half_turn != mirror
    windows = [_windows(board, grid) for grid in grids]
    valid = board.has_data.copy()
    for grid, w in zip(grids, windows):  # the coverage rule of foothold_patches, in its arithmetic
        valid &= 1.0 - (grid.size - w.count) / grid.size >= config.min_coverage
    plans = [_scale_plan(board, s, grid, windows[s], valid, terms[s], flip_u, flip_v, dtype)
             for s, grid in enumerate(grids)]
    out = np.zeros((len(grids), board.na, board.width))
    valid_w = np.pad(valid, ((0, 0), (0, board.width - board.nb))).ravel()
    local = threading.local()
    size = max(p.rows * board.width * p.grid.size for p in plans)

    def block(task: tuple[_ScalePlan, int]) -> None:
        if getattr(local, "buf", None) is None:  # one buffer per thread, reused by every block
            local.buf = np.empty(size, dtype=dtype)
        _score_block(task[0], task[1], board, valid_w, out, local.buf)

    tasks = [(p, a0) for p in reversed(plans) for a0 in range(0, board.na, p.rows)]
    # NumPy and BLAS release the GIL: blocks run on all cores, BLAS itself on one.
    with _blas().limit(limits=1, user_api="blas"):
        workers = min(usable_cores(), len(tasks))
        if workers > 1:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                list(pool.map(block, tasks))
                list(pool.map(lambda p: _finish_masked(p, out), reversed(plans)))
        else:
            for task in tasks:
                block(task)
            for plan in plans:
                _finish_masked(plan, out)
    reward_out = out[:, :, :board.nb].sum(axis=0)
    return np.where(valid, reward_out, -np.inf), valid
