"""What passes between the controller and the robot: measurements in, joint targets out.

A real LittleDog's controller reads, every control period (100 Hz), its joint
encoders, the body pose from motion capture and its three-axis foot force
sensors, and answers with set-points for the joint servos. These two types
are that interface; the controller (:mod:`footfall.control.controller`) sees
the robot only through :class:`Measurements`, and the simulator
(:mod:`footfall.sim.episode`) only through :class:`JointTargets`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Measurements:
    """One control period's readings of the robot's sensors.

    The foot positions, centre of mass and foot Jacobians are passed in as the
    simulator computed them (stage 1 of the controller split: the same numbers
    the controller has always read); the foot force sensors are read at each call.
    """

    time: float  # [s] since the run began
    joint_angles: np.ndarray  # (4, 3) [rad] encoders, LEG_NAMES x (hip roll, hip pitch, knee)
    body_position: np.ndarray  # (3,) [m] trunk origin, world frame (motion capture)
    body_rpy: np.ndarray  # (3,) [rad] trunk roll, pitch, yaw, Z-Y-X (motion capture)
    read_forces: Callable[[], np.ndarray]  # () -> (4, 3) [N] foot force sensors, world frame
    foot_positions: np.ndarray  # (4, 3) [m] ball-foot centres, world frame
    centre_of_mass: np.ndarray  # (3,) [m] whole robot, world frame
    foot_jacobians: Callable[[], np.ndarray]  # () -> (4, 3, 3) [m/rad] of the foot centres


@dataclass(frozen=True, eq=False)
class JointTargets:
    """Set-points of the twelve joint servos for one control period (held until the next).

    The servo applies ``kp (q - q_meas) + kd (qd - qd_meas) + torque``.
    """

    q: np.ndarray  # (4, 3) [rad] joint angles
    qd: np.ndarray  # (4, 3) [rad/s] joint velocities
    torque: np.ndarray | None  # (4, 3) [N m] feed-forward torques; None: none
