"""The expert's ray terms, compiled: every ray sample of a foothold read once, no temporaries.

The terrain terms of :func:`footfall.expert.terms.terrain_terms` reduce the
ball-centre surface sampled along K ray directions at J distances around each
foothold -- the steepest secant in a ring, the rise in a disc, the fall below
a cone -- and count the map's no-data cells along the same rays. Written as
whole-array NumPy that is a dozen (n, K, J) temporaries a call; here it is one
pass over the samples with the same arithmetic in the same order, so the
results are the same bits (``tests/test_expert_rays.py`` holds it to the
NumPy rules of :mod:`footfall.experiments.bench.expert`). Positions and
heights in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np

from footfall.core.bilinear import surface_point
from footfall.core.sphere_surface import SphereSurface

if TYPE_CHECKING:  # the settings live with the expert
    from footfall.expert.synthetic import ExpertConfig


@dataclass(frozen=True, eq=False)
class RaySamples:
    """Where the terrain terms sample each ray, and which samples each term reads."""

    s: np.ndarray  # (J,) [m] distances of the samples along a ray, increasing
    near: np.ndarray  # (J,) bool: the slip ring, slip_distance / 2 to slip_distance
    jp: int  # the sample nearest pinch_distance
    in_trap: np.ndarray  # (J,) bool: within trap_radius
    in_edge: np.ndarray  # (J,) bool: within edge_radius (E samples)
    edge_offset: np.ndarray  # (E,) [m] the walkable cone's fall at those samples
    edge_weight: np.ndarray  # (E,) [-] how likely a slip that far is, 1 - s / edge_radius
    unknown: np.ndarray  # (U,) [m] the distances within unknown_radius

    @classmethod
    def of(cls, cfg: ExpertConfig) -> RaySamples:
        """The samples of ``cfg``: every ``ray_step`` out to the slip and pinch distances, then
        every ``far_step`` out to the longest reach of any term."""
        longest = max(cfg.slip_distance, cfg.pinch_distance, cfg.trap_radius, cfg.edge_radius,
                      cfg.unknown_radius, cfg.riser_distance)
        near_reach = max(cfg.slip_distance, cfg.pinch_distance)
        s_near = cfg.ray_step * np.arange(1, int(math.floor(near_reach / cfg.ray_step + 1e-9)) + 1)
        s_far = np.arange(s_near[-1] + cfg.far_step, longest + cfg.far_step - 1e-12, cfg.far_step)
        s = np.concatenate([s_near, s_far])
        near = (s >= 0.5 * cfg.slip_distance - 1e-12) & (s <= cfg.slip_distance + 1e-12)
        if not near.any():
            near = s == s[0]
        in_edge = s < cfg.edge_radius
        return cls(s=s, near=near, jp=int(np.argmin(np.abs(s - cfg.pinch_distance))),
                   in_trap=s <= cfg.trap_radius + 1e-12, in_edge=in_edge,
                   edge_offset=cfg.walkable_slope * s[in_edge],
                   edge_weight=1.0 - s[in_edge] / cfg.edge_radius,
                   unknown=np.ascontiguousarray(s[s <= cfg.unknown_radius + 1e-12]))


def ray_terms(ball: SphereSurface | None, xy: np.ndarray, seat: np.ndarray, dirs: np.ndarray,
              rays: RaySamples) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`ray_reductions` of the surface ``ball`` (``None``: no surface anywhere, every
    rise 0) around ``xy`` (n, 2) [m] seated at ``seat`` (n,) [m]: hold, pinch, trap, drop."""
    if ball is None:  # a window whose origin is NaN: every sample falls outside it
        filled, known, origin, res, complete = (np.zeros((2, 2)), np.zeros((2, 2)),
                                                (np.nan, np.nan), 1.0, False)
    else:
        filled, known, origin, res, complete = (ball.filled, ball.known, ball.origin,
                                                ball.resolution, ball.complete)
    return ray_reductions(filled, known, float(origin[0]), float(origin[1]), res, complete,
                          np.ascontiguousarray(xy, dtype=np.float64),
                          np.ascontiguousarray(seat, dtype=np.float64),
                          np.ascontiguousarray(dirs, dtype=np.float64), rays.s, rays.near,
                          rays.jp, rays.in_trap, rays.edge_offset, rays.edge_weight,
                          rays.in_edge)


@numba.njit(cache=True, nogil=True)
def ray_reductions(filled, known, ox, oy, res, complete, xy, seat, d, s, near, jp, in_trap,
                   edge_offset, edge_weight, in_edge):  # pragma: no cover - compiled
    """The ray reductions of the ball-centre surface around footholds ``xy`` (n, 2) [m].

    The surface is a window (``filled`` heights [m], 0 where unknown; ``known`` 1.0 / 0.0;
    cell (0, 0) at (ox, oy) [m], ``res`` [m/cell]); ``seat`` (n,) [m] the seated ball centres;
    ``d`` (K, 2) unit ray directions with d[k + K/2] = -d[k]; ``s`` (J,) [m] the distances of
    the samples. A sample without a surface counts as a rise of 0. With rise = surface - seat
    and secant = rise / s, returns four (n,) arrays:

    * hold: min over rays of the max secant over the samples where ``near`` [-];
    * pinch: max over opposite ray pairs of the smaller secant at sample ``jp`` [-];
    * trap: min over rays of the max rise where ``in_trap`` [m];
    * drop: max over rays and the samples where ``in_edge`` (E of them, in order) of
      (-rise - edge_offset[e]) * edge_weight[e] [m].
    """
    n = xy.shape[0]
    k_rays = d.shape[0]
    half = k_rays // 2
    hold = np.empty(n)
    pinch = np.empty(n)
    trap = np.empty(n)
    drop = np.empty(n)
    tilt = np.empty(k_rays)
    for i in range(n):
        least_hold = np.inf
        least_trap = np.inf
        worst_drop = -np.inf
        for k in range(k_rays):
            most_secant = -np.inf
            most_rise = -np.inf
            e = 0
            for j in range(s.shape[0]):
                h = surface_point(filled, known, ox, oy, res, complete,
                                   xy[i, 0] + s[j] * d[k, 0], xy[i, 1] + s[j] * d[k, 1])
                rise = h - seat[i]
                if np.isnan(rise):
                    rise = 0.0
                secant = rise / s[j]
                if near[j] and secant > most_secant:
                    most_secant = secant
                if j == jp:
                    tilt[k] = secant
                if in_trap[j] and rise > most_rise:
                    most_rise = rise
                if in_edge[j]:
                    fall = (-rise - edge_offset[e]) * edge_weight[e]
                    if fall > worst_drop:
                        worst_drop = fall
                    e += 1
            if most_secant < least_hold:
                least_hold = most_secant
            if most_rise < least_trap:
                least_trap = most_rise
        best_pair = -np.inf
        for k in range(half):
            pair = min(tilt[k], tilt[k + half])
            if pair > best_pair:
                best_pair = pair
        hold[i] = least_hold
        pinch[i] = best_pair
        trap[i] = least_trap
        drop[i] = worst_drop
    return hold, pinch, trap, drop


@numba.njit(cache=True, nogil=True)
def no_data_share(h, ox, oy, res, xy, d, s):  # pragma: no cover - compiled
    """Share (n,) [-] of the points without map data -- each foothold ``xy`` (n, 2) [m] itself and
    xy + s[j] d[k] for the distances ``s`` (J,) [m] along the directions ``d`` (K, 2) -- where a
    point has no data when the cell containing it is off the map ``h`` (nx, ny) [m] (cell
    (0, 0) at (ox, oy) [m], ``res`` [m/cell]) or NaN."""
    nx, ny = h.shape
    n = xy.shape[0]
    out = np.empty(n)
    total = 1 + d.shape[0] * s.shape[0]
    for i in range(n):
        count = 0
        for m in range(total):
            if m == 0:
                px = xy[i, 0]
                py = xy[i, 1]
            else:
                k = (m - 1) // s.shape[0]
                j = (m - 1) % s.shape[0]
                px = xy[i, 0] + s[j] * d[k, 0]
                py = xy[i, 1] + s[j] * d[k, 1]
            ci = np.floor((px - ox) / res + 0.5)
            cj = np.floor((py - oy) / res + 0.5)
            if not (ci >= 0 and ci < nx and cj >= 0 and cj < ny) or np.isnan(h[int(ci), int(cj)]):
                count += 1
        out[i] = count / total
    return out
