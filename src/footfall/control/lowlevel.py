"""Low-level control (paper §IV-B.6): from body and foot trajectories to joint set-points.

Every control period (100 Hz) the desired body pose and the desired world
positions of the four ball-foot centres become joint angle set-points by
the closed-form inverse kinematics of each leg; the robot's PD servo
(400 Hz, in the simulator) tracks them. The loop is closed at 100 Hz on the
true body pose (motion capture on the real robot, the simulator here), in
two ways:

* the swing foot's target is expressed in the *measured* body frame, so the
  foot goes where the world target is even when the body is off its plan;
* the stance legs, which move the body, are commanded for a body pose that
  is the desired one plus an integral of the pose error (``BodyCorrection``),
  which removes the steady sag and lean of a compliant PD servo under load.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from footfall.errors import FootfallError
from footfall.kinematics import inverse_kinematics, world_to_body
from footfall.robot import RobotDescription


@dataclass(frozen=True)
class LowLevelConfig:
    """Gains and limits of the 100 Hz closed loop."""

    period: float = 0.01  # [s] set-point period (paper: 100 Hz)
    position_gain: float = 0.2  # [-] share of the body position error added to the correction per period
    attitude_gain: float = 0.2  # [-] share of the roll / pitch error added per period
    max_position_correction: float = 0.03  # [m] bound of the accumulated position correction
    max_attitude_correction: float = 0.2  # [rad] bound of the accumulated roll / pitch correction

    def __post_init__(self) -> None:
        if not self.period > 0:
            raise FootfallError(f"low-level period must be > 0 s, got {self.period}")
        for name in ("position_gain", "attitude_gain"):
            if not 0 <= getattr(self, name) <= 1:
                raise FootfallError(f"low-level {name} must be in [0, 1]")
        for name in ("max_position_correction", "max_attitude_correction"):
            if not getattr(self, name) >= 0:
                raise FootfallError(f"low-level {name} must be >= 0")


class BodyCorrection:
    """Integral correction of the commanded body pose from the measured one (100 Hz).

    ``update(desired, measured)`` accumulates ``gain * (desired - measured)``
    for the height, roll and pitch -- what a compliant servo loses under load
    -- bounded, and returns the pose to command: desired + correction.
    """

    def __init__(self, config: LowLevelConfig) -> None:
        self.config = config
        self.position = np.zeros(3)  # [m]
        self.attitude = np.zeros(2)  # [rad] roll, pitch

    def update(self, desired_position: np.ndarray, desired_rpy: np.ndarray,
               measured_position: np.ndarray, measured_rpy: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """Commanded body position (3,) [m] and roll, pitch, yaw (3,) [rad]."""
        c = self.config
        error = np.asarray(desired_position) - measured_position
        error[:2] = 0.0  # the horizontal position follows the COG plan open loop: an
        # integral on a moving reference only adds overshoot; height is what the servo loses
        self.position = np.clip(self.position + c.position_gain * error,
                                -c.max_position_correction, c.max_position_correction)
        err = desired_rpy[:2] - measured_rpy[:2]
        err = (err + np.pi) % (2 * np.pi) - np.pi
        self.attitude = np.clip(self.attitude + c.attitude_gain * err,
                                -c.max_attitude_correction, c.max_attitude_correction)
        rpy = np.array([desired_rpy[0] + self.attitude[0], desired_rpy[1] + self.attitude[1],
                        desired_rpy[2]])
        return desired_position + self.position, rpy


def joint_targets(robot: RobotDescription, feet_world: np.ndarray, stance_position: np.ndarray,
                  stance_rpy: np.ndarray, swing: int | None, measured_position: np.ndarray,
                  measured_rpy: np.ndarray, previous: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint set-points (4, 3) [rad] that put the ball-foot centres at ``feet_world`` (4, 3) [m].

    Stance legs are solved in the commanded body frame (``stance_position``,
    ``stance_rpy``); the swing leg ``swing`` (index in LEG_NAMES, or None)
    in the measured one. A foot out of reach keeps its ``previous``
    set-points (4, 3). Returns the set-points and a (4,) bool of the legs
    that were reachable.
    """
    feet_world = np.asarray(feet_world, dtype=np.float64)
    local = world_to_body(feet_world, stance_position, stance_rpy)
    if swing is not None:
        local[swing] = world_to_body(feet_world[swing], measured_position, measured_rpy)
    q = np.array(previous, dtype=np.float64, copy=True)
    ok = np.zeros(4, dtype=bool)
    for k, leg in enumerate(robot.legs):  # four legs, each its own closed form
        qk, okk = inverse_kinematics(leg, local[k], robot)
        if okk:
            q[k] = qk
            ok[k] = True
    return q, ok
