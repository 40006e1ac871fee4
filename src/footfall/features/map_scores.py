"""A foothold scorer's value at every cell of a map: a score layer to hand to a planner or RViz.

The planner's scorer (a learned model's function for a leg, or a named reward such as
the hand-tuned one) evaluated densely (:func:`footfall.features.dense.score_grid`) on a
lattice whose points are the map's own cell centres, for one leg (a right leg's
patches mirrored) and one body heading. Only the terrain part of the value is
defined without a robot state, so that is what a layer holds; cells that are not a
valid foothold (no data there, or too little of the patch measured) are NaN.

A map coarser than the scorer's patch samples is read as the walker reads it, by
bilinear interpolation of the heights; the layer says so (``interpolated``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.features.dense import score_grid
from footfall.features.scorer import FootholdScorer


@dataclass(frozen=True)
class ScoreLayer:
    """A scorer's terrain value at every cell of a map."""

    values: np.ndarray  # (nx, ny) the value at each cell centre; NaN: not a valid foothold
    leg: str  # the leg scored for (LF, RF, LH, RH)
    heading: float  # [rad] the body heading the patches are oriented by
    interpolated: bool  # the map's cells are coarser than the scorer's patch samples

    @property
    def valid_share(self) -> float:
        """The share of cells that are valid footholds."""
        return float(np.isfinite(self.values).mean())


def score_layer(hmap: HeightMap, scorer: FootholdScorer, leg: str = "LF", heading: float = 0.0,
                robot: RobotDescription = LITTLEDOG) -> ScoreLayer:
    """``scorer``'s terrain value at every cell centre of ``hmap`` for ``leg`` at ``heading``.

    Raises
    ------
    FootfallError
        For an unknown leg or a heading that is not a finite number [rad].
    """
    if leg not in LEG_NAMES:
        raise FootfallError(f"leg must be one of {', '.join(LEG_NAMES)}, got {leg!r}")
    if not np.isfinite(heading):
        raise FootfallError(f"heading must be a finite number [rad], got {heading!r}")
    grid = score_grid(hmap, scorer, spacing=hmap.resolution, yaw=float(heading),
                      mirror=robot.leg(leg).mirrored, dtype=np.float64)
    values = np.full(hmap.shape, np.nan)
    i = np.rint((grid.x - hmap.origin[0]) / hmap.resolution).astype(np.intp)
    j = np.rint((grid.y - hmap.origin[1]) / hmap.resolution).astype(np.intp)
    reward = np.where(grid.valid & np.isfinite(grid.reward), grid.reward, np.nan)
    values[np.ix_(i, j)] = reward
    return ScoreLayer(values, leg, float(heading),
                      hmap.resolution > scorer.config.template_resolution + 1e-12)
