"""The robot's state at a foothold decision (paper §II-A).

The 3-D positions of all feet, the body position and orientation, and
which leg swings; plus the goal the robot walks toward, which the pose
features need for progress.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription


@dataclass(frozen=True, eq=False)
class RobotState:
    """Where the robot stands when it chooses the next foothold of ``swing_leg``.

    ``feet[k]`` is the world position [m] of the contact point of leg
    ``LEG_NAMES[k]`` (LF, RF, LH, RH): the terrain point under the ball foot.
    """

    feet: np.ndarray  # (4, 3) [m] world contact points, in LEG_NAMES order
    body_position: np.ndarray  # (3,) [m] world position of the body origin
    body_rpy: np.ndarray  # (3,) [rad] roll, pitch, yaw of the body
    swing_leg: str  # the leg that moves next
    goal: np.ndarray = field(default_factory=lambda: np.array([1e3, 0.0]))  # (2,) [m] world x, y

    def __post_init__(self) -> None:
        feet = np.array(self.feet, dtype=np.float64)
        pos = np.array(self.body_position, dtype=np.float64)
        rpy = np.array(self.body_rpy, dtype=np.float64)
        goal = np.array(self.goal, dtype=np.float64)
        if feet.shape != (4, 3) or pos.shape != (3,) or rpy.shape != (3,) or goal.shape != (2,):
            raise FootfallError("robot state needs feet (4, 3), body position (3,), "
                                "body roll/pitch/yaw (3,) and goal (2,)")
        if not all(np.isfinite(a).all() for a in (feet, pos, rpy, goal)):
            raise FootfallError("robot state must be finite")
        if self.swing_leg not in LEG_NAMES:
            raise FootfallError(f"unknown swing leg {self.swing_leg!r}; legs are {', '.join(LEG_NAMES)}")
        for name, arr in (("feet", feet), ("body_position", pos), ("body_rpy", rpy), ("goal", goal)):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def swing_index(self) -> int:
        """Index of the swing leg in LEG_NAMES."""
        return LEG_NAMES.index(self.swing_leg)

    @property
    def yaw(self) -> float:
        """Heading of the body [rad]."""
        return float(self.body_rpy[2])

    def to_vector(self) -> np.ndarray:
        """The state as 20 numbers: feet (12), body position (3), rpy (3), goal (2)."""
        return np.concatenate([self.feet.ravel(), self.body_position, self.body_rpy, self.goal])

    @classmethod
    def from_vector(cls, vector: np.ndarray, swing_leg: str) -> "RobotState":
        """Inverse of :meth:`to_vector`."""
        v = np.asarray(vector, dtype=np.float64)
        if v.shape != (20,):
            raise FootfallError(f"a state vector has 20 numbers, got shape {v.shape}")
        return cls(v[:12].reshape(4, 3), v[12:15], v[15:18], swing_leg, v[18:20])


def nominal_state(hmap, body_xy, yaw: float, swing_leg: str, goal=None, robot=None) -> RobotState:
    """The robot standing in its default stance at ``body_xy`` [m] with heading ``yaw`` [rad].

    Feet at the nominal stance positions on the terrain (heights from the
    map; cells without data count as height 0), the body level at the
    nominal height above the mean foot height. ``goal`` defaults to 1 km
    straight ahead.
    """
    robot = robot or LITTLEDOG
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    xy = np.asarray(body_xy, dtype=np.float64)
    feet_xy = np.array([robot.nominal_foot(n)[:2] for n in LEG_NAMES]) @ rot.T + xy
    z = np.nan_to_num(hmap.height_at(feet_xy), nan=0.0)
    feet = np.column_stack([feet_xy, z])
    body = np.array([xy[0], xy[1], z.mean() + robot.nominal_height])
    goal = xy + 1e3 * np.array([c, s]) if goal is None else goal
    return RobotState(feet, body, np.array([0.0, 0.0, yaw]), swing_leg, goal)


def feet_pitch(feet: np.ndarray, robot=None) -> float:
    """Pitch [rad] of the line from the hind feet's mean to the front feet's mean.

    ``feet`` (4, 3) [m] in ``LEG_NAMES`` order. Positive when the front feet
    stand lower (nose down, the body-frame convention of
    :mod:`footfall.core.kinematics`); 0 on level ground. The body a planner
    predicts pitched so follows the terrain under its feet, as the pose finder
    will pitch it: a level prediction puts the front hips too high to reach
    down a step (and the hind hips too high on the way up).
    """
    robot = robot or LITTLEDOG
    feet = np.asarray(feet, dtype=np.float64)
    front = np.array([robot.leg(n).hip[0] > 0 for n in LEG_NAMES])
    f, h = feet[front].mean(axis=0), feet[~front].mean(axis=0)
    run = max(float(np.hypot(f[0] - h[0], f[1] - h[1])), 1e-6)
    return float(np.arctan2(h[2] - f[2], run))


def stance_target(state: RobotState, robot: RobotDescription, lead: float) -> np.ndarray:
    """The swing leg's gait-nominal foothold (2,) [m]: its default stance around the body,
    moved ``lead`` [m] ahead along the body's heading."""
    c, sn = math.cos(state.yaw), math.sin(state.yaw)
    nominal = np.asarray(robot.nominal_foot(state.swing_leg)[:2]) + (lead, 0.0)
    return np.asarray(state.body_position[:2]) + np.array(
        [c * nominal[0] - sn * nominal[1], sn * nominal[0] + c * nominal[1]])
