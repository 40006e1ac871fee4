"""What the controller knows of its body in one control period, from its measurements.

:class:`BodyEstimate` holds the measured joint angles and body pose, and the
quantities the controller works with: the ball-foot centres, the centre of
mass, the foot force readings in the world frame and the feet's Jacobians.
"""

from __future__ import annotations

import numpy as np

from footfall.control.measurements import Measurements
from footfall.core.robot import RobotDescription


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
    feet : ndarray of shape (4, 3)
        Ball-foot centres [m], world frame.
    com : ndarray of shape (3,)
        Centre of mass [m], world frame.
    """

    def __init__(self, m: Measurements, robot: RobotDescription) -> None:
        self.time = m.time
        self.q = m.joint_angles
        self.pose = (m.body_position, m.body_rpy)
        self.feet = m.foot_positions
        self.com = m.centre_of_mass
        self._m = m

    def forces(self) -> np.ndarray:
        """Foot force sensor readings (4, 3) [N], world frame, +z for a foot pressed down."""
        return self._m.read_forces()

    def jacobians(self) -> np.ndarray:
        """Jacobians (4, 3, 3) [m/rad] of the foot centres (world frame) in their legs' joints."""
        return self._m.foot_jacobians()
