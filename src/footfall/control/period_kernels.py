"""The control period's kinematics of one pose, compiled: four legs at 100 Hz.

Every control period the controller turns the measured attitude into a
matrix, works out where its feet and centre of mass are, how far each
stance ball has rolled, and solves the four legs' inverse kinematics. On a
few dozen numbers NumPy's per-call overhead is nearly all the cost, and
Python floats were still a third of the period; these kernels do the same
arithmetic, operation for operation, compiled (Numba). Each is called by
the function that documents it:

* :func:`rotation` -- :func:`footfall.control.lowlevel.body_rotation`;
* :func:`shins` -- :func:`footfall.control.lowlevel.shin_rotations`;
* :func:`rolled_few` -- :func:`footfall.control.lowlevel.rolled` for a few feet;
* :func:`points` and :func:`jacobians` --
  :func:`footfall.control.estimate.body_points`, ``body_jacobians``;
* :func:`solve_legs` -- :func:`footfall.control.lowlevel.joint_targets`' closed form
  (:func:`footfall.core.kinematics.leg_angles`, the one copy of it).

Angles in radians, lengths in metres, like their callers.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from footfall.core.kinematics import leg_angles


@numba.njit(cache=True, nogil=True)
def rotation(roll, pitch, yaw):  # pragma: no cover - compiled
    """The body's rotation matrix (3, 3) from roll, pitch, yaw [rad] (Z-Y-X), by MuJoCo's
    ``mju_euler2Quat`` (intrinsic z, y, x) then ``mju_quat2Mat``, one operation for one."""
    w, x, y, z = 1.0, 0.0, 0.0, 0.0
    for turn in range(3):  # each turn about a moving axis: yaw (z), pitch (y), roll (x)
        angle = yaw if turn == 0 else (pitch if turn == 1 else roll)
        c, s = math.cos(angle / 2), math.sin(angle / 2)
        b1 = s if turn == 2 else 0.0
        b2 = s if turn == 1 else 0.0
        b3 = s if turn == 0 else 0.0
        w, x, y, z = (w * c - x * b1 - y * b2 - z * b3,
                      w * b1 + x * c + y * b3 - z * b2,
                      w * b2 - x * b3 + y * c + z * b1,
                      w * b3 + x * b2 - y * b1 + z * c)
    out = np.empty((3, 3))
    if w == 1 and x == 0 and y == 0 and z == 0:
        out[:] = 0.0
        out[0, 0] = out[1, 1] = out[2, 2] = 1.0
        return out
    ww, wx, wy, wz = w * w, w * x, w * y, w * z
    xx, xy, xz, yy, yz, zz = x * x, x * y, x * z, y * y, y * z, z * z
    out[0, 0], out[0, 1], out[0, 2] = ww + xx - yy - zz, 2 * (xy - wz), 2 * (xz + wy)
    out[1, 0], out[1, 1], out[1, 2] = 2 * (xy + wz), ww - xx + yy - zz, 2 * (yz - wx)
    out[2, 0], out[2, 1], out[2, 2] = 2 * (xz - wy), 2 * (yz + wx), ww - xx - yy + zz
    return out


@numba.njit(cache=True, nogil=True)
def shins(q, body):  # pragma: no cover - compiled
    """World orientations (4, 3, 3) of the lower legs from joint angles ``q`` (4, 3) [rad] and
    the body's rotation ``body`` (3, 3): ``body @ Rx(q1) Ry(q2 + q3)`` per leg."""
    out = np.empty((q.shape[0], 3, 3))
    leg = np.empty((3, 3))
    for k in range(q.shape[0]):
        c1, s1 = math.cos(q[k, 0]), math.sin(q[k, 0])
        pitch = q[k, 1] + q[k, 2]
        c2, s2 = math.cos(pitch), math.sin(pitch)
        leg[0, 0], leg[0, 1], leg[0, 2] = c2, 0.0, s2
        leg[1, 0], leg[1, 1], leg[1, 2] = s1 * s2, c1, -s1 * c2
        leg[2, 0], leg[2, 1], leg[2, 2] = -c1 * s2, s1, c1 * c2
        for i in range(3):
            for j in range(3):
                out[k, i, j] = body[i, 0] * leg[0, j] + body[i, 1] * leg[1, j] \
                    + body[i, 2] * leg[2, j]
    return out


@numba.njit(cache=True, nogil=True)
def rolled_few(start, now, radius):  # pragma: no cover - compiled
    """How far (k, 3) [m] balls of ``radius`` [m] have rolled from the orientations ``start``
    to ``now`` (k, 3, 3): ``radius * (phi_y, -phi_x, 0)`` of the rotation vector phi of
    ``now @ start^T``."""
    out = np.zeros((start.shape[0], 3))
    d = np.empty((3, 3))
    for k in range(start.shape[0]):
        for i in range(3):
            for j in range(3):
                d[i, j] = now[k, i, 0] * start[k, j, 0] + now[k, i, 1] * start[k, j, 1] \
                    + now[k, i, 2] * start[k, j, 2]
        cos = min(max(0.5 * (d[0, 0] + d[1, 1] + d[2, 2] - 1.0), -1.0), 1.0)
        sin = math.sqrt(1.0 - cos * cos)
        factor = 0.5 if sin <= 1e-9 else math.acos(cos) / max(2.0 * sin, 1e-18)
        scale = radius * factor
        out[k, 0] = scale * (d[0, 2] - d[2, 0])
        out[k, 1] = scale * (d[1, 2] - d[2, 1])
    return out


@numba.njit(cache=True, nogil=True)
def points(q, hips, parts, total):  # pragma: no cover - compiled
    """Foot centres (4, 3) [m] and centre of mass (3,) [m], body frame, from joint angles ``q``
    (4, 3) [rad]; ``hips`` (4, 4): hip x, y, z [m] and side * hip_offset [m] per leg;
    ``parts`` (p, 4): each part's distance down the upper leg [m], then the lower [m], lateral
    share of side * hip_offset [-], mass [kg], the foot last; ``total`` mass [kg]."""
    feet = np.empty((4, 3))
    cx = cy = cz = 0.0
    for k in range(4):
        c1, s1 = math.cos(q[k, 0]), math.sin(q[k, 0])
        c2, s2 = math.cos(q[k, 1]), math.sin(q[k, 1])
        c23, s23 = math.cos(q[k, 1] + q[k, 2]), math.sin(q[k, 1] + q[k, 2])
        px = py = pz = 0.0
        for i in range(parts.shape[0]):
            a, b, share, mass = parts[i, 0], parts[i, 1], parts[i, 2], parts[i, 3]
            x, z, y = -a * s2 - b * s23, -a * c2 - b * c23, share * hips[k, 3]
            px, py, pz = x + hips[k, 0], c1 * y - s1 * z + hips[k, 1], s1 * y + c1 * z + hips[k, 2]
            cx, cy, cz = cx + mass * px, cy + mass * py, cz + mass * pz
        feet[k, 0], feet[k, 1], feet[k, 2] = px, py, pz  # the last part: the foot
    com = np.empty(3)
    com[0], com[1], com[2] = cx / total, cy / total, cz / total
    return feet, com


@numba.njit(cache=True, nogil=True)
def jacobians(q, sides, l1, l2):  # pragma: no cover - compiled
    """Foot-centre Jacobians (4, 3, 3) [m/rad], body frame, from joint angles ``q`` (4, 3)
    [rad]; ``sides`` (4,) side * hip_offset [m]; ``l1``, ``l2`` upper and lower leg [m]."""
    out = np.empty((4, 3, 3))
    for k in range(4):
        c1, s1 = math.cos(q[k, 0]), math.sin(q[k, 0])
        bx, bz = -l2 * math.sin(q[k, 1] + q[k, 2]), -l2 * math.cos(q[k, 1] + q[k, 2])
        fx, fz = -l1 * math.sin(q[k, 1]) + bx, -l1 * math.cos(q[k, 1]) + bz
        side = sides[k]
        out[k, 0, 0], out[k, 0, 1], out[k, 0, 2] = 0.0, fz, bz
        out[k, 1, 0], out[k, 1, 1], out[k, 1, 2] = -s1 * side - c1 * fz, s1 * fx, s1 * bx
        out[k, 2, 0], out[k, 2, 1], out[k, 2, 2] = c1 * side - s1 * fz, -c1 * fx, -c1 * bx
    return out


@numba.njit(cache=True, nogil=True)
def solve_legs(local, legs, limits, lengths, knee, previous):  # pragma: no cover - compiled
    """The closed-form inverse kinematics of four legs stacked as one of the first leg's knee
    direction (:func:`footfall.core.kinematics.inverse_kinematics`).

    ``local`` (4, 3) [m]: the reflected body-frame targets; ``legs`` (4, 13): per leg hip x,
    y, z [m], side * hip_offset [m], the three angle flips [-], lower and upper limits (3 + 3)
    [rad]; ``limits`` (2, 3) [rad]: the stacked leg's lower and upper limits; ``lengths``:
    upper leg, lower leg, hip offset [m]; ``knee`` +1 knee forward, -1 back. Returns the
    set-points (4, 3) [rad] -- unflipped, clipped to each leg's limits, a leg without a
    solution keeping ``previous`` -- and ``ok`` (4,): solved within the stacked limits.
    """
    out = previous.copy()
    ok = np.zeros(4, dtype=np.bool_)
    for k in range(4):
        q1, q2, q3, solved = leg_angles(local[k, 0] - legs[k, 0], local[k, 1] - legs[k, 1],
                                        local[k, 2] - legs[k, 2], legs[k, 3], knee,
                                        lengths[0], lengths[1], lengths[2])
        if not solved:  # out of the leg's reach (or NaN): keep the previous set-points
            continue
        ok[k] = (limits[0, 0] <= q1 <= limits[1, 0]) and (limits[0, 1] <= q2 <= limits[1, 1]) \
            and (limits[0, 2] <= q3 <= limits[1, 2])
        for j, angle in enumerate((q1, q2, q3)):
            out[k, j] = min(max(angle * legs[k, 4 + j], legs[k, 7 + j]), legs[k, 10 + j])
    return out, ok
