"""Scoring a candidate set F with a scorer: terrain part plus state part (paper Eq. 1).

The whole-board counterpart, the terrain part at every lattice point of a map
in one call, is :meth:`FootholdScorer.dense <footfall.features.scorer.FootholdScorer.dense>`
(:func:`footfall.features.dense.score_grid`).
"""

from __future__ import annotations

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.family import Candidates
from footfall.features.scorer import FootholdScorer


def score_footholds(hmap: HeightMap, state: RobotState, footholds: np.ndarray,
                    scorer: FootholdScorer, robot: RobotDescription = LITTLEDOG) -> np.ndarray:
    """Values (n,) of candidate footholds (n, 3) [m] of ``state``'s swing leg by ``scorer``.

    Footholds that are not valid (no data, too little patch coverage) get -inf.
    """
    return scorer.values(Candidates.of_state(hmap, state, footholds, scorer.config, robot))
