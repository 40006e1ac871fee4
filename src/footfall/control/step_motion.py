"""A step's body motion: the COG trajectory and the desired body pose at every control period.

From where the feet stand and the footstep plan, the COG planner
(:mod:`footfall.control.cog`) gives the body's horizontal path through the
support triangles of the next steps, and the pose finder
(:mod:`footfall.control.pose_finder`) the body height and attitude for the
stance after touch-down; :func:`body_motion` samples both at the control
rate, from the start of the shift to the planned touch-down.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from footfall.control.cog import CogConfig, CogTrajectory, plan_cog, support_margin
from footfall.control.footstep import FootstepPlan
from footfall.control.lowlevel import transfer_weight
from footfall.control.pose_finder import PoseConfig, find_pose
from footfall.core.heightmap import HeightMap
from footfall.core.robot import RobotDescription


@dataclass(frozen=True, eq=False)
class BodyMotion:
    """The body's plan for one step, sampled at the control periods of its shift and swing."""

    traj: CogTrajectory  # the COG trajectory (its lift_off[0], touch_down[0] [s]: this step's)
    times: np.ndarray  # (n,) [s] from the start of the shift, one per control period
    positions: np.ndarray  # (n, 3) [m] desired body positions at those times
    attitudes: np.ndarray  # (n, 3) [rad] desired body roll, pitch, yaw at those times
    margin: float  # [m] least margin of the planned centre of mass inside the swing triangle


def body_motion(hmap: HeightMap, feet: np.ndarray, s: int, plan: FootstepPlan,
                cog: tuple[np.ndarray, np.ndarray], desired: tuple[np.ndarray, np.ndarray],
                period: float, cog_config: CogConfig, pose_config: PoseConfig,
                robot: RobotDescription) -> BodyMotion:
    """The body motion of the step of leg ``s`` (a LEG_NAMES index).

    Parameters
    ----------
    hmap : HeightMap
    feet : ndarray (4, 3)
        Contact points [m] of the feet where they stand now.
    s : int
        The swing leg.
    plan : FootstepPlan
        The footstep plan of this step and the next.
    cog : (ndarray (2,), ndarray (2,))
        Planned centre-of-mass position [m] and velocity [m/s] now.
    desired : (ndarray (3,), ndarray (3,))
        Desired body position [m] and roll, pitch, yaw [rad] now: the motion starts here.
    period : float
        [s] control period.
    """
    traj = plan_cog(feet, plan.steps, cog[0], cog[1], cog_config, robot)
    after = feet.copy()
    after[s] = plan.foothold
    pose = find_pose(hmap, after, traj.waypoints[0, 1], float(plan.body_yaw[0]), robot,
                     pose_config)
    t_lift, t_down = float(traj.lift_off[0]), float(traj.touch_down[0])
    margin = float(np.min(support_margin(traj.triangles[0],
                                         traj.position(np.linspace(t_lift, t_down, 20)))))
    n = max(1, round(t_down / period))
    times = np.minimum(np.arange(1, n + 1) * period, t_down)
    u = transfer_weight(times, t_down)[:, None]  # smoothstep from this pose to the next
    z0, rpy0 = desired[0][2], desired[1]
    rpy1 = np.array(pose.rpy)
    rpy1[2] = rpy0[2] + ((rpy1[2] - rpy0[2] + np.pi) % (2 * np.pi) - np.pi)
    positions = np.column_stack([traj.position(times), z0 + (pose.height - z0) * u[:, 0]])
    attitudes = rpy0 + (rpy1 - rpy0) * u
    return BodyMotion(traj, times, positions, attitudes, margin)
