"""Small terrains the tests share."""

import numpy as np
from scipy.ndimage import gaussian_filter

from footfall.core.heightmap import HeightMap


def rough_map(seed: int = 4) -> HeightMap:
    """A smooth random surface 0.5 x 0.4 m at 1 mm, centred on the origin (heights ~ +-2 cm)."""
    rng = np.random.default_rng(seed)
    heights = gaussian_filter(rng.normal(size=(500, 400)), 6) * 0.15
    return HeightMap(heights, 0.001, (-0.25, -0.2))
