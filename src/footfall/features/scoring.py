"""Scoring a candidate set F with a reward: terrain part plus state part (paper Eq. 1).

The whole-board counterpart, the terrain part at every lattice point of a map
in one call, is :func:`footfall.features.dense.score_grid`.
"""

from __future__ import annotations

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.family import Candidates
from footfall.features.reward import LinearReward


def score_footholds(hmap: HeightMap, state: RobotState, footholds: np.ndarray,
                    reward: LinearReward, robot: RobotDescription = LITTLEDOG) -> np.ndarray:
    """Full reward (terrain + templates + pose) of candidate footholds (n, 3) [m] -> (n,).

    Footholds that are not valid (no data, too little patch coverage) get -inf.
    """
    c = Candidates.of_state(hmap, state, footholds, reward.config, robot)
    r = reward.terrain_reward(c)
    if reward.has_state_part:
        r = r + reward.state_reward(c)
    return r
