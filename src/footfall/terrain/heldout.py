"""The held-out terrain kinds: six module kinds that no tuning of footfall ever used.

footfall's controller, rewards and expert were tuned on the paper's kinds
(:mod:`footfall.terrain.generators`, :mod:`footfall.terrain.rocky`), mostly on
boards of rocky and steps modules. These kinds are for measuring whether that
carries over to terrain no one tuned on (``footfall benchmark-terrain --suite
held-out``, :mod:`footfall.experiments.terrain_suite`). Each is a
:data:`~footfall.terrain.geometry.Generator` of a different character:

* ``stones`` -- stepping stones: flat-topped, slightly tilted stones standing
  above the ground, with gaps between them;
* ``washboard`` -- a raised bed of ridges across the path with holes through it;
* ``scree`` -- overlapping tilted slabs, like a field of flat rock fragments;
* ``logbarrier`` -- a bar across the path with logs lying diagonally over it;
* ``rolling`` -- smooth rolling ground with a ridge and a gully;
* ``scan`` -- rolling rocks whose map has no-data holes (NaN) where a scanner
  looking from behind and above sees no surface, and a few dropouts: the
  planner must not stand there, and the simulator fills them down to the
  map's lowest height (:func:`footfall.sim.hfield.terrain_surface`).

Their difficulty mappings were fixed by the robot's geometry (step heights of
the same scale as steps and rocky at the same difficulty, gaps of the order of
the foot and the leg's reach) before any run on them, and are not to be
changed to make the suite's numbers better: a change to a held-out kind makes
a new kind, with a new name. Each module starts and ends at z = 0 in x.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.ndimage import gaussian_filter

from footfall.terrain.geometry import (
    MODULE_CELLS,
    MODULE_RESOLUTION,
    MODULE_SIZE,
    cell_centres,
    lerp,
)
from footfall.terrain.occlusion import as_scanned

EDGE = 0.05  # [m] flat approach and exit at both ends of every held-out module
RAMP = 0.03  # [m] over which a raised bed rises from and returns to z = 0


def _window(x: np.ndarray) -> np.ndarray:
    """0 on the flat approach and exit, rising linearly over :data:`RAMP` to 1 inside, (610, 1)."""
    inside = np.minimum(x - EDGE, MODULE_SIZE - EDGE - x)
    return np.clip(inside / RAMP, 0.0, 1.0)


def _inside(x: np.ndarray) -> np.ndarray:
    """True between the flat approach and exit, (610, 1)."""
    return (x >= EDGE) & (x <= MODULE_SIZE - EDGE)


def stones(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Stepping stones: flat-topped discs standing above the ground with gaps; heights in [0, 0.07] m.

    Stones sit on a jittered grid between the flat approach and exit, each a
    disc with a planar top tilted in a random direction; between them the
    ground is at z = 0, so a foot that misses a stone drops the stone's height.

    Difficulty mapping (d in [0, 1]):

    * stone height ``(0.01 + 0.05 d) * U(0.8, 1.2)`` [m]: about 0.01 m at d = 0,
      0.05-0.07 m at d = 1.
    * grid spacing ``0.07 + 0.05 d`` [m] and stone radius ``0.035 - 0.01 d`` [m]:
      gaps of about 0 at d = 0 (stones touch), about 7 cm between stone edges at d = 1.
    * top tilt up to ``0.02 + 0.18 d`` [rad]; grid jitter 15 % of the spacing.
    """
    x, y = cell_centres()
    spacing = lerp(difficulty, 0.07, 0.12)  # [m]
    radius = lerp(difficulty, 0.035, 0.025)  # [m]
    xs = np.arange(EDGE + radius, MODULE_SIZE - EDGE - radius + 1e-9, spacing)
    ys = np.arange(-0.5 * MODULE_SIZE + radius, 0.5 * MODULE_SIZE - radius + 1e-9, spacing)
    cx, cy = (a.ravel() for a in np.meshgrid(xs, ys, indexing="ij"))
    n = cx.size
    cx = cx + rng.uniform(-0.15, 0.15, n) * spacing
    cy = cy + rng.uniform(-0.15, 0.15, n) * spacing
    height = lerp(difficulty, 0.01, 0.06) * rng.uniform(0.8, 1.2, n)  # [m]
    tilt = lerp(difficulty, 0.02, 0.2) * np.sqrt(rng.uniform(0, 1, n))  # [rad]
    heading = rng.uniform(0, 2 * math.pi, n)  # [rad] direction the top falls towards
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):  # a few dozen stones, each vectorised over its cells
        dx, dy = x - cx[k], y - cy[k]
        top = height[k] - math.tan(tilt[k]) * (dx * math.cos(heading[k]) + dy * math.sin(heading[k]))
        z = np.where(dx * dx + dy * dy <= radius * radius, np.maximum(z, top), z)
    return np.clip(z, 0.0, None) * _inside(x)


def washboard(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Ridges across the path on a raised bed, with round holes through it; heights in [0, 0.08] m.

    The bed rises from the approach over 3 cm, carries ridges of a sinusoidal
    profile across the path (their crests slightly yawed), and falls back before
    the exit; round holes go down to the ground (z = 0).

    Difficulty mapping (d in [0, 1]):

    * ridge amplitude (crest to trough) ``0.006 + 0.034 d`` [m]; bed height under
      the troughs ``0.005 + 0.025 d`` [m].
    * ridge wavelength U(0.07, 0.11) m, yaw U(-0.1, 0.1) rad: independent of d.
    * holes ``3 + round(9 d)`` of radius ``(0.01 + 0.015 d) * U(0.8, 1.2)`` [m].
    """
    x, y = cell_centres()
    amplitude = lerp(difficulty, 0.006, 0.04)  # [m]
    base = lerp(difficulty, 0.005, 0.03)  # [m]
    wavelength = rng.uniform(0.07, 0.11)  # [m]
    yaw = rng.uniform(-0.1, 0.1)  # [rad]
    phase = rng.uniform(0, 2 * math.pi)
    along = x + math.tan(yaw) * y
    z = (base + 0.5 * amplitude * (1 - np.cos(2 * math.pi * along / wavelength + phase))) \
        * _window(x)
    n_holes = 3 + int(round(9 * difficulty))
    hx = rng.uniform(EDGE + RAMP, MODULE_SIZE - EDGE - RAMP, n_holes)
    hy = rng.uniform(-0.25, 0.25, n_holes)
    hr = lerp(difficulty, 0.01, 0.025) * rng.uniform(0.8, 1.2, n_holes)  # [m]
    for k in range(n_holes):
        z = np.where((x - hx[k]) ** 2 + (y - hy[k]) ** 2 <= hr[k] ** 2, 0.0, z)
    return z


def scree(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Overlapping tilted slabs, each later one covering the earlier; heights in [0, 0.08] m.

    Rectangular slabs of random size and heading are dropped one after the
    other between the approach and the exit, each covering what lies under its
    footprint with a planar top tilted in a random direction, so the bed is a
    patchwork of tilted faces with edges where one slab overlaps another, and
    bare ground between them.

    Difficulty mapping (d in [0, 1]):

    * slab thickness at its centre ``(0.004 + 0.03 d) * U(0.7, 1.3)`` [m].
    * slab tilt up to ``0.05 + 0.30 d`` [rad] (about 3 to 20 deg).
    * slabs ``30 + round(20 d)`` of 6-14 x 4-9 cm: independent of d otherwise.
    """
    x, y = cell_centres()
    n = 30 + int(round(20 * difficulty))
    cx = rng.uniform(EDGE + 0.03, MODULE_SIZE - EDGE - 0.03, n)
    cy = rng.uniform(-0.28, 0.28, n)
    half_l, half_w = rng.uniform(0.03, 0.07, n), rng.uniform(0.02, 0.045, n)  # [m]
    yaw = rng.uniform(0, math.pi, n)
    thick = lerp(difficulty, 0.004, 0.034) * rng.uniform(0.7, 1.3, n)  # [m]
    tilt = lerp(difficulty, 0.05, 0.35) * np.sqrt(rng.uniform(0, 1, n))  # [rad]
    heading = rng.uniform(0, 2 * math.pi, n)
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):  # a few dozen slabs, each vectorised over the module
        dx, dy = x - cx[k], y - cy[k]
        u = dx * math.cos(yaw[k]) + dy * math.sin(yaw[k])
        v = -dx * math.sin(yaw[k]) + dy * math.cos(yaw[k])
        top = thick[k] - math.tan(tilt[k]) * (dx * math.cos(heading[k])
                                              + dy * math.sin(heading[k]))
        z = np.where((np.abs(u) <= half_l[k]) & (np.abs(v) <= half_w[k]), np.maximum(top, 0.0), z)
    return z * _inside(x)


def logbarrier(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A bar across the path with one or two logs lying diagonally over it; heights in [0, 0.11] m.

    The bar has a flat top; each log is a half cylinder lying at a steep angle
    to the path and riding over the bar where it crosses it, so the bar's top
    is broken by round ridges and the logs by a hump.

    Difficulty mapping (d in [0, 1]):

    * bar height ``(0.01 + 0.05 d) * U(0.85, 1.0)`` [m], width U(0.04, 0.08) m.
    * log radius ``(0.01 + 0.025 d) * U(0.85, 1.0)`` [m]; 1 + (d > 0.5 with
      probability 1/2) logs, yawed 0.3-0.7 rad from across the path.
    """
    x, y = cell_centres()
    bar_h = lerp(difficulty, 0.01, 0.06) * rng.uniform(0.85, 1.0)  # [m]
    bar_w = rng.uniform(0.04, 0.08)  # [m]
    centre = rng.uniform(0.25, 0.36)  # [m]
    bar = np.where(np.abs(x - centre) <= bar_w / 2, bar_h, 0.0) * np.ones_like(y)
    n_logs = 1 + int(difficulty > 0.5 and rng.uniform() < 0.5)
    z = bar.copy()
    for _ in range(n_logs):
        r = lerp(difficulty, 0.01, 0.035) * rng.uniform(0.85, 1.0)  # [m]
        yaw = rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 0.7)  # [rad] from across the path
        lx = centre + rng.uniform(-0.06, 0.06)  # [m] where its axis crosses y = 0
        u = (x - lx) * math.cos(yaw) + y * math.sin(yaw)  # [m] from the log's axis
        log = np.sqrt(np.clip(r * r - u * u, 0.0, None))
        z = np.maximum(z, np.where(log > 0, log + bar, 0.0))
    return z * _inside(x)


def rolling(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Smooth rolling ground with a ridge and a gully across it; heights in [0, 0.10] m.

    Smoothed random relief (correlation length 4-8 cm), one ridge and one gully
    crossing the path at an angle, on a bed that rises smoothly from the
    approach over 8 cm and returns before the exit; never below z = 0.

    Difficulty mapping (d in [0, 1]):

    * relief standard deviation ``0.002 + 0.008 d`` [m].
    * ridge height and gully depth ``0.006 + 0.024 d`` [m]; the bed ``0.005 m``
      above the gully's depth.
    * ridge and gully widths (Gaussian sigma) U(0.015, 0.03) m, yaw U(-0.5, 0.5) rad.
    """
    x, y = cell_centres()
    sigma = rng.uniform(0.04, 0.08) / MODULE_RESOLUTION  # [cells]
    noise = gaussian_filter(rng.standard_normal((MODULE_CELLS, MODULE_CELLS)), sigma,
                            mode="wrap")
    feature = lerp(difficulty, 0.006, 0.03)  # [m]
    z = 0.005 + feature + noise / max(float(noise.std()), 1e-12) * lerp(difficulty, 0.002, 0.01)
    for sign in (1.0, -1.0):  # the ridge, then the gully
        yaw = rng.uniform(-0.5, 0.5)
        at = rng.uniform(0.15, 0.46)
        width = rng.uniform(0.015, 0.03)
        u = (x - at) * math.cos(yaw) + y * math.sin(yaw)
        z = z + sign * feature * np.exp(-0.5 * (u / width) ** 2)
    rise = np.clip(np.minimum(x - EDGE, MODULE_SIZE - EDGE - x) / 0.08, 0.0, 1.0)
    return np.clip(z, 0.0, 0.10) * (rise * rise * (3 - 2 * rise))  # smoothstep


def scan(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Rolling rocks as a scanner sees them: no-data holes (NaN) behind rises and dropouts.

    The surface is :func:`rolling` ground with rock-like bumps (smoothed noise
    at 1-2 cm); a scanner 0.3 m behind the module's start at 0.6 m height sees
    no surface where a rise in front hides it (the shadow), and misses a few
    blobs of cells elsewhere (dropouts), by the rule of
    :func:`footfall.terrain.occlusion.as_scanned`. Those cells are NaN: the
    planner has no data there, and the simulator fills them down to the map's
    lowest height.

    Difficulty mapping (d in [0, 1]):

    * the rolling ground at difficulty d, bumps of standard deviation
      ``0.002 + 0.008 d`` [m]; the scanner 0.3 m behind the module at 0.6 m;
    * dropouts ``2 + round(8 d)`` blobs of radius U(0.008, 0.02) m.
    """
    x, _ = cell_centres()
    z = rolling(difficulty, rng)
    bumps = gaussian_filter(rng.standard_normal((MODULE_CELLS, MODULE_CELLS)),
                            rng.uniform(0.01, 0.02) / MODULE_RESOLUTION, mode="wrap")
    z = np.clip(z + bumps / max(float(bumps.std()), 1e-12)
                * lerp(difficulty, 0.002, 0.01) * _window(x), 0.0, None)
    return as_scanned(z, difficulty, rng)


HELD_OUT = (("stones", stones), ("washboard", washboard), ("scree", scree),
            ("logbarrier", logbarrier), ("rolling", rolling), ("scan", scan))
"""The held-out kinds, name -> generator, in the suite's order."""
