"""The paper's terrain module kinds but rocky (§IV-A): flat, steps, barrier, slope and logs.

Each is a :data:`~footfall.terrain.geometry.Generator`: ``(difficulty, rng) ->
heights (610, 610) [m]``, every random number drawn from ``rng``, the edges that
meet a neighbouring module at height 0. They are registered as terrain kinds in
:mod:`footfall.terrain.kinds`; the rocky kind has a module of its own
(:mod:`footfall.terrain.rocky`).
"""

from __future__ import annotations

import math

import numpy as np

from footfall.terrain.geometry import MODULE_CELLS, MODULE_SIZE, cell_centres, lerp


def flat(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A flat module: every height 0 [m] (``difficulty`` and ``rng`` are ignored)."""
    return np.zeros((MODULE_CELLS, MODULE_CELLS))


def steps(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Steps up onto a platform and back down to the ground; heights in [0, 0.10] m.

    Flat approach, 1-3 steps up (number drawn from the seed), a platform,
    1-3 steps down (drawn independently), flat exit; the module starts and
    ends at z = 0. The step edges run across the path, yawed together by a
    small angle.

    Difficulty mapping (d in [0, 1]):

    * platform height ``H = (0.015 + 0.085 d) * U(0.85, 1.0)`` [m]:
      0.013-0.015 m at d = 0, up to 0.10 m at d = 1; split into risers of
      unequal height (each 0.6-1.4 x the mean riser).
    * tread depth U(0.05, 0.07) m, flat approach/exit U(0.07, 0.10) m,
      edge yaw U(-0.08, 0.08) rad: independent of d.
    """
    x, y = cell_centres()
    n_up, n_down = (int(n) for n in rng.integers(1, 4, size=2))
    total = lerp(difficulty, 0.015, 0.10) * rng.uniform(0.85, 1.0)  # [m]
    up = rng.uniform(0.6, 1.4, size=3)[:n_up]
    down = rng.uniform(0.6, 1.4, size=3)[:n_down]
    up_risers = total * up / up.sum()  # [m]
    down_risers = total * down / down.sum()  # [m]
    tread = rng.uniform(0.05, 0.07)  # [m]
    margin_in, margin_out = rng.uniform(0.07, 0.10, size=2)  # [m]
    yaw = rng.uniform(-0.08, 0.08)  # [rad]
    along = x + math.tan(yaw) * y  # [m] position along the path, skewed with the edges
    up_levels = np.concatenate([[0.0], np.cumsum(up_risers)])  # [m] after 0..n_up edges
    down_levels = total - np.concatenate([[0.0], np.cumsum(down_risers)])  # [m]
    up_levels[-1], down_levels[-1] = total, 0.0  # exact platform and exit heights
    up_edges = margin_in + tread * np.arange(n_up)  # [m]
    down_edges = MODULE_SIZE - margin_out - tread * np.arange(n_down)[::-1]  # [m]
    passed_up = (along[..., None] >= up_edges).sum(axis=-1)  # edges behind each cell
    passed_down = (along[..., None] >= down_edges).sum(axis=-1)
    return np.minimum(up_levels[passed_up], down_levels[passed_down])


def barrier(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Bars lying across the path, with 45-degree chamfered top edges; heights in [0, 0.10] m.

    1-3 bars (number drawn from the seed), each in its own slot of the middle
    of the module ``x in [0.12, 0.49]`` m, slightly yawed; the module starts
    and ends at z = 0.

    Difficulty mapping (d in [0, 1]):

    * bar height ``(0.01 + 0.09 d) * U(0.7, 1.0)`` [m]: 0.007-0.01 m at d = 0,
      up to 0.10 m at d = 1.
    * bar width U(0.02, 0.08) m, yaw U(-0.05, 0.05) rad, chamfer
      min(3 mm, width / 4, height / 2): independent of d.
    """
    x, y = cell_centres()
    n = int(rng.integers(1, 4))
    heights = lerp(difficulty, 0.01, 0.10) * rng.uniform(0.7, 1.0, size=3)  # [m]
    widths = rng.uniform(0.02, 0.08, size=3)  # [m]
    jitter = rng.uniform(-0.5, 0.5, size=3)  # [-] of the free room in a slot
    yaws = rng.uniform(-0.05, 0.05, size=3)  # [rad]
    start, end = 0.12, 0.49  # [m] stretch of the module holding the bars
    slot = (end - start) / n  # [m]
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):
        h, w, yaw = heights[k], widths[k], yaws[k]
        centre = start + (k + 0.5) * slot + jitter[k] * (slot - w - 0.04)
        u = np.abs((x - centre) * math.cos(yaw) + y * math.sin(yaw))  # [m] from the bar axis
        chamfer = min(0.003, w / 4, h / 2)  # [m]
        bar = np.where(u <= w / 2, np.minimum(h, h - chamfer + (w / 2 - u)), 0.0)
        z = np.maximum(z, bar)
    return z


def slope(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A ramp up, a plateau and a ramp down, tilted sideways; heights in [0, 0.102] m.

    The profile along x rises linearly from z = 0, holds, and falls back to
    z = 0 before the end of the module. A lateral tilt drawn from the seed
    scales the profile by ``1 + k y / 0.305`` with k in U(-0.35, 0.35), so the
    plateau leans left or right while the module's ends stay at z = 0.

    Difficulty mapping (d in [0, 1]):

    * plateau height on the centre line ``H = 0.015 + 0.06 d`` [m]:
      0.015 m at d = 0, 0.075 m at d = 1 (0.10 m at the high side with the
      largest tilt).
    * ramp angles ``(8 + 17 d) deg * U(0.8, 1.0)`` each: 6-8 deg at d = 0,
      20-25 deg (0.35-0.44 rad) at d = 1.
    * flat approach/exit U(0.04, 0.08) m: independent of d.
    """
    x, y = cell_centres()
    height = lerp(difficulty, 0.015, 0.075)  # [m]
    angles = np.radians(lerp(difficulty, 8.0, 25.0)) * rng.uniform(0.8, 1.0, size=2)  # [rad]
    run_up, run_down = height / np.tan(angles)  # [m] horizontal length of each ramp
    margin_in, margin_out = rng.uniform(0.04, 0.08, size=2)  # [m]
    tilt = rng.uniform(-0.35, 0.35)  # [-] relative height change at the side edges
    rise = (x - margin_in) / run_up
    fall = (MODULE_SIZE - margin_out - x) / run_down
    profile = height * np.clip(np.minimum(rise, fall), 0.0, 1.0)  # (610, 1) [m]
    return profile * (1.0 + tilt * y / (0.5 * MODULE_SIZE))


def logs(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Half-cylinder logs lying across the path at slight random angles; heights in [0, 0.09] m.

    1-3 logs (number drawn from the seed, reduced so that the logs fit with
    a gap of at least 3 cm), each centred in its own slot of
    ``x in [0.075, 0.535]`` m; the module starts and ends at z = 0.

    Difficulty mapping (d in [0, 1]):

    * log radius = height ``(0.015 + 0.075 d) * U(0.8, 1.0)`` [m]:
      0.012-0.015 m at d = 0, up to 0.09 m at d = 1 (then at most 2 logs).
    * yaw U(-0.1, 0.1) rad: independent of d.
    """
    x, y = cell_centres()
    n_drawn = int(rng.integers(1, 4))
    max_radius = lerp(difficulty, 0.015, 0.09)  # [m]
    radii = max_radius * rng.uniform(0.8, 1.0, size=3)  # [m]
    yaws = rng.uniform(-0.1, 0.1, size=3)  # [rad]
    jitter = rng.uniform(-0.5, 0.5, size=3)  # [-] of the free room in a slot
    start, end = 0.075, 0.535  # [m] stretch of the module holding the logs
    n = max(1, min(n_drawn, int((end - start) // (2 * max_radius + 0.03))))
    slot = (end - start) / n  # [m]
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):
        r, yaw = radii[k], yaws[k]
        centre = start + (k + 0.5) * slot + jitter[k] * max(slot - 2 * r - 0.03, 0.0)
        u = (x - centre) * math.cos(yaw) + y * math.sin(yaw)  # [m] from the log's axis
        z = np.maximum(z, np.sqrt(np.clip(r * r - u * u, 0.0, None)))
    return z

