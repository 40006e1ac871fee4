"""Closed-form forward and inverse kinematics of a 3-joint leg, and body poses.

Pure, vectorised functions: every function takes arrays of any leading shape.
Leg geometry (see :mod:`footfall.core.robot`): the hip roll joint turns about the
body's x axis at the hip; the upper leg hangs ``hip_offset`` further out
along the rolled y axis; hip pitch and knee turn about that rolled y axis.
In the leg's sagittal plane the foot centre is at

    x = -L1 sin(q2) - L2 sin(q2 + q3),   z = -L1 cos(q2) - L2 cos(q2 + q3),

and the roll rotates the plane about the hip's x axis.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numba
import numpy as np

from footfall.core.robot import Leg, RobotDescription


def rotation_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrices from roll, pitch, yaw [rad] (Z-Y-X order), (..., 3) -> (..., 3, 3).

    ``R @ v_body`` gives the world-frame vector: R = Rz(yaw) Ry(pitch) Rx(roll).
    """
    rpy = np.asarray(rpy, dtype=np.float64)
    cr, cp, cy = np.cos(rpy[..., 0]), np.cos(rpy[..., 1]), np.cos(rpy[..., 2])
    sr, sp, sy = np.sin(rpy[..., 0]), np.sin(rpy[..., 1]), np.sin(rpy[..., 2])
    row0 = np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1)
    row1 = np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1)
    row2 = np.stack([-sp, cp * sr, cp * cr], axis=-1)
    return np.stack([row0, row1, row2], axis=-2)


def world_to_body(points: np.ndarray, body_position: np.ndarray, body_rpy: np.ndarray) -> np.ndarray:
    """World points [m] (..., 3) expressed in the body frame of a pose."""
    rot = rotation_matrix(body_rpy)
    return (np.asarray(points, dtype=np.float64) - np.asarray(body_position)) @ rot


def body_to_world(points: np.ndarray, body_position: np.ndarray, body_rpy: np.ndarray) -> np.ndarray:
    """Body-frame points [m] (..., 3) expressed in the world frame."""
    rot = rotation_matrix(body_rpy)
    return np.asarray(points, dtype=np.float64) @ rot.T + np.asarray(body_position)


def _planar(q2: np.ndarray, q3: np.ndarray, robot: RobotDescription) -> tuple[np.ndarray, ...]:
    l1, l2 = robot.upper_leg, robot.lower_leg
    knee_x, knee_z = -l1 * np.sin(q2), -l1 * np.cos(q2)
    foot_x = knee_x - l2 * np.sin(q2 + q3)
    foot_z = knee_z - l2 * np.cos(q2 + q3)
    return knee_x, knee_z, foot_x, foot_z


def _roll(q1: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray, hip: tuple) -> np.ndarray:
    c, s = np.cos(q1), np.sin(q1)
    return np.stack([x + hip[0], c * y - s * z + hip[1], s * y + c * z + hip[2]], axis=-1)


def forward_kinematics(leg: Leg, q: np.ndarray, robot: RobotDescription) -> np.ndarray:
    """Foot-centre position [m] in the body frame from joint angles [rad], (..., 3) -> (..., 3)."""
    q = np.asarray(q, dtype=np.float64)
    _, _, fx, fz = _planar(q[..., 1], q[..., 2], robot)
    return _roll(q[..., 0], fx, np.full_like(fx, leg.side * robot.hip_offset), fz, leg.hip)


def knee_position(leg: Leg, q: np.ndarray, robot: RobotDescription) -> np.ndarray:
    """Knee-axis position [m] in the body frame from joint angles [rad], (..., 3) -> (..., 3)."""
    q = np.asarray(q, dtype=np.float64)
    kx, kz, _, _ = _planar(q[..., 1], q[..., 2], robot)
    return _roll(q[..., 0], kx, np.full_like(kx, leg.side * robot.hip_offset), kz, leg.hip)


def inverse_kinematics(leg: Leg, foot: np.ndarray, robot: RobotDescription
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles [rad] that put the foot centre at ``foot`` [m] (body frame).

    Closed form, with the knee branch of the leg (``leg.knee_forward``) and
    the leg hanging below its roll axis. Returns ``(q, ok)``: ``q`` of shape
    (..., 3) (NaN where no solution exists) and ``ok`` (...) true where the
    point is in the workspace and every joint is within its limits.
    """
    p = np.asarray(foot, dtype=np.float64) - np.asarray(leg.hip)
    q, reached = _ik_angles(p, leg.side * robot.hip_offset,
                            1.0 if leg.knee_forward else -1.0, robot)
    return q, reached & within_limits(leg, q)


def _ik_angles(p: np.ndarray, side: float | np.ndarray, knee: float | np.ndarray,
               robot: RobotDescription) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles [rad] (..., 3) putting foot centres ``p`` (..., 3) [m], relative to the hip,
    on a leg whose upper leg hangs ``side`` [m] out along y (``leg.side * hip_offset``) with knee
    sign ``knee`` (+1: forward); and whether each is within reach (...), limits not checked.

    ``side`` and ``knee`` broadcast against ``p``'s leading shape (one leg, or every leg at once).
    NaN angles where there is no solution. Compiled (:func:`_ik_kernel`): the footstep planner
    and the pose finder solve thousands of points a step, and the controller four a period.
    """
    p = np.asarray(p, dtype=np.float64)
    lead = p.shape[:-1]
    flat = np.ascontiguousarray(p).reshape(-1, 3)
    sides = np.ascontiguousarray(np.broadcast_to(side, lead), dtype=np.float64).reshape(-1)
    knees = np.ascontiguousarray(np.broadcast_to(knee, lead), dtype=np.float64).reshape(-1)
    q, reached = _ik_kernel(flat, sides, knees, robot.upper_leg, robot.lower_leg,
                            robot.hip_offset)
    return q.reshape(p.shape), reached.reshape(lead)


@numba.njit(cache=True, nogil=True, inline="always")
def leg_angles(px, py, pz, side, knee, l1, l2, d):  # pragma: no cover - compiled
    """The closed-form inverse kinematics of one foot centre (px, py, pz) [m] relative to the
    hip, compiled: the one copy every kernel calls (:func:`_ik_angles` documents it).

    ``side`` [m] is ``leg.side * hip_offset``, ``knee`` +1 forward / -1 back, ``l1``, ``l2``
    [m] the upper and lower leg, ``d`` [m] the hip offset. Returns (q1, q2, q3) [rad] and
    whether the point is within reach; q1 is NaN out of the roll plane's reach, q2 and q3
    NaN out of the leg's length."""
    pi, tau = np.pi, 2 * np.pi
    rho2 = py * py + pz * pz - d * d
    in_plane = rho2 >= 0
    zp = -math.sqrt(rho2) if in_plane else np.nan
    q1 = (math.atan2(pz, py) - math.atan2(zp, side) + pi) % tau - pi
    c3 = (px * px + zp * zp - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    reach = abs(c3) <= 1.0
    q3 = (math.acos(c3) if reach else np.nan) * knee
    q2 = (math.atan2(-px, -zp) - math.atan2(l2 * math.sin(q3), l1 + l2 * math.cos(q3))
          + pi) % tau - pi
    return q1, q2, q3, in_plane and reach


@numba.njit(cache=True, nogil=True)
def _ik_kernel(p, side, knee, l1, l2, d):  # pragma: no cover - compiled
    """:func:`_ik_angles` of points ``p`` (n, 3) [m] with ``side`` (n,) [m], ``knee`` (n,)."""
    n = p.shape[0]
    q = np.empty((n, 3))
    reached = np.empty(n, dtype=np.bool_)
    for i in range(n):
        q[i, 0], q[i, 1], q[i, 2], reached[i] = leg_angles(p[i, 0], p[i, 1], p[i, 2], side[i],
                                                           knee[i], l1, l2, d)
    return q, reached


def reaches_points(leg: Leg, points: np.ndarray, body_position: np.ndarray,
                   body_rpy: np.ndarray, robot: RobotDescription) -> np.ndarray:
    """Whether ``leg`` reaches the world foot centres ``points`` (n, 3) [m] within its joint
    limits, the body at ``body_position`` (3,) [m] and ``body_rpy`` (3,) [rad]: (n,) bool.

    :func:`inverse_kinematics` of :func:`world_to_body`'s points, in one compiled pass
    (:func:`_reach_kernel`; the footstep planner asks it of thousands of points a step)."""
    lo, hi = _limit_arrays(leg.limits)
    return _reach_kernel(np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3),
                         np.asarray(body_position, dtype=np.float64),
                         np.asarray(body_rpy, dtype=np.float64),
                         np.asarray(leg.hip, dtype=np.float64), leg.side * robot.hip_offset,
                         1.0 if leg.knee_forward else -1.0, robot.upper_leg, robot.lower_leg,
                         robot.hip_offset, lo, hi)


@numba.njit(cache=True, nogil=True, inline="always")
def rotation3(rpy):  # pragma: no cover - compiled
    """:func:`rotation_matrix` of one roll, pitch, yaw (3,) [rad], compiled: (3, 3)."""
    cr, cp, cy = math.cos(rpy[0]), math.cos(rpy[1]), math.cos(rpy[2])
    sr, sp, sy = math.sin(rpy[0]), math.sin(rpy[1]), math.sin(rpy[2])
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


@numba.njit(cache=True, nogil=True, inline="always")
def hip_frame(rot, body, hip, x, y, z):  # pragma: no cover - compiled
    """The world point (x, y, z) [m] relative to the hip ``hip`` (3,) [m] in the body frame of
    a body at ``body`` (3,) [m] turned by ``rot`` (:func:`rotation3`): :func:`world_to_body`
    less the hip, compiled."""
    v0, v1, v2 = x - body[0], y - body[1], z - body[2]
    return (v0 * rot[0, 0] + v1 * rot[1, 0] + v2 * rot[2, 0] - hip[0],
            v0 * rot[0, 1] + v1 * rot[1, 1] + v2 * rot[2, 1] - hip[1],
            v0 * rot[0, 2] + v1 * rot[1, 2] + v2 * rot[2, 2] - hip[2])


@numba.njit(cache=True, nogil=True)
def _reach_kernel(points, body, rpy, hip, side, knee, l1, l2, d, lo, hi
                  ):  # pragma: no cover - compiled
    """:func:`reaches_points`: the rotation of :func:`rotation_matrix`, the closed form of
    :func:`_ik_angles`, the limits of :func:`within_limits`, point by point.

    A point farther from the hip than any foot can be -- |p|^2 > d^2 + (l1 + l2)^2, where the
    closed form's knee cosine exceeds 1 -- is not reached, and is told so without the
    trigonometry (with a margin of 1e-9 of that bound, far beyond rounding, so that no
    answer changes: the lattice around the hip is mostly such points)."""
    rot = rotation3(rpy)
    out = np.zeros(points.shape[0], dtype=np.bool_)
    far = (d * d + (l1 + l2) * (l1 + l2)) * (1.0 + 1e-9)
    for i in range(points.shape[0]):
        px, py, pz = hip_frame(rot, body, hip, points[i, 0], points[i, 1], points[i, 2])
        if px * px + py * py + pz * pz > far:
            continue
        q1, q2, q3, ok = leg_angles(px, py, pz, side, knee, l1, l2, d)
        if not ok:
            continue
        out[i] = (lo[0] <= q1 <= hi[0]) and (lo[1] <= q2 <= hi[1]) and (lo[2] <= q3 <= hi[2])
    return out


@lru_cache(maxsize=64)
def _limit_arrays(limits: tuple[tuple[float, float], ...]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper joint limits (3,) [rad] of a leg's limits, made once per distinct leg."""
    lo, hi = np.array(limits, dtype=np.float64).T.copy()
    lo.flags.writeable = hi.flags.writeable = False  # shared between callers
    return lo, hi


def within_limits(leg: Leg, q: np.ndarray) -> np.ndarray:
    """Whether joint angles [rad] (..., 3) are all within the leg's limits (NaN: false)."""
    q = np.asarray(q, dtype=np.float64)
    lo, hi = _limit_arrays(leg.limits)
    with np.errstate(invalid="ignore"):
        return np.all((q >= lo) & (q <= hi), axis=-1)


def joint_limit_margin(leg: Leg, q: np.ndarray) -> np.ndarray:
    """Smallest distance [rad] of any joint from its nearest limit, (..., 3) -> (...).

    Negative outside the limits; NaN where ``q`` is NaN.
    """
    q = np.asarray(q, dtype=np.float64)
    lo = np.array([lim[0] for lim in leg.limits])
    hi = np.array([lim[1] for lim in leg.limits])
    return np.min(np.minimum(q - lo, hi - q), axis=-1)


# ------------------------------------------------------- all four legs at once
@lru_cache(maxsize=8)
def _leg_arrays(robot: RobotDescription) -> tuple[np.ndarray, ...]:
    """The legs' hips (4, 3) [m], ``side * hip_offset`` (4,) [m], knee signs (4,) [-] and
    joint limits lower, upper (4, 3) [rad], in ``robot.legs`` order (made once per robot)."""
    hips = np.array([leg.hip for leg in robot.legs], dtype=np.float64)
    side = np.array([leg.side * robot.hip_offset for leg in robot.legs], dtype=np.float64)
    knee = np.array([1.0 if leg.knee_forward else -1.0 for leg in robot.legs])
    lo, hi = (np.array([[lim[i] for lim in leg.limits] for leg in robot.legs], dtype=np.float64)
              for i in (0, 1))
    for a in (hips, side, knee, lo, hi):
        a.flags.writeable = False  # shared between callers
    return hips, side, knee, lo, hi


def legs_inverse_kinematics(robot: RobotDescription, foot: np.ndarray
                            ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`inverse_kinematics` of every leg at once: foot centres (..., 4, 3) [m] (body frame,
    ``robot.legs`` order) -> angles (..., 4, 3) [rad] (NaN: no solution) and ``ok`` (..., 4).

    The same element-wise operations as the one-leg function with each leg's
    hip, side, knee branch and limits broadcast over the leg axis, so the
    very same numbers, in a quarter of the NumPy calls.
    """
    hips, side, knee, lo, hi = _leg_arrays(robot)
    q, reached = _ik_angles(np.asarray(foot, dtype=np.float64) - hips, side, knee, robot)
    with np.errstate(invalid="ignore"):
        ok = reached & np.all((q >= lo) & (q <= hi), axis=-1)
    return q, ok


def _legs_point(robot: RobotDescription, q: np.ndarray, knee: bool) -> np.ndarray:
    """Knees (``knee``) or foot centres (..., 4, 3) [m], body frame, of angles (..., 4, 3) [rad]."""
    hips, side, _, _, _ = _leg_arrays(robot)
    q = np.asarray(q, dtype=np.float64)
    kx, kz, fx, fz = _planar(q[..., 1], q[..., 2], robot)
    x, z = (kx, kz) if knee else (fx, fz)
    return _roll(q[..., 0], x, np.broadcast_to(side, x.shape), z,
                 (hips[:, 0], hips[:, 1], hips[:, 2]))


def legs_knee_position(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """:func:`knee_position` of every leg at once: angles (..., 4, 3) [rad] -> (..., 4, 3) [m]."""
    return _legs_point(robot, q, knee=True)


def legs_joint_limit_margin(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """:func:`joint_limit_margin` of every leg at once: (..., 4, 3) [rad] -> (..., 4) [rad]."""
    _, _, _, lo, hi = _leg_arrays(robot)
    q = np.asarray(q, dtype=np.float64)
    return np.min(np.minimum(q - lo, hi - q), axis=-1)


def legs_forward_kinematics(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """:func:`forward_kinematics` of every leg at once: angles (..., 4, 3) [rad] -> foot centres
    (..., 4, 3) [m], body frame, ``robot.legs`` order."""
    return _legs_point(robot, q, knee=False)


def legs_jacobians(robot: RobotDescription, q: np.ndarray) -> np.ndarray:
    """Jacobians (..., 4, 3, 3) [m/rad] of the foot centres (body frame) in their own legs'
    joint angles (..., 4, 3) [rad]: ``J[..., i, :, j]`` is how far foot i moves per radian of
    its joint j (hip roll, hip pitch, knee).

    Analytic: hip pitch and knee move the foot in the leg's plane, ``d(x, z)/dq2 = (z, -x)``
    of the foot from the hip pitch axis and ``d(x, z)/dq3 = (z, -x)`` of the foot from the
    knee; the hip roll turns the rolled plane about the body's x axis.
    """
    _, side, _, _, _ = _leg_arrays(robot)
    q = np.asarray(q, dtype=np.float64)
    l1, l2 = robot.upper_leg, robot.lower_leg
    q1, q2, q23 = q[..., 0], q[..., 1], q[..., 1] + q[..., 2]
    c1, s1 = np.cos(q1), np.sin(q1)
    below_x, below_z = -l2 * np.sin(q23), -l2 * np.cos(q23)  # the foot from the knee
    fx, fz = -l1 * np.sin(q2) + below_x, -l1 * np.cos(q2) + below_z  # from the hip pitch axis
    y = np.broadcast_to(side, fx.shape)
    jac = np.empty(q.shape + (3,))
    jac[..., 0, 0] = 0.0
    jac[..., 1, 0] = -s1 * y - c1 * fz
    jac[..., 2, 0] = c1 * y - s1 * fz
    for j, (dx, dz) in ((1, (fz, -fx)), (2, (below_z, -below_x))):
        jac[..., 0, j] = dx
        jac[..., 1, j] = -s1 * dz
        jac[..., 2, j] = c1 * dz
    return jac
