"""Pose features of a foothold: everything about it that is not terrain shape (paper §V).

Progress toward the goal, stability margins of the support triangles the
foothold takes part in, reachability, differences between leg heights, and
knee, shin, body and swing-path clearance. The paper used 26; so does this
module. Every feature is computed for a whole candidate set at once, in the
body's heading frame (yaw only: slopes and heights stay relative to gravity),
and is mirrored for right legs where it has a lateral sense, so that a right
leg looks like a left leg. ``POSE_FEATURE_DOCS`` describes each one and is
rendered in ``docs/features.md``.

Clearances are capped (``CLEARANCE_CAP``): a knee 5 cm above the terrain is
as safe as one 50 cm above it, and the cap keeps a linear reward from paying
for height it does not need. Map cells without data count as no obstacle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import (
    inverse_kinematics,
    joint_limit_margin,
    knee_position,
    rotation_matrix,
    world_to_body,
)
from footfall.core.robot import LEG_NAMES, LITTLEDOG, Leg, RobotDescription, per_robot
from footfall.core.state import RobotState
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates, FeatureFamily, register_family
from footfall.features.support_kernels import hull_areas, triangles_margins

CLEARANCE_CAP = 0.05  # [m] clearances above this count as fully clear
BODY_CLEARANCE_CAP = 0.10  # [m] body clearances above this count as fully clear
_SHIN_SAMPLES = 8  # points along the lower leg checked against the terrain
_PATH_SAMPLES = 16  # points along the straight swing path checked against the terrain
_TRUNK_SAMPLES = (7, 4)  # grid of points under the trunk footprint (x, y)

POSE_FEATURE_DOCS: dict[str, str] = {
    "progress": "[m] advance of the swing foot toward the goal: (f - current foot) . goal direction",
    "lead": "[m] how far ahead of the body origin the foothold lies along the goal direction",
    "step_length": "[m] horizontal distance from the current foot position to the foothold",
    "nominal_dx_abs": "[m] |fore/aft offset| of the foothold from the leg's nominal stance position (heading frame)",
    "nominal_dy_out": "[m] how far the foothold lies outward of the nominal stance position",
    "nominal_dy_in": "[m] how far the foothold lies inward of the nominal stance position",
    "step_up": "[m] rise of the foot: max(f_z - current foot z, 0)",
    "step_down": "[m] drop of the foot: max(current foot z - f_z, 0)",
    "above_stance": "[m] max(f_z - mean height of the three stance feet, 0)",
    "below_stance": "[m] max(mean height of the three stance feet - f_z, 0)",
    "lateral_height_diff": "[m] |f_z - height of the other foot at the same end (front or hind)|",
    "fore_aft_height_diff": "[m] |f_z - height of the other foot on the same side|",
    "leg_drop": "[m] vertical distance from the body origin down to the foothold",
    "next_inradius": "[m] inscribed-circle radius of the support triangle of the next swing (feet other than the next swing leg, with the foot at f)",
    "next_cog_margin": "[m] signed distance of the body origin's ground projection to the nearest edge of that triangle (> 0 inside)",
    "second_inradius": "[m] inscribed-circle radius of the support triangle of the swing after next",
    "second_cog_margin": "[m] signed distance of the body origin's projection to the nearest edge of that triangle",
    "support_area": "[m^2] area of the convex hull of the four feet after the step",
    "reach_margin": "[m] distance of the foot centre inside the leg's maximal reach from the hip",
    "joint_margin": "[rad] smallest distance of any joint angle from its limit (inverse kinematics at the current body pose)",
    "hip_roll_abs": "[rad] |hip roll angle| needed to reach the foothold",
    "knee_clearance": "[m] height of the knee above the terrain below it, capped at CLEARANCE_CAP",
    "shin_clearance": "[m] least clearance of the lower leg (surface, not axis) above the terrain along its length, capped at CLEARANCE_CAP",
    "body_clearance": "[m] clearance of the trunk's underside above the highest terrain under it, with the body at its nominal height over the new stance, capped at BODY_CLEARANCE_CAP",
    "min_foot_distance": "[m] horizontal distance to the nearest other foot (feet or lower legs colliding)",
    "swing_obstacle": "[m] how far the terrain along the straight swing path rises above the higher of lift-off and touch-down",
}
POSE_FEATURE_NAMES: tuple[str, ...] = tuple(POSE_FEATURE_DOCS)


def triangle_margins(tri: np.ndarray, point: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inradius [m] and signed edge distance [m] of a point, triangles (n, 3, 2), point (2,).

    The inradius is the triangle's area over its semi-perimeter (0 for a
    degenerate one); the distance is to the nearest edge, > 0 inside, for
    either winding (0 for a degenerate edge: two feet on one spot leave no
    margin). Compiled (:func:`footfall.features.support_kernels.triangles_margins`).
    """
    tri = np.ascontiguousarray(tri, dtype=np.float64).reshape(-1, 3, 2)
    return triangles_margins(tri, float(point[0]), float(point[1]))


def hull_area(points: np.ndarray) -> np.ndarray:
    """Area [m^2] of the convex hull of 4 points, (n, 4, 2) -> (n,).

    For four points in convex position the non-crossing ordering has the
    largest shoelace area (crossed orderings give a difference of two
    triangles); when one point lies inside the triangle of the others, that
    triangle is the hull and is larger than every ordering's area. Compiled
    (:func:`footfall.features.support_kernels.hull_areas`).
    """
    return hull_areas(np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 4, 2))


def _terrain_clear(hmap: HeightMap, points: np.ndarray) -> np.ndarray:
    """Height [m] of points (..., 3) above the terrain; no data counts as clear (+inf)."""
    ground = hmap.height_at(points[..., :2])
    return np.where(np.isnan(ground), np.inf, points[..., 2] - ground)


@per_robot
def _samples(robot: RobotDescription) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fixed sample points of the clearance features, made once per robot: the shin's
    fractions from knee to foot (_SHIN_SAMPLES,) [-], the trunk footprint's grid in the heading
    frame (_TRUNK_SAMPLES product, 2) [m], the swing path's fractions (_PATH_SAMPLES,) [-]."""
    frac = np.linspace(0.0, 1.0 - robot.foot_radius / robot.lower_leg, _SHIN_SAMPLES)
    lx, ly = robot.trunk_size[0] / 2, robot.trunk_size[1] / 2
    gx, gy = np.meshgrid(np.linspace(-lx, lx, _TRUNK_SAMPLES[0]),
                         np.linspace(-ly, ly, _TRUNK_SAMPLES[1]), indexing="ij")
    trunk = np.column_stack([gx.ravel(), gy.ravel()])
    path = np.linspace(0.0, 1.0, _PATH_SAMPLES)
    for a in (frac, trunk, path):
        a.flags.writeable = False  # shared between calls
    return frac, trunk, path


def pose_features(hmap: HeightMap, state: RobotState, footholds: np.ndarray,
                  robot: RobotDescription = LITTLEDOG) -> np.ndarray:
    """The 26 pose features of candidate footholds, (n, 3) -> (n, 26), in POSE_FEATURE_NAMES order.

    Parameters
    ----------
    footholds : array of shape (n, 3)
        Candidate contact points [m] (x, y, terrain height) in the world frame.
    """
    f = np.asarray(footholds, dtype=np.float64).reshape(-1, 3)
    leg = robot.leg(state.swing_leg)
    out = {**_motion(state, f, leg, robot), **_heights(state, f, leg),
           **_support(state, f, leg, robot), **_reach_and_leg_clearance(hmap, state, f, leg, robot),
           **_body_and_swing(hmap, state, f, robot)}
    return np.column_stack([out[name] for name in POSE_FEATURE_NAMES])


def _heading_rotation(yaw: float) -> np.ndarray:
    """The (2, 2) rotation by the body's heading ``yaw`` [rad]: heading frame -> world."""
    return rotation_matrix(np.array([0.0, 0.0, yaw]))[:2, :2]


def _motion(state: RobotState, f: np.ndarray, leg: Leg, robot: RobotDescription
            ) -> dict[str, np.ndarray]:
    """Progress toward the goal, lead, step length and the offsets from the nominal stance (n,)."""
    s, feet = state.swing_index, state.feet
    yaw = state.yaw
    heading = np.array([np.cos(yaw), np.sin(yaw)])
    body_xy = state.body_position[:2]
    to_goal = state.goal - body_xy
    dist = np.linalg.norm(to_goal)
    goal_dir = to_goal / dist if dist > 1e-9 else heading
    out: dict[str, np.ndarray] = {}
    out["progress"] = (f[:, :2] - feet[s, :2]) @ goal_dir
    out["lead"] = (f[:, :2] - body_xy) @ goal_dir
    out["step_length"] = np.linalg.norm(f[:, :2] - feet[s, :2], axis=1)
    # Offsets from the nominal stance, in the heading frame, lateral sense mirrored.
    rel = (f[:, :2] - body_xy) @ _heading_rotation(yaw)  # heading-frame x, y
    nominal = np.array(robot.nominal_foot(leg.name)[:2])
    out["nominal_dx_abs"] = np.abs(rel[:, 0] - nominal[0])
    outward = leg.side * (rel[:, 1] - nominal[1])
    out["nominal_dy_out"] = np.maximum(outward, 0.0)
    out["nominal_dy_in"] = np.maximum(-outward, 0.0)
    return out


def _heights(state: RobotState, f: np.ndarray, leg: Leg) -> dict[str, np.ndarray]:
    """Height differences (n,) [m] of the foothold from the feet and the body."""
    s, feet = state.swing_index, state.feet
    stance = [k for k in range(4) if k != s]
    out: dict[str, np.ndarray] = {}
    dz = f[:, 2] - feet[s, 2]
    out["step_up"] = np.maximum(dz, 0.0)
    out["step_down"] = np.maximum(-dz, 0.0)
    mean_stance = feet[stance, 2].mean()
    out["above_stance"] = np.maximum(f[:, 2] - mean_stance, 0.0)
    out["below_stance"] = np.maximum(mean_stance - f[:, 2], 0.0)
    same_end = LEG_NAMES.index(("R" if leg.side > 0 else "L") + leg.name[1])
    same_side = LEG_NAMES.index(leg.name[0] + ("H" if leg.front else "F"))
    out["lateral_height_diff"] = np.abs(f[:, 2] - feet[same_end, 2])
    out["fore_aft_height_diff"] = np.abs(f[:, 2] - feet[same_side, 2])
    out["leg_drop"] = state.body_position[2] - f[:, 2]
    return out


def _support(state: RobotState, f: np.ndarray, leg: Leg, robot: RobotDescription
             ) -> dict[str, np.ndarray]:
    """Margins (n,) [m] of the support triangles of the next two swings of the crawl gait, the
    swing foot at f, and the support area (n,) [m^2] after the step."""
    out: dict[str, np.ndarray] = {}
    order = list(robot.gait_order)
    after = np.broadcast_to(state.feet[:, :2], (f.shape[0], 4, 2)).copy()
    after[:, state.swing_index] = f[:, :2]
    for label, ahead in (("next", 1), ("second", 2)):
        lifted = LEG_NAMES.index(order[(order.index(leg.name) + ahead) % 4])
        tri = after[:, [k for k in range(4) if k != lifted]]
        inradius, margin = triangle_margins(tri, state.body_position[:2])
        out[f"{label}_inradius"] = inradius
        out[f"{label}_cog_margin"] = margin
    out["support_area"] = hull_area(after)
    return out


def _reach_and_leg_clearance(hmap: HeightMap, state: RobotState, f: np.ndarray, leg: Leg,
                             robot: RobotDescription) -> dict[str, np.ndarray]:
    """Reachability at the current body pose, and the knee's and shin's clearance (n,)."""
    out: dict[str, np.ndarray] = {}
    centre = f + np.array([0.0, 0.0, robot.foot_radius])
    local = world_to_body(centre, state.body_position, state.body_rpy)
    q, _ = inverse_kinematics(leg, local, robot)
    hip = np.array(leg.hip)
    out["reach_margin"] = robot.max_reach - np.linalg.norm(local - hip, axis=1)
    out["joint_margin"] = joint_limit_margin(leg, q)
    out["hip_roll_abs"] = np.abs(q[:, 0])
    rot = rotation_matrix(state.body_rpy)
    knee = knee_position(leg, q, robot) @ rot.T + state.body_position
    out["knee_clearance"] = np.minimum(_terrain_clear(hmap, knee), CLEARANCE_CAP)
    # Shin samples from the knee to one foot radius short of the foot centre.
    frac = _samples(robot)[0]
    shin = knee[:, None, :] + frac[None, :, None] * (centre - knee)[:, None, :]
    shin_clear = _terrain_clear(hmap, shin).min(axis=1) - robot.lower_leg_radius
    out["shin_clearance"] = np.minimum(shin_clear, CLEARANCE_CAP)
    return out


def _body_and_swing(hmap: HeightMap, state: RobotState, f: np.ndarray, robot: RobotDescription
                    ) -> dict[str, np.ndarray]:
    """The trunk's clearance over the new stance, the nearest other foot and the terrain along
    the straight swing path (n,) [m]."""
    s, feet = state.swing_index, state.feet
    stance = [k for k in range(4) if k != s]
    body_xy = state.body_position[:2]
    out: dict[str, np.ndarray] = {}
    mean_feet_z = (feet[stance, 2].sum() + f[:, 2]) / 4.0
    body_z = mean_feet_z + robot.nominal_height
    _, trunk, t = _samples(robot)
    under = trunk @ _heading_rotation(state.yaw).T + body_xy
    ground = hmap.height_at(under)
    top = np.nanmax(ground) if np.isfinite(ground).any() else -np.inf
    out["body_clearance"] = np.minimum(body_z - robot.trunk_size[2] / 2 - top, BODY_CLEARANCE_CAP)
    others = feet[stance, :2]
    out["min_foot_distance"] = np.min(np.linalg.norm(f[:, None, :2] - others[None], axis=2), axis=1)
    path = feet[s, None, None, :2] + t[None, :, None] * (f[:, None, :2] - feet[s, None, None, :2])
    path_ground = hmap.height_at(path)
    path_top = np.where(np.isfinite(path_ground).any(axis=1),
                        np.nanmax(np.where(np.isnan(path_ground), -np.inf, path_ground), axis=1),
                        -np.inf)
    out["swing_obstacle"] = np.maximum(path_top - np.maximum(f[:, 2], feet[s, 2]), 0.0)
    return out


@register_family
@dataclass(frozen=True, eq=False)
class PoseFeatures(FeatureFamily):
    """The 26 pose features as a feature family: they need the robot's state (paper §V)."""

    name: ClassVar[str] = "pose"
    needs_state: ClassVar[bool] = True

    @classmethod
    def create(cls, config: FeatureConfig, robot: RobotDescription = LITTLEDOG) -> PoseFeatures:
        return cls()

    def columns(self) -> tuple[str, ...]:
        return POSE_FEATURE_NAMES

    def compute(self, c: Candidates) -> np.ndarray:
        if c.state is None:
            raise FootfallError("pose features need the robot's state")
        return pose_features(c.hmap, c.state, c.footholds, c.robot)

    def memo_key(self) -> tuple[str]:
        """No parameters: the columns depend on the candidates (and their state) alone."""
        return (self.name,)
