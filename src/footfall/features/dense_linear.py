"""Dense scoring of a linear reward: one matrix product per scale over a whole board.

Where the lattice, the patch samples and the map cells line up (heading 0 or
pi, spacing and template resolution whole multiples of the map resolution:
the usual case for boards) the patches are gathered from the map by long
contiguous copies, and every feature family that is linear in the patch
heights (:meth:`FeatureFamily.dense <footfall.features.family.FeatureFamily.dense>`)
is scored from one matrix product per scale, in blocks of lattice rows, on
all cores. The map's heights are taken relative to one reference and 0
where there is no data, so a window's products need no per-window copy:

    sum over the samples with data of w (h - h0) = w . h - h0 sum w,
    sum of (h - h0)^2 = sum h^2 - 2 h0 sum h + n h0^2,

with ``h0`` the lattice point's own height, ``sum w`` the column's sum (all
of it for a complete window, a prefix-sum look-up where the map's border
cuts the window, the data mask's product where a hole lies in it) and the
window sums of h and h^2 from running sums of the map
(:mod:`footfall.features.window_sums`). Windows with no-data samples are
scored by the families' masked definitions, collected over all blocks and
finished once per scale; windows whose coverage is too low are not valid
footholds. Families without a dense form, and headings or spacings that do
not line up, are scored by the generic form
(:func:`footfall.features.dense.dense_values`'s interpolated patches). Both
give the same numbers as the per-candidate definitions.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
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
from footfall.features.window_sums import window_sums

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


@dataclass(frozen=True, eq=False)
class _Board:
    """The map padded and laid out in polyphase order, with the lattice's geometry [cells].

    Heights are relative to one reference height and 0 where there is no data,
    so that a window's sums over its samples with data are plain sums.
    """

    poly: np.ndarray  # (step, step, big_x, big_y): poly[rx, ry, m, n] = padded[step m + rx, step n + ry]
    data: np.ndarray | None  # the same layout, 1 where the map has data; None: no holes
    heights: np.ndarray  # (padded shape) float64 heights [m], 0 where no data
    holes: np.ndarray | None  # (padded shape) float64: 1 at the map's no-data cells; None: none
    h0: np.ndarray  # (na, width) heights of the lattice points; NaN: none
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
    heights = np.zeros((big_x * step, big_y * step))
    nodata = np.isnan(h)
    np.subtract(h, ref, out=heights[mx:mx + nx, my:my + ny])
    heights[mx:mx + nx, my:my + ny][nodata] = 0.0

    def polyphase(a: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(a.astype(dtype, copy=False)
                                    .reshape(big_x, step, big_y, step).transpose(1, 3, 0, 2))

    width = big_y
    h0 = np.full((na, width), np.nan)
    h0[:, :nb] = np.where(has_data, h0_map - ref, np.nan)
    holes = data = None
    if nodata.any():
        holes = np.zeros(heights.shape)
        holes[mx:mx + nx, my:my + ny] = nodata
        inside = np.zeros(heights.shape, dtype=bool)
        inside[mx:mx + nx, my:my + ny] = ~nodata
        data = polyphase(inside)
    return _Board(polyphase(heights), data, heights, holes, h0, (nx, ny), (mx, my), step, tap,
                  na, nb, width, has_data)


@dataclass(frozen=True, eq=False)
class _Windows:
    """The patch windows of one scale at every lattice point: how much of each holds data."""

    count: np.ndarray  # (na, nb) samples with data
    sums: tuple[np.ndarray, np.ndarray]  # (na, width) sums of the heights and their squares [m, m^2]
    span_u: tuple[np.ndarray, np.ndarray]  # (na,) first and last sample on the map along u
    span_v: tuple[np.ndarray, np.ndarray]  # (nb,) the same along v
    holed: np.ndarray | None  # (na * width,) bool: the window holds holes of the map


def _windows(board: _Board, grid: PatchGrid) -> _Windows:
    """Samples with data in each window of a scale (the part on the map less the holes in it),
    and the sums of their heights and squared heights."""
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
    pad = ((0, 0), (0, board.width - board.nb))
    sums = tuple(np.pad(q, pad) for q in window_sums(board.heights, tap, x0, y0, nu, nv))
    holed = None
    if board.holes is not None:
        in_holes = np.rint(window_sums(board.holes, tap, x0, y0, nu, nv)[0]).astype(np.int64)
        count = count - in_holes
        holed = np.pad(in_holes > 0, pad).ravel()
    return _Windows(count, sums, span_u, span_v, holed)


@dataclass(frozen=True, eq=False)
class _ScalePlan:
    """Everything a block of scale s needs, in the map's orientation and buffer order."""

    s: int
    grid: PatchGrid
    rows: int  # lattice rows per block
    groups: tuple  # per phase group: (first buffer row, view (nq, np, na * width) of its samples)
    mask_groups: tuple | None  # the same views of the data mask; None: the map has no holes
    terms: tuple[DenseTerms, ...]  # the families' dense terms on this scale
    z_t: np.ndarray  # (sum b_k, taps) the families' height columns^T, buffer order, dtype
    z_sum: np.ndarray  # (sum b_k,) their sums over all samples, dtype
    all_t: np.ndarray  # (1 + sum e_k + sum b_k, taps) [ones | mask columns | height columns]^T
    z_rows: tuple[slice, ...]  # per family: its rows of z_t
    m_rows: tuple[slice, ...]  # per family: its rows of all_t
    dirty: np.ndarray  # (na * width,) bool: valid, but the window has no-data samples
    holed: np.ndarray | None  # (na * width,) bool: the window holds holes of the map
    prefix: np.ndarray  # (nu + 1, nv + 1, rows of all_t) 2-D prefix sums of all_t, map order
    sums: tuple[np.ndarray, np.ndarray]  # (na * width,) sums of heights and squares [m, m^2]
    span: tuple  # window samples on the map: u from, u to (na,); v from, v to (width,)
    pending: list = field(default_factory=list)  # masked sums of dirty windows, from every block


def _row_slices(widths: list[int], start: int = 0) -> tuple[slice, ...]:
    bounds = np.cumsum([start] + widths)
    return tuple(slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:]))


def _phase_groups(board: _Board, grid: PatchGrid, poly: np.ndarray) -> tuple[tuple, np.ndarray]:
    """Strided views of a polyphase map, one per group of samples sharing a phase.

    Sample (q, p) of a group for lattice point (a, b) is phase element
    (m0 + a + tq q) * width + n0 + b + tq p: a run over (a, b). Returns the
    groups and the permutation of the patch samples into buffer order.
    """
    step, tap, width = board.step, board.tap, board.width
    mx, my = board.margin
    hu, hv = grid.half_counts
    nu, nv = grid.shape
    item = poly.itemsize
    tq = tap // np.gcd(step, tap)  # phase rows (columns) between neighbouring samples of a group
    period = step // np.gcd(step, tap)  # samples u, u + period, ... share a phase
    groups, perm, row = [], [], 0
    for su in range(min(period, nu)):
        for sv in range(min(period, nv)):
            us, vs = np.arange(su, nu, period), np.arange(sv, nv, period)
            ex, ey = mx - hu * tap + tap * su, my - hv * tap + tap * sv
            phase = poly[ex % step, ey % step].reshape(-1)
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
    groups, perm = _phase_groups(board, grid, board.poly)
    mask_groups = None if board.data is None else _phase_groups(board, grid, board.data)[0]
    z_cols = _orient(np.concatenate([t.z_columns for t in terms] + [np.zeros((grid.size, 0))],
                                    axis=1), grid, flip_u, flip_v)
    all_cols = np.concatenate([_orient(np.concatenate(
        [np.ones((grid.size, 1))] + [t.m_columns for t in terms], axis=1), grid, flip_u, flip_v),
        z_cols], axis=1)
    # Windows whose only no-data samples are off the map keep a rectangle
    # of samples: their column sums are four look-ups in a 2-D prefix sum.
    prefix = np.zeros((nu + 1, nv + 1, all_cols.shape[1]))
    prefix[1:, 1:] = all_cols.reshape(nu, nv, -1).cumsum(0).cumsum(1)
    vlo = np.pad(windows.span_v[0], (0, width - nb))
    vhi = np.pad(windows.span_v[1], (0, width - nb))
    return _ScalePlan(
        s=s, grid=grid, rows=max(1, _BLOCK_BYTES // (dtype.itemsize * width * grid.size)),
        groups=groups, mask_groups=mask_groups, terms=tuple(terms),
        z_t=np.ascontiguousarray(z_cols[perm].T, dtype=dtype),
        z_sum=z_cols.sum(axis=0).astype(dtype),
        all_t=np.ascontiguousarray(all_cols[perm].T, dtype=dtype),
        z_rows=_row_slices([t.z_columns.shape[1] for t in terms]),
        m_rows=_row_slices([t.m_columns.shape[1] for t in terms], start=1),
        dirty=np.pad(valid & (windows.count < grid.size), ((0, 0), (0, width - nb))).ravel(),
        holed=windows.holed, prefix=prefix,
        sums=tuple(q.ravel() for q in windows.sums),
        span=(windows.span_u[0], windows.span_u[1] + 1, vlo, vhi + 1))


def _gather(groups: tuple, size: int, width: int, a0: int, k: int, buf: np.ndarray) -> np.ndarray:
    """The samples (taps, k * width) of the windows of lattice rows a0 .. a0 + k."""
    n = k * width
    c = buf[:size * n].reshape(size, n)
    for row, src in groups:
        part = src[:, :, a0 * width:a0 * width + n]
        taps = part.shape[0] * part.shape[1]
        np.copyto(c[row:row + taps].reshape(part.shape), part)
    return c


def _column_sums(plan: _ScalePlan, board: _Board, c_rows: tuple[int, int], idx: np.ndarray,
                 buf: np.ndarray) -> np.ndarray:
    """Sums (rows of all_t, nd) of the columns over the samples with data of windows ``idx``
    (flat indices) of the block of lattice rows ``c_rows``.

    Four look-ups in a prefix sum where only the map's edge cuts a window (a
    rectangle of samples is left); the data mask times the columns where a
    hole of the map lies in one.
    """
    a0, k = c_rows
    width = board.width
    if plan.holed is None or not plan.holed[a0 * width + idx].any():
        u0, u1, v0, v1 = plan.span
        ia, jb = np.divmod(idx, width)
        ia += a0
        u0, u1, v0, v1 = u0[ia], u1[ia], v0[jb], v1[jb]
        pre = plan.prefix
        return (pre[u1, v1] - pre[u0, v1] - pre[u1, v0] + pre[u0, v0]).T
    m = _gather(plan.mask_groups, plan.grid.size, width, a0, k, buf)
    return (plan.all_t @ np.take(m, idx, axis=1)).astype(np.float64)


def _score_block(plan: _ScalePlan, a0: int, board: _Board, out: np.ndarray, buf: np.ndarray
                 ) -> None:
    """Score the complete windows of lattice rows a0 ..; keep the sums of the others."""
    width = board.width
    k = min(plan.rows, board.na - a0)
    here = slice(a0 * width, (a0 + k) * width)  # the block's points in flat lattice order
    c = _gather(plan.groups, plan.grid.size, width, a0, k, buf)
    g = plan.z_t @ c  # (sum b_k, n): the columns times the heights, relative to the reference
    h0 = board.h0[a0:a0 + k].reshape(-1)
    s1, s2 = (q[here] for q in plan.sums)
    idx = np.flatnonzero(plan.dirty[here])
    # Complete windows: every sample holds data, so each column sums to its full sum.
    zt = g - np.outer(plan.z_sum, h0.astype(g.dtype))
    size = plan.grid.size
    zz = s2 - 2.0 * h0 * s1 + size * h0 * h0
    r = np.zeros(k * width)
    for terms, rows in zip(plan.terms, plan.z_rows):
        terms.add_full(zt[rows], zz, s1 - size * h0, r)
    r[idx] = 0.0  # the masked definitions add theirs at the end
    if idx.size:
        sums = _column_sums(plan, board, (a0, k), idx, buf)
        n_m = plan.all_t.shape[0] - plan.z_t.shape[0]
        h0d = h0[idx]
        zt_d = g[:, idx].astype(np.float64) - h0d * sums[n_m:]
        count = sums[0]
        zz_d = s2[idx] - 2.0 * h0d * s1[idx] + count * h0d * h0d
        plan.pending.append((a0 * width + idx, zt_d, sums[:n_m], zz_d))  # list.append: thread-safe
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
    local = threading.local()
    workers = usable_cores()
    # NumPy, BLAS and the compiled window sums release the GIL: the scales' window sums, then
    # the blocks, run on all cores, BLAS itself on one.
    with _blas().limit(limits=1, user_api="blas"), (
            ThreadPoolExecutor(max_workers=workers) if workers > 1 else nullcontext()) as pool:
        each = map if pool is None else pool.map
        windows = list(each(lambda grid: _windows(board, grid), grids))
        valid = board.has_data.copy()
        for grid, w in zip(grids, windows):  # the coverage rule of foothold_patches, in its arithmetic
            valid &= 1.0 - (grid.size - w.count) / grid.size >= config.min_coverage
        plans = [_scale_plan(board, s, grid, windows[s], valid, terms[s], flip_u, flip_v, dtype)
                 for s, grid in enumerate(grids)]
        out = np.zeros((len(grids), board.na, board.width))
        size = max(p.rows * board.width * p.grid.size for p in plans)

        def block(task: tuple[_ScalePlan, int]) -> None:
            if getattr(local, "buf", None) is None:  # one buffer per thread, reused by every block
                local.buf = np.empty(size, dtype=dtype)
            _score_block(task[0], task[1], board, out, local.buf)

        list(each(block, [(p, a0) for p in reversed(plans) for a0 in range(0, board.na, p.rows)]))
        list(each(lambda p: _finish_masked(p, out), reversed(plans)))
    reward_out = out[:, :, :board.nb].sum(axis=0)
    return np.where(valid, reward_out, -np.inf), valid
