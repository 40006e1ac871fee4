"""Benchmark of the compiled bilinear samplers against the NumPy rules they replace.

:func:`map_reference` and :func:`surface_reference` are the whole-array NumPy
evaluations of a height map's and a sphere surface's sampling rules (footfall's
before the samplers were compiled): the baseline here and the specification the
tests compare the compiled samplers with, bit for bit. ``bench_sampling`` times
both on the work of one decision of the learning curve -- the three patch
scales around every reachable foothold, and the expert's rays around them.
"""

from __future__ import annotations

import os
import platform

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES
from footfall.core.sphere_surface import SphereSurface, sphere_surface
from footfall.core.state import nominal_state
from footfall.experiments.bench.timing import best_time
from footfall.features.candidates import reachable_footholds
from footfall.features.config import FeatureConfig
from footfall.terrain import make_board


def map_reference(hmap: HeightMap, points: np.ndarray) -> np.ndarray:
    """A height map's bilinear heights [m] at points (..., 2) [m], NumPy over whole arrays."""
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


def surface_reference(surface: SphereSurface, points: np.ndarray) -> np.ndarray:
    """A sphere surface's bilinear heights [m] at points (..., 2) [m], NumPy over whole
    arrays."""
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


def bench_sampling(states: int = 8, repeats: int = 3, seed: int = 0) -> dict:
    """Compiled sampling against the NumPy rules on a rocky 0.5 module, per decision.

    At ``states`` robot states (swing legs in turn) every reachable foothold
    (5 mm lattice): its patches on the three scales (the features' work) and
    the walking expert's ball-surface samples along 16 rays of 12 samples
    around each (its terrain terms' work); each timed ``repeats`` times, best
    counts; medians over the states [ms], their ratio, and whether the results
    are equal bit for bit.
    """
    board = make_board([("rocky", 0.5)], seed)
    grids = FeatureConfig().grids
    angles = 2 * np.pi * np.arange(16) / 16
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])
    dist = np.linspace(0.002, 0.05, 12)
    rows: dict[str, list[float]] = {k: [] for k in ("patch_np", "patch_nb", "ray_np", "ray_nb")}
    sizes, equal = [], True
    for i, x in enumerate(np.linspace(0.75, 1.10, states)):
        st = nominal_state(board, (float(x), 0.0), 0.0, LEG_NAMES[i % 4])
        f = reachable_footholds(board, st)
        sizes.append(int(f.shape[0]))
        xy = np.ascontiguousarray(f[:, :2])
        mirror = i % 2 == 1

        def numpy_patches():
            return [map_reference(board, board.sample_points(xy, 0.0, mirror, g)) for g in grids]

        def compiled_patches():
            return [board.patches(xy, 0.0, mirror, g) for g in grids]

        ball = sphere_surface(board, xy.min(axis=0) - 0.06, xy.max(axis=0) + 0.06, 0.01)
        rays = xy[:, None, None, :] + dist[None, None, :, None] * dirs[None, :, None, :]
        equal &= all(np.array_equal(a, b, equal_nan=True)
                     for a, b in zip(numpy_patches(), compiled_patches()))
        equal &= np.array_equal(surface_reference(ball, rays), ball.along_rays(xy, dirs, dist),
                                equal_nan=True)
        rows["patch_np"].append(best_time(numpy_patches, repeats))
        rows["patch_nb"].append(best_time(compiled_patches, repeats))
        rows["ray_np"].append(best_time(lambda: surface_reference(
            ball, xy[:, None, None, :] + dist[None, None, :, None] * dirs[None, :, None, :]),
            repeats))
        rows["ray_nb"].append(best_time(lambda: ball.along_rays(xy, dirs, dist), repeats))
    med = {k: float(np.median(v)) * 1000 for k, v in rows.items()}
    return {"machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
            "states": states, "candidates_median": float(np.median(sizes)), "equal": bool(equal),
            "patches": {"numpy_ms": med["patch_np"], "compiled_ms": med["patch_nb"],
                        "speedup": med["patch_np"] / med["patch_nb"]},
            "rays": {"numpy_ms": med["ray_np"], "compiled_ms": med["ray_nb"],
                     "speedup": med["ray_np"] / med["ray_nb"]}}


def format_sampling(r: dict) -> str:
    """Human-readable lines of :func:`bench_sampling`."""
    lines = [f"{r['candidates_median']:.0f} reachable footholds (median of {r['states']} states); "
             f"compiled equal to NumPy bit for bit: {'yes' if r['equal'] else 'NO'}"]
    for key, label in (("patches", "patches, three scales"),
                       ("rays", "expert's ball surface along 16 x 12 ray samples")):
        lines.append(f"{label}: NumPy {r[key]['numpy_ms']:.1f} ms, compiled "
                     f"{r[key]['compiled_ms']:.1f} ms (x{r[key]['speedup']:.1f})")
    return "\n".join(lines)
