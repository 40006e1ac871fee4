"""How far a lower leg stands off the terrain: its knee and shin against the map's sphere surface.

The lower leg is a capsule of ``lower_leg_radius`` from the knee axis down to
where it meets the ball foot. Spheres of that radius are set along it, from
the knee to the ball, and each is compared with the map's sphere surface of
the same radius (:func:`footfall.core.sphere_surface.board_sphere`): the
height at which such a sphere lowered onto the map would come to rest. A
sample's clearance is its centre's height above that rest height -- 0 where
the shin touches the terrain, negative where it would cut into it -- so a
shin beside a wall is seen as well as one above a rock. The synthetic expert
weighs a foothold by it (:func:`footfall.expert.terms.leg_terms`), and the
footstep planner drops footholds whose leg would lean on the terrain over
the coming stance (``FootstepConfig.leg_clearance``).
"""

from __future__ import annotations

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import RobotDescription
from footfall.core.sphere_surface import board_sphere, sample_surface


def shin_fractions(robot: RobotDescription, samples: int, span: float | None = None
                   ) -> np.ndarray:
    """Where the samples lie (samples,) [-] of the way from the knee axis (0) to the ball's
    centre (1): down to ``span``, or (None) to where the shin meets the ball foot (one ball
    and one shin radius short of the ball's centre)."""
    end = 1.0 - (robot.foot_radius + robot.lower_leg_radius) / robot.lower_leg
    return np.linspace(0.0, end if span is None else min(float(span), end), int(samples))


def leg_gaps(hmap: HeightMap, knee: np.ndarray, centre: np.ndarray, robot: RobotDescription,
             samples: int, span: float | None = None) -> np.ndarray:
    """Least clearance [m] of the lower legs from ``knee`` (n, 3) to the ball centres
    ``centre`` (n, 3) [m] (world frame) above the terrain, (n,), over the part of each
    down to ``span`` (:func:`shin_fractions`).

    Samples with no data below them are no obstacle (inf); a leg with a non-finite point
    (no posture) is inf too -- the caller decides what that means.
    """
    t = shin_fractions(robot, samples, span)
    spheres = knee[:, None, :] + t[None, :, None] * (centre - knee)[:, None, :]  # (n, S, 3)
    ground = sample_surface(board_sphere(hmap, robot.lower_leg_radius),
                            np.nan_to_num(spheres[..., :2]))
    return np.where(np.isnan(ground), np.inf, spheres[..., 2] - ground).min(axis=1)
