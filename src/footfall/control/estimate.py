"""What the controller knows of its body in one control period, worked out from its measurements.

A robot does not measure where its feet are or where its centre of mass is:
it works them out from its joint encoders and its body pose (motion capture)
with its own description. :class:`BodyEstimate` does that, once per control
period: the ball-foot centres by the legs' forward kinematics
(:func:`footfall.core.kinematics.legs_forward_kinematics`), the centre of
mass from the parts' masses (:func:`footfall.core.mass.body_centre_of_mass`),
the foot force readings turned from each foot's frame into the world's, and
-- when asked -- the feet's analytic Jacobians
(:func:`footfall.core.kinematics.legs_jacobians`). They agree with the
simulator's own values to rounding (``tests/test_estimate.py``).

The same formulas are written out here on Python floats for the four legs of
one pose (:func:`body_points`, :func:`body_jacobians`): at 100 Hz NumPy's
per-call overhead on a few dozen numbers would cost more than the physics.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from footfall.control.lowlevel import body_rotation, shin_rotations
from footfall.control.measurements import Measurements
from footfall.core.mass import leg_masses, shin_length
from footfall.core.robot import RobotDescription


@lru_cache(maxsize=8)
def _legs(robot: RobotDescription) -> tuple:
    """Per leg (hip x, y, z [m], side * hip_offset [m]); the parts' (distance down the upper
    leg [m], then down the lower [m], lateral share of side * hip_offset, mass [kg]), the foot
    last; the total mass [kg]: as Python floats."""
    l1 = robot.upper_leg
    masses = leg_masses(robot).tolist()
    along = ((0.0, 0.0, 0.5), (0.5 * l1, 0.0, 1.0), (l1, 0.5 * shin_length(robot), 1.0),
             (l1, robot.lower_leg, 1.0))  # hip link, thigh, lower leg, foot
    legs = tuple((*map(float, leg.hip), float(leg.side * robot.hip_offset)) for leg in robot.legs)
    parts = tuple((a, b, share, m) for (a, b, share), m in zip(along, masses))
    return legs, parts, float(robot.total_mass)


def body_points(robot: RobotDescription, q: np.ndarray) -> tuple[list, list]:
    """The foot centres (4 x 3) [m] and the centre of mass (3,) [m] in the body frame, from the
    joint angles (4, 3) [rad], as nested lists of floats.

    :func:`footfall.core.kinematics.legs_forward_kinematics` and
    :func:`footfall.core.mass.body_centre_of_mass` for one pose: each part's
    centre lies ``a`` down the upper leg and ``b`` down the lower in the leg's
    plane, which the hip roll turns about the body's x axis.
    """
    legs, parts, total = _legs(robot)
    feet, cx, cy, cz = [], 0.0, 0.0, 0.0
    for (q1, q2, q3), (hx, hy, hz, side) in zip(q.tolist(), legs):
        c1, s1 = math.cos(q1), math.sin(q1)
        c2, s2 = math.cos(q2), math.sin(q2)
        c23, s23 = math.cos(q2 + q3), math.sin(q2 + q3)
        for a, b, share, mass in parts:
            x, z, y = -a * s2 - b * s23, -a * c2 - b * c23, share * side
            px, py, pz = x + hx, c1 * y - s1 * z + hy, s1 * y + c1 * z + hz
            cx, cy, cz = cx + mass * px, cy + mass * py, cz + mass * pz
        feet.append([px, py, pz])  # the last part: the foot
    return feet, [cx / total, cy / total, cz / total]


def body_jacobians(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """:func:`footfall.core.kinematics.legs_jacobians` for one pose: (4, 3, 3) [m/rad], body
    frame, from the joint angles (4, 3) [rad]."""
    legs, _, _ = _legs(robot)
    l1, l2 = robot.upper_leg, robot.lower_leg
    out = []
    for (q1, q2, q3), (_, _, _, side) in zip(q.tolist(), legs):
        c1, s1 = math.cos(q1), math.sin(q1)
        bx, bz = -l2 * math.sin(q2 + q3), -l2 * math.cos(q2 + q3)  # the foot from the knee
        fx, fz = -l1 * math.sin(q2) + bx, -l1 * math.cos(q2) + bz  # from the hip pitch axis
        out.append(((0.0, fz, bz),
                    (-s1 * side - c1 * fz, s1 * fx, s1 * bx),
                    (c1 * side - s1 * fz, -c1 * fx, -c1 * bx)))
    return np.array(out)


class BodyEstimate:
    """The robot's state as the controller sees it in one control period.

    Parameters
    ----------
    m : Measurements
        This period's readings.
    robot : RobotDescription
        The robot.

    Attributes
    ----------
    time : float
        [s] since the run began.
    q : ndarray of shape (4, 3)
        Joint angles [rad].
    pose : (ndarray (3,), ndarray (3,))
        Body position [m] and roll, pitch, yaw [rad].
    rotation : ndarray of shape (3, 3)
        The body's attitude as a matrix (body to world).
    feet : ndarray of shape (4, 3)
        Ball-foot centres [m], world frame.
    com : ndarray of shape (3,)
        Centre of mass [m], world frame.
    """

    def __init__(self, m: Measurements, robot: RobotDescription) -> None:
        self.time = m.time
        self.q = m.joint_angles
        self.pose = (m.body_position, m.body_rpy)
        self.rotation = rot = body_rotation(m.body_rpy)
        feet, com = body_points(robot, self.q)
        position = np.asarray(m.body_position, dtype=np.float64)
        self.feet = np.array(feet) @ rot.T + position
        self.com = rot @ com + position
        self._m, self._robot = m, robot
        self._forces: np.ndarray | None = None
        self._jacobians: np.ndarray | None = None

    def forces(self) -> np.ndarray:
        """Foot force sensor readings (4, 3) [N], world frame, +z for a foot pressed down."""
        if self._forces is None:  # each foot's frame turns with its shin
            feet = shin_rotations(self.q, self.rotation)
            self._forces = np.einsum("kij,kj->ki", feet, self._m.foot_forces)
        return self._forces

    def jacobians(self) -> np.ndarray:
        """Jacobians (4, 3, 3) [m/rad] of the foot centres (world frame) in their legs' joints."""
        if self._jacobians is None:
            self._jacobians = self.rotation @ body_jacobians(self._robot, self.q)
        return self._jacobians
