"""A terrain module's geometry: 61 x 61 cm at 1 mm, its frame, and its cells in metres.

The paper's testbed (§IV-A) is a row of interchangeable 61 x 61 cm terrain
modules scanned at 1 mm. Module frame: x in [0, 0.61) m forward, y in
[-0.305, 0.305) m left, z up; heights >= 0 above the ground plane z = 0. A
module generator (:data:`Generator`) fills such a grid; the helpers here turn
metres into cells for them.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

MODULE_SIZE = 0.61  # [m] side length of a square terrain module (61 cm)
MODULE_RESOLUTION = 0.001  # [m/cell] scan resolution (1 mm)
MODULE_CELLS = int(round(MODULE_SIZE / MODULE_RESOLUTION))  # [cells] per side (610)
MODULE_ORIGIN = (0.5 * MODULE_RESOLUTION, -0.5 * MODULE_SIZE + 0.5 * MODULE_RESOLUTION)
# [m] centre of cell (0, 0) of a module: (0.0005, -0.3045)

Generator = Callable[[float, np.random.Generator], np.ndarray]
"""A module generator: ``(difficulty, rng) -> heights``. ``difficulty`` in [0, 1] [-] sets the
obstacle sizes (each generator's docstring gives its mapping); ``rng`` (numpy.random.Generator)
is the source of all randomness; ``heights`` (610, 610) [m] are indexed [x, y] in the module
frame, cell centres at :data:`MODULE_ORIGIN` + index * :data:`MODULE_RESOLUTION`."""


def cell_centres() -> tuple[np.ndarray, np.ndarray]:
    """Cell-centre coordinates of a module, as broadcastable arrays.

    Returns
    -------
    x : ndarray, shape (610, 1)
        Forward coordinate of each row of cells [m].
    y : ndarray, shape (1, 610)
        Lateral coordinate of each column of cells [m].
    """
    idx = np.arange(MODULE_CELLS)
    x = MODULE_ORIGIN[0] + idx * MODULE_RESOLUTION
    y = MODULE_ORIGIN[1] + idx * MODULE_RESOLUTION
    return x[:, None], y[None, :]


def lerp(difficulty: float, easy: float, hard: float) -> float:
    """Linear map of difficulty in [0, 1] onto [easy, hard] (any unit)."""
    return easy + (hard - easy) * difficulty


def cell_window(cx: float, cy: float, radius: float) -> tuple[slice, slice]:
    """Index slices of the module cells within ``radius`` [m] of (cx, cy) [m]."""
    i0 = max(int(math.floor((cx - radius - MODULE_ORIGIN[0]) / MODULE_RESOLUTION)), 0)
    i1 = min(int(math.ceil((cx + radius - MODULE_ORIGIN[0]) / MODULE_RESOLUTION)) + 1, MODULE_CELLS)
    j0 = max(int(math.floor((cy - radius - MODULE_ORIGIN[1]) / MODULE_RESOLUTION)), 0)
    j1 = min(int(math.ceil((cy + radius - MODULE_ORIGIN[1]) / MODULE_RESOLUTION)) + 1, MODULE_CELLS)
    return slice(i0, max(i0, i1)), slice(j0, max(j0, j1))

