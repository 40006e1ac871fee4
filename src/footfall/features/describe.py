"""Everything footfall computes about one foothold, as plain data.

Backs ``footfall features``: the 27 terrain features by name and the three
template patches around a point, strictly -- a foothold off the map, a patch
that runs off it, or too little data is an error, not a guess.
"""

from __future__ import annotations

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.features.patches import foothold_patches
from footfall.features.terrain_features import feature_names, terrain_features_from_patches


def _nan_to_none(a: np.ndarray) -> list:
    return [[None if np.isnan(v) else float(v) for v in row] for row in a]


def describe_foothold(hmap: HeightMap, x: float, y: float, yaw: float = 0.0, leg: str = "LF",
                      config: FeatureConfig | None = None,
                      robot: RobotDescription = LITTLEDOG) -> dict:
    """Terrain features and template patches of the foothold at (x, y) [m].

    ``yaw`` [rad] is the body heading that orients the patches; right legs
    (``RF``, ``RH``) see them mirrored in y. Patches are heights relative to
    the foothold [m], indexed [u, v] with u forward and v left of the body.
    """
    config = config or FeatureConfig()
    leg_info = robot.leg(leg)
    if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(yaw)):
        raise FootfallError("position and yaw must be finite numbers")
    if not hmap.is_inside([x, y]):
        x0, x1, y0, y1 = hmap.bounds
        raise FootfallError(f"foothold ({x:.4f}, {y:.4f}) m is off the map "
                            f"(x in [{x0:.4f}, {x1:.4f}], y in [{y0:.4f}, {y1:.4f}])")
    for scale, grid in zip(config.scales, config.grids):
        pts = hmap.sample_points([[x, y]], yaw, leg_info.mirrored, grid)
        if not hmap.is_inside(pts).all():
            raise FootfallError(f"the {scale.name} patch ({scale.length_x * 1000:.0f} x "
                                f"{scale.length_y * 1000:.0f} mm) at ({x:.4f}, {y:.4f}) m "
                                f"runs off the map")
    fp = foothold_patches(hmap, [[x, y]], yaw, leg_info.mirrored, config)
    if np.isnan(fp.heights[0]):
        raise FootfallError(f"the map has no data at ({x:.4f}, {y:.4f}) m")
    if not fp.valid[0]:
        worst = int(np.argmin(fp.coverage[0]))
        raise FootfallError(f"too little data around ({x:.4f}, {y:.4f}) m: the "
                            f"{config.scales[worst].name} patch has data in "
                            f"{fp.coverage[0, worst]:.0%} of its samples "
                            f"(needs {config.min_coverage:.0%})")
    values = terrain_features_from_patches(fp.relative, config)[0]
    patches = {}
    for scale, grid, rel, cov in zip(config.scales, config.grids, fp.relative, fp.coverage[0]):
        patches[scale.name] = {
            "resolution": grid.resolution, "shape": list(grid.shape),
            "length": [scale.length_x, scale.length_y], "coverage": float(cov),
            "u": [float(u) for u in grid.u], "v": [float(v) for v in grid.v],
            "heights": _nan_to_none(rel[0].reshape(grid.shape)),
        }
    return {"position": [float(x), float(y)], "yaw": float(yaw), "leg": leg,
            "mirrored": leg_info.mirrored, "height": float(fp.heights[0]),
            "units": {"position": "m", "yaw": "rad", "height": "m", "patch heights":
                      "m relative to the foothold", "slope": "-", "curv": "1/m", "std": "m"},
            "terrain_features": {n: float(v) for n, v in zip(feature_names(config), values)},
            "patches": patches}
