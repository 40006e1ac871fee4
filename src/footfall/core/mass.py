"""Where the robot's mass is: its parts' masses and the whole robot's centre of mass.

The masses of a :class:`~footfall.core.robot.RobotDescription` sit where the
simulator's model puts them (:mod:`footfall.sim.mjcf`): the trunk's at the
body origin; in each leg the hip link's half way from the roll axis out to
the thigh, the thigh's half way down the upper leg, the lower leg's (the
foot's mass aside) half way down the shin to where it meets the ball, and
the foot's at the ball's centre. :func:`centre_of_mass` places them by the
leg's kinematics (:mod:`footfall.core.kinematics`) from the joint angles and
the body pose -- what a robot knows from its encoders and motion capture.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from footfall.core.kinematics import rotation_matrix
from footfall.core.robot import RobotDescription


@lru_cache(maxsize=8)
def leg_masses(robot: RobotDescription) -> np.ndarray:
    """Masses (4,) [kg] of a leg's parts: hip link, thigh, lower leg without the foot, foot."""
    out = np.array([robot.hip_link_mass, robot.upper_leg_mass,
                    robot.lower_leg_mass - robot.foot_mass, robot.foot_mass])
    out.flags.writeable = False  # shared between callers
    return out


@lru_cache(maxsize=8)
def _hips(robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
    """The legs' hip roll axes (4, 3) [m] (body frame) and ``side * hip_offset`` (4,) [m]."""
    hips = np.array([leg.hip for leg in robot.legs], dtype=np.float64)
    side = np.array([leg.side * robot.hip_offset for leg in robot.legs], dtype=np.float64)
    hips.flags.writeable = side.flags.writeable = False  # shared between callers
    return hips, side


def shin_length(robot: RobotDescription) -> float:
    """Length [m] of the shin from the knee axis to where it meets the ball foot."""
    return robot.lower_leg - robot.foot_radius - robot.lower_leg_radius


def leg_mass_points(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """Where the masses of :func:`leg_masses` sit, (..., 4, 4, 3) [m] in the body frame, from
    the joint angles (..., 4, 3) [rad]: legs in ``robot.legs`` order, then the parts."""
    hips, side = _hips(robot)
    q = np.asarray(q, dtype=np.float64)
    l1 = robot.upper_leg
    # each part's centre in the leg's plane: (distance down the upper leg, then down the lower)
    along = np.array([[0.0, 0.0], [0.5 * l1, 0.0], [l1, 0.5 * shin_length(robot)],
                      [l1, robot.lower_leg]])
    q1, q2, q23 = q[..., 0, None], q[..., 1, None], q[..., 2, None] + q[..., 1, None]
    x = -along[:, 0] * np.sin(q2) - along[:, 1] * np.sin(q23)  # (..., 4 legs, 4 parts)
    z = -along[:, 0] * np.cos(q2) - along[:, 1] * np.cos(q23)
    y = side[:, None] * np.array([0.5, 1.0, 1.0, 1.0])  # the hip link reaches half way out
    c, s = np.cos(q1), np.sin(q1)
    return np.stack([x + hips[:, 0, None], c * y - s * z + hips[:, 1, None],
                     s * y + c * z + hips[:, 2, None]], axis=-1)


def body_centre_of_mass(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """The whole robot's centre of mass (..., 3) [m] in the body frame, from the joint angles
    (..., 4, 3) [rad] (``robot.legs`` order)."""
    points = leg_mass_points(robot, q)  # (..., 4, 4, 3) [m]; the trunk's mass is at the origin
    return np.einsum("p,...lpi->...i", leg_masses(robot), points) / robot.total_mass


def centre_of_mass(robot: RobotDescription, q: np.ndarray, position: np.ndarray,
                   rpy: np.ndarray) -> np.ndarray:
    """World position (3,) [m] of the whole robot's centre of mass.

    Parameters
    ----------
    q : array of shape (4, 3)
        Joint angles [rad], ``robot.legs`` order.
    position, rpy : arrays of shape (3,)
        Body origin [m] and roll, pitch, yaw [rad] (Z-Y-X) in the world.
    """
    return (rotation_matrix(rpy) @ body_centre_of_mass(robot, q)
            + np.asarray(position, dtype=np.float64))
