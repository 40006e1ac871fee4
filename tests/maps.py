"""Small terrains the tests share."""

import numpy as np
from scipy.ndimage import gaussian_filter

from footfall.core.heightmap import HeightMap


def rough_map(seed: int = 4) -> HeightMap:
    """A smooth random surface 0.5 x 0.4 m at 1 mm, centred on the origin (heights ~ +-2 cm)."""
    rng = np.random.default_rng(seed)
    heights = gaussian_filter(rng.normal(size=(500, 400)), 6) * 0.15
    return HeightMap(heights, 0.001, (-0.25, -0.2))


def short_flat_board() -> HeightMap:
    """Flat ground 0.8 m long, recorded as three modules (start, middle, goal): short walks."""
    res = 0.001
    heights = np.zeros((round(0.8 / res), round(0.4 / res)))
    modules = [{"kind": "flat", "x_start": 0.0, "x_end": 0.36},
               {"kind": "flat", "x_start": 0.36, "x_end": 0.44},
               {"kind": "flat", "x_start": 0.44, "x_end": 0.8}]
    return HeightMap(heights, res, (0.0, -0.2), metadata={"modules": modules})
