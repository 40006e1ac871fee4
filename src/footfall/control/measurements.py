"""What passes between the controller and the robot: measurements in, joint targets out.

A real LittleDog's controller reads, every control period (100 Hz), its joint
encoders, the body pose from motion capture and its three-axis foot force
sensors, and answers with set-points for the joint servos. These two types
are that interface; the controller (:mod:`footfall.control.controller`) sees
the robot only through :class:`Measurements`, and the simulator
(:mod:`footfall.sim.episode`) only through :class:`JointTargets`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Measurements:
    """One control period's readings of the robot's sensors: what a LittleDog knows.

    Everything else the controller uses -- where its feet are, its centre of
    mass, the forces in the world frame -- it works out from these with the
    robot description (:class:`~footfall.control.estimate.BodyEstimate`).
    """

    time: float  # [s] since the run began
    joint_angles: np.ndarray  # (4, 3) [rad] encoders, LEG_NAMES x (hip roll, hip pitch, knee)
    body_position: np.ndarray  # (3,) [m] trunk origin, world frame (motion capture)
    body_rpy: np.ndarray  # (3,) [rad] trunk roll, pitch, yaw, Z-Y-X (motion capture)
    foot_forces: np.ndarray  # (4, 3) [N] foot force sensors, each in its foot's frame (which
    # turns with the shin): the force the foot passes into the lower leg


@dataclass(frozen=True, eq=False)
class JointTargets:
    """Set-points of the twelve joint servos for one control period (held until the next).

    The servo applies ``kp (q - q_meas) + kd (qd - qd_meas) + torque``.
    """

    q: np.ndarray  # (4, 3) [rad] joint angles
    qd: np.ndarray  # (4, 3) [rad/s] joint velocities
    torque: np.ndarray | None  # (4, 3) [N m] feed-forward torques; None: none
