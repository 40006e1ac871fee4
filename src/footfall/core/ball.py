"""A rigid ball lowered onto a height grid: where its centre comes to rest, for every cell.

``B(c) = max over cells c' within radius of h(c') + sqrt(radius^2 - |c - c'|^2)``,
a grey-scale dilation of the heights by the ball's cap. The walking expert
judges footholds on it (:mod:`footfall.expert.synthetic`); a ball foot's
single contact in the pad physics variant follows it
(:mod:`footfall.sim.foot_pads`).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage


def ball_centre_surface(heights: np.ndarray, resolution: float, radius: float) -> np.ndarray:
    """Centre height [m] of a ball of ``radius`` [m] resting over each cell of ``heights`` [m].

    Cells are points at their centres, ``resolution`` [m] apart; -inf or NaN
    cells give no support, and so does everything beyond the grid. A cell
    with no supporting cell within ``radius`` gets -inf.
    """
    reach = int(math.ceil(radius / resolution))
    off = np.arange(-reach, reach + 1) * resolution
    d2 = off[:, None] ** 2 + off[None, :] ** 2
    footprint = d2 <= radius * radius * (1 + 1e-9)
    cap = np.sqrt(np.clip(radius * radius - d2, 0.0, None))
    return ndimage.grey_dilation(np.where(np.isnan(heights), -np.inf, heights),
                                 footprint=footprint, structure=np.where(footprint, cap, 0.0),
                                 mode="constant", cval=-np.inf)
