"""Candidate footholds: the set F of terrain points the swing leg can reach.

Points of a lattice (every ``spacing`` metres from the map's cell (0, 0))
around the swing leg's hip, at the terrain's height, whose ball-foot centre
the leg's closed-form inverse kinematics reaches within its joint limits with
the body where the state puts it.
"""

from __future__ import annotations

import numpy as np

from footfall.core.clearance import posed_leg_gaps
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import (
    body_to_world,
    inverse_kinematics,
    joint_limit_margin,
    reaches_points,
    world_to_body,
)
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.config import FeatureConfig
from footfall.features.patches import patch_coverage

DEFAULT_SPACING = 0.005  # [m] distance between neighbouring candidate footholds


def lattice(hmap: HeightMap, x_range: tuple[float, float], y_range: tuple[float, float],
            spacing: float) -> np.ndarray:
    """Lattice points (n, 2) [m] within the ranges, every ``spacing`` from cell (0, 0)'s centre."""
    if not spacing > 0:
        raise FootfallError(f"candidate spacing must be > 0, got {spacing}")
    ox, oy = hmap.origin
    ia = np.arange(np.ceil((x_range[0] - ox) / spacing), np.floor((x_range[1] - ox) / spacing) + 1)
    jb = np.arange(np.ceil((y_range[0] - oy) / spacing), np.floor((y_range[1] - oy) / spacing) + 1)
    xx, yy = np.meshgrid(ox + ia * spacing, oy + jb * spacing, indexing="ij")
    return np.column_stack([xx.ravel(), yy.ravel()])


def reaches(state: RobotState, footholds: np.ndarray, robot: RobotDescription = LITTLEDOG
            ) -> np.ndarray:
    """Whether the swing leg of ``state`` reaches each contact point (n, 3) [m] -> (n,) bool:
    inverse kinematics of the ball-foot centre (``foot_radius`` above the point) within the
    joint limits, at the state's body pose."""
    centre = np.asarray(footholds, dtype=np.float64) + (0.0, 0.0, robot.foot_radius)
    return reaches_points(robot.leg(state.swing_leg), centre, state.body_position,
                          state.body_rpy, robot).reshape(centre.shape[:-1])


def joint_margins(state: RobotState, footholds: np.ndarray, robot: RobotDescription = LITTLEDOG
                  ) -> np.ndarray:
    """Smallest distance [rad] of any joint of the swing leg of ``state`` from its limits with
    the ball-foot centre on each contact point (n, 3) [m] -> (n,), at the state's body pose;
    negative outside the limits, NaN where the leg cannot reach the point."""
    leg = robot.leg(state.swing_leg)
    centre = np.asarray(footholds, dtype=np.float64) + (0.0, 0.0, robot.foot_radius)
    q, _ = inverse_kinematics(leg, world_to_body(centre, state.body_position, state.body_rpy),
                              robot)
    return joint_limit_margin(leg, q)


def leg_clearances(hmap: HeightMap, state: RobotState, footholds: np.ndarray,
                   robot: RobotDescription = LITTLEDOG, samples: int = 10,
                   span: float | None = None) -> np.ndarray:
    """Least clearance [m] of the swing leg's knee and shin above the terrain with the ball-foot
    centre on each contact point (n, 3) [m] -> (n,), at the state's body pose: ``samples``
    spheres of the lower leg's radius from the knee down to the ball, or to ``span`` [-] of
    the way to its centre (:func:`footfall.core.clearance.posed_leg_gaps`); 0 where the leg
    touches the terrain, negative where it would cut into it, NaN where the leg cannot reach
    the point."""
    centre = np.asarray(footholds, dtype=np.float64) + (0.0, 0.0, robot.foot_radius)
    return posed_leg_gaps(hmap, robot.leg(state.swing_leg), centre, state.body_position,
                          state.body_rpy, robot, samples, span)


def reachable_footholds(hmap: HeightMap, state: RobotState, robot: RobotDescription = LITTLEDOG,
                        spacing: float = DEFAULT_SPACING, config: FeatureConfig | None = None
                        ) -> np.ndarray:
    """The candidate set F of the swing leg, shape (n, 3): x, y and terrain height z [m].

    A lattice point is a candidate if the map has data there, the leg's
    inverse kinematics reaches the ball-foot centre (``foot_radius`` above the
    point) within the joint limits, and -- if ``config`` is given -- its
    feature patches have enough data (``config.min_coverage``).
    """
    leg = robot.leg(state.swing_leg)
    hip = body_to_world(np.array(leg.hip), state.body_position, state.body_rpy)
    reach = robot.max_reach
    pts = lattice(hmap, (hip[0] - reach, hip[0] + reach), (hip[1] - reach, hip[1] + reach), spacing)
    z = hmap.height_at(pts)
    has_data = ~np.isnan(z)
    out = np.column_stack([pts[has_data], z[has_data]])
    out = out[reaches(state, out, robot)]
    if config is not None and out.shape[0]:
        cov = patch_coverage(hmap, out, state.yaw, leg.mirrored, config)
        out = out[np.all(cov >= config.min_coverage, axis=1)]
    return out
