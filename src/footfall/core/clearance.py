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

import math

import numba
import numpy as np

from footfall.core.bilinear import surface_point
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import hip_frame, leg_angles, rotation3
from footfall.core.robot import Leg, RobotDescription
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


def posed_leg_gaps(hmap: HeightMap, leg: Leg, centre: np.ndarray, body_position: np.ndarray,
                   body_rpy: np.ndarray, robot: RobotDescription, samples: int,
                   span: float | None = None) -> np.ndarray:
    """Least clearance [m] (n,) of ``leg``'s knee and shin above the terrain with its ball
    centre on each of ``centre`` (n, 3) [m] (world frame), the body at ``body_position`` (3,)
    [m] and ``body_rpy`` (3,) [rad]: the leg's closed-form inverse kinematics, its knee, and
    :func:`leg_gaps` of the lower leg down to ``span``, in one compiled pass
    (:func:`_posed_kernel`; the footstep planner asks it of a few hundred footholds at two
    poses a step). NaN where the leg has no posture for the point (out of reach); inf where
    no sample has terrain data below it."""
    surface = board_sphere(hmap, robot.lower_leg_radius)
    points = np.ascontiguousarray(centre, dtype=np.float64).reshape(-1, 3)
    if surface is None:  # a map without data: every reachable point inf, the others NaN
        filled, known, origin, res, complete = (np.zeros((2, 2)), np.zeros((2, 2)),
                                                np.array([np.nan, np.nan]), 1.0, False)
    else:
        filled, known, origin, res, complete = (surface.filled, surface.known, surface.origin,
                                                surface.resolution, surface.complete)
    return _posed_kernel(points, np.asarray(body_position, dtype=np.float64),
                         np.asarray(body_rpy, dtype=np.float64),
                         np.asarray(leg.hip, dtype=np.float64), leg.side * robot.hip_offset,
                         1.0 if leg.knee_forward else -1.0, robot.upper_leg,
                         robot.lower_leg, robot.hip_offset, shin_fractions(robot, samples, span),
                         filled, known, float(origin[0]), float(origin[1]), float(res),
                         bool(complete))


@numba.njit(cache=True, nogil=True)
def _posed_kernel(points, body, rpy, hip, side, knee_sign, l1, l2, d, t, filled, known, ox, oy,
                  res, complete):  # pragma: no cover - compiled
    """:func:`posed_leg_gaps`: the hip frame of :func:`~footfall.core.kinematics.hip_frame`,
    the angles of :func:`~footfall.core.kinematics.leg_angles`, the knee of
    :func:`~footfall.core.kinematics.knee_position` back in the world frame, and the samples of
    :func:`leg_gaps`, point by point."""
    rot = rotation3(rpy)
    n = points.shape[0]
    out = np.empty(n)
    for i in range(n):
        cx, cy, cz = points[i, 0], points[i, 1], points[i, 2]
        px, py, pz = hip_frame(rot, body, hip, cx, cy, cz)
        q1, q2, q3, _ = leg_angles(px, py, pz, side, knee_sign, l1, l2, d)
        if not (math.isfinite(q1) and math.isfinite(q2) and math.isfinite(q3)):
            out[i] = np.nan
            continue
        kx, kz = -l1 * math.sin(q2), -l1 * math.cos(q2)  # the knee in the leg's plane
        c, s = math.cos(q1), math.sin(q1)
        bx, by, bz = kx + hip[0], c * side - s * kz + hip[1], s * side + c * kz + hip[2]
        wx = bx * rot[0, 0] + by * rot[0, 1] + bz * rot[0, 2] + body[0]
        wy = bx * rot[1, 0] + by * rot[1, 1] + bz * rot[1, 2] + body[1]
        wz = bx * rot[2, 0] + by * rot[2, 1] + bz * rot[2, 2] + body[2]
        least = np.inf
        for j in range(t.shape[0]):
            sx = wx + t[j] * (cx - wx)
            sy = wy + t[j] * (cy - wy)
            ground = surface_point(filled, known, ox, oy, res, complete, sx, sy)
            if not np.isnan(ground):
                least = min(least, wz + t[j] * (cz - wz) - ground)
        out[i] = least
    return out
