"""Training kinds beyond the paper's: ridges, a pitted deck, rock as scanned, pavers with open joints.

The paper's module kinds (:mod:`footfall.terrain.generators`,
:mod:`footfall.terrain.rocky`) are the terrain footfall's parameters were first
chosen on. These three widen the training side with characters none of them
has (docs/terrain-suite.md, "Two more training kinds", "A training kind
with holes" and "A training kind with stepping stones"): each is a
:data:`~footfall.terrain.geometry.Generator`, registered in
:mod:`footfall.terrain.kinds`, walked by the training suite and the ablation,
and -- unlike the held-out kinds -- open to tuning.

* ``ridges`` -- ground made of ridges across the path and nothing else;
* ``pitted`` -- a raised deck with round pits through it that the ball foot sinks into;
* ``rockyscan`` -- the paper's rocky module as a scanner sees it: no data behind rises;
* ``pavers`` -- level pavers of different heights whose joints are open to the ground.

Their difficulty mappings were fixed from the robot's geometry (heights of the
scale of steps and rocky at the same difficulty, flanks about the ball's
friction cone, pits and joints wider than the ball) before any run on them.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from footfall.terrain.geometry import MODULE_CELLS, MODULE_SIZE, cell_centres, lerp
from footfall.terrain.occlusion import as_scanned
from footfall.terrain.rocky import rocky

RIDGE_SPAN = (0.05, 0.56)  # [m] stretch of the module whose ridge centres lie in
RIDGE_FADE = (0.01, 0.07)  # [m] from either end, the ridges rise from 0 to full height over this
MIN_RIDGE_WIDTH = 0.03  # [m] narrowest ridge, foot to foot
PIT_REACH = 0.25  # [m] pit centres lie within this of the path's centre line (|y|)
PAVER_SITES = 50  # Voronoi sites over the paved strip: pavers about 7 cm across on average
PAVED_FROM = (0.06, 0.09)  # [m] the paved strip starts this far after the module's start (and
# ends as far before its end), drawn uniformly
JOINT_NEIGHBOURS = 4  # sites whose bisectors bound a cell's paver (the nearest and 3 more)


def ridges(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Ground made of ridges across the path, each with its own yaw; heights in [0, 0.05] m.

    Each ridge is a raised-cosine bump ``h cos^2(pi u / w)`` for ``|u| <= w / 2``
    (u [m] across the ridge's axis): a smooth crest, a smooth foot, its steepest
    flank ``atan(pi h / w)`` half-way up. The ridges lie across the path, each
    yawed on its own, so neighbours close in and open up across the width; where
    they overlap the higher one wins and they meet in a V-shaped trough. The
    module starts and ends at z = 0: the ridges rise from nothing over its first
    and last ``RIDGE_FADE`` (a smoothstep from 1 to 7 cm), so a ridge cut by an
    end leaves no cliff.

    Difficulty mapping (d in [0, 1]):

    * ridge height ``h = (0.008 + 0.042 d) * U(0.75, 1.0)`` [m]: 6-8 mm at d = 0,
      28-37 mm at d = 0.7, up to 50 mm at d = 1.
    * steepest flank ``(0.25 + 0.65 d) * U(0.85, 1.0)`` [rad]: 12-14 deg at
      d = 0, 34-40 deg at d = 0.7 (the ball's friction cone is 38.7 deg), 44-52
      deg at d = 1; with h it sets the width ``w = max(pi h / tan(flank), 0.03)`` [m].
    * centres spaced U(0.06, 0.11) m from ``RIDGE_SPAN[0]``, yaw U(-0.2, 0.2) rad
      each: independent of d.
    """
    x, y = cell_centres()
    centres = [RIDGE_SPAN[0] + rng.uniform(0.0, 0.03)]
    while True:
        nxt = centres[-1] + rng.uniform(0.06, 0.11)
        if nxt > RIDGE_SPAN[1]:
            break
        centres.append(nxt)
    n = len(centres)
    height = lerp(difficulty, 0.008, 0.05) * rng.uniform(0.75, 1.0, n)  # [m]
    flank = lerp(difficulty, 0.25, 0.9) * rng.uniform(0.85, 1.0, n)  # [rad]
    width = np.maximum(math.pi * height / np.tan(flank), MIN_RIDGE_WIDTH)  # [m]
    yaw = rng.uniform(-0.2, 0.2, n)  # [rad]
    z = np.zeros((MODULE_CELLS, MODULE_CELLS))
    for k in range(n):  # a handful of ridges, each vectorised over the module
        u = (x - centres[k]) * math.cos(yaw[k]) + y * math.sin(yaw[k])  # [m] across its axis
        bump = height[k] * np.cos(math.pi * u / width[k]) ** 2
        z = np.maximum(z, np.where(np.abs(u) <= 0.5 * width[k], bump, 0.0))
    inside = np.clip((np.minimum(x, MODULE_SIZE - x) - RIDGE_FADE[0])
                     / (RIDGE_FADE[1] - RIDGE_FADE[0]), 0.0, 1.0)  # (610, 1)
    return z * (inside * inside * (3 - 2 * inside))  # smoothstep: no cliff where a ridge is cut


def pitted(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A raised deck with round pits through it to the ground; heights in [0, 0.05] m.

    The deck is flat with vertical edges, from 7-10 cm after the module's start
    to 7-10 cm before its end; each pit is a round hole down to z = 0, wider than
    the 1 cm ball foot, so a foot set in one sinks to the ground with the deck's
    edge around it.

    Difficulty mapping (d in [0, 1]):

    * deck height ``(0.01 + 0.04 d) * U(0.85, 1.0)`` [m]: about 1 cm at d = 0,
      32-38 mm at d = 0.7, up to 5 cm at d = 1.
    * ``6 + round(14 d)`` pits (16 at d = 0.7) of radius U(0.012, 0.028) m, centres
      uniform over the deck within ``PIT_REACH`` of the centre line: their size
      is independent of d.
    """
    x, y = cell_centres()
    start = rng.uniform(0.07, 0.10)  # [m]
    end = MODULE_SIZE - rng.uniform(0.07, 0.10)  # [m]
    deck = lerp(difficulty, 0.01, 0.05) * rng.uniform(0.85, 1.0)  # [m]
    n = 6 + int(round(14 * difficulty))
    px = rng.uniform(start, end, n)
    py = rng.uniform(-PIT_REACH, PIT_REACH, n)
    pr = rng.uniform(0.012, 0.028, n)  # [m]
    on_deck = ((x >= start) & (x <= end)) & np.ones_like(y, dtype=bool)
    in_pit = ((x[..., None] - px) ** 2 + (y[..., None] - py) ** 2 <= pr ** 2).any(axis=-1)
    return np.where(on_deck & ~in_pit, deck, 0.0)


def rockyscan(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """The paper's rocky module as a scanner sees it: NaN behind rises and in dropouts.

    The surface is :func:`footfall.terrain.rocky.rocky` at the same difficulty
    and from the same ``rng``; the cells a scanner 0.3 m behind the module at
    0.6 m cannot see (in cracks, holes and behind rock edges that fall away
    from it) and a few dropout discs have no data, by the rule of
    :func:`footfall.terrain.occlusion.as_scanned` that the held-out ``scan``
    uses. The planner has no data there; the simulator fills those cells down
    to the board's lowest height, so a hidden crack or hole is at least as deep
    as the board's floor.

    Difficulty mapping (d in [0, 1]): the rocky kind's, and ``2 + round(8 d)``
    dropouts of radius U(0.008, 0.02) m.
    """
    return as_scanned(rocky(difficulty, rng), difficulty, rng)


def pavers(difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """Level pavers of different heights with joints open to the ground; heights in [0, 0.05] m.

    The paved strip runs from U(0.06, 0.09) m after the module's start to as
    far before its end, across the whole width. It is the Voronoi partition of
    :data:`PAVER_SITES` uniform random sites, each cell a paver with a level
    top and vertical sides, shrunk back from every neighbour so that the joint
    between two pavers is ground (z = 0) of the joint's width: a cell is
    ground where it lies within half a joint of the bisector between its
    nearest site and any of the next ``JOINT_NEIGHBOURS - 1``. Pavers come in
    many sizes, slivers narrower than the ball among them.

    Difficulty mapping (d in [0, 1]):

    * joint width ``0.004 + 0.046 d`` [m]: 4 mm at d = 0 (the 2 cm ball
      bridges it), 36 mm at d = 0.7, 50 mm at d = 1;
    * each paver's top ``(0.01 + 0.04 d) * U(0.5, 1.0)`` [m]: 19-38 mm at
      d = 0.7, up to 50 mm at d = 1;
    * the sites and the strip's ends: independent of d.
    """
    x, y = cell_centres()
    start = rng.uniform(*PAVED_FROM)  # [m]
    end = MODULE_SIZE - rng.uniform(*PAVED_FROM)  # [m]
    sites = np.column_stack([rng.uniform(start, end, PAVER_SITES),
                             rng.uniform(-0.5 * MODULE_SIZE, 0.5 * MODULE_SIZE, PAVER_SITES)])
    top = lerp(difficulty, 0.01, 0.05) * rng.uniform(0.5, 1.0, PAVER_SITES)  # [m]
    joint = lerp(difficulty, 0.004, 0.05)  # [m]
    cells = np.column_stack([np.broadcast_to(x, (MODULE_CELLS, MODULE_CELLS)).ravel(),
                             np.broadcast_to(y, (MODULE_CELLS, MODULE_CELLS)).ravel()])
    dist, idx = cKDTree(sites).query(cells, k=JOINT_NEIGHBOURS)
    near = sites[idx[:, :1]]  # (cells, 1, 2) the paver's own site
    apart = np.linalg.norm(sites[idx[:, 1:]] - near, axis=-1)  # [m] to each next site
    to_joint = (dist[:, 1:] ** 2 - dist[:, :1] ** 2) / (2.0 * apart)  # [m] to each bisector
    paved = (to_joint.min(axis=1) >= 0.5 * joint) & (cells[:, 0] >= start) & (cells[:, 0] <= end)
    return np.where(paved, top[idx[:, 0]], 0.0).reshape(MODULE_CELLS, MODULE_CELLS)


ADDED = (("ridges", ridges), ("pitted", pitted), ("rockyscan", rockyscan), ("pavers", pavers))
"""The training kinds beyond the paper's, name -> generator, in the training suite's order."""
