"""Stance load control: each stance foot carries its share of the weight, felt by its force sensor.

A position-controlled quadruped on four feet is statically indeterminate:
on uneven ground the stiff legs put the weight on whichever diagonal pair
stands highest, like a four-legged table on a rough floor. A foot that was
set down exactly where it touched the ground carries nothing until the body
sags onto it, and when the loaded foot of the other diagonal lifts, the
body tips onto the unloaded one -- the step that starts most slides and
falls on rocks (``footfall walk --explain``).

So, every control period, the share of the weight each stance foot should
carry is found from where the feet and the measured centre of mass are
(:func:`load_shares`: moment balance about the centre of mass, the spare
degree of freedom of four feet spent on spreading the load evenly), and
each foot's target height is moved by the force error its sensor measures
(:func:`load_offsets`): down while it carries too little, up while it
carries too much. A leg about to lift is unloaded this way first, and a leg
just set down takes its share gradually. The offsets sum to nothing over
the stance feet (the measured total is shared out), so the body height is
left to the body controller. The same shares, times the weight, give each
stance leg's servos the joint torques that carry its foot's part as a
feed-forward (:func:`support_torques`), so that the servos' stiffness does
not have to.
"""

from __future__ import annotations

import numba
import numpy as np


def load_shares(feet_xy: np.ndarray, com_xy: np.ndarray, availability: np.ndarray
                ) -> np.ndarray:
    """Share [-] (k,) of the weight each of k feet should carry; the shares sum to 1.

    The shares ``s`` balance the moment about the centre of mass,
    ``sum s_i (p_i - c) = 0``, and of all such shares minimise
    ``sum s_i^2 / a_i``: a foot of availability ``a_i`` 0 carries nothing, a
    foot of availability 1 its full part. Three available feet have one
    solution (the barycentric coordinates of the centre of mass); four share
    the spare degree of freedom. Shares are clipped at 0 (a centre of mass
    outside the support cannot be balanced) and scaled back to sum 1.

    Compiled (:func:`_shares`): called once or twice every control period on
    four feet, where NumPy's per-call overhead would be nearly all its cost.

    Parameters
    ----------
    feet_xy : array of shape (k, 2)
        Horizontal positions [m] of the feet.
    com_xy : array of shape (2,)
        Horizontal position [m] of the centre of mass.
    availability : array of shape (k,)
        Availability [-] in [0, 1] of each foot to carry load.
    """
    return _shares(np.ascontiguousarray(feet_xy, dtype=np.float64),
                   np.ascontiguousarray(com_xy, dtype=np.float64),
                   np.ascontiguousarray(availability, dtype=np.float64))


@numba.njit(cache=True, nogil=True)
def _shares(feet_xy, com_xy, availability):  # pragma: no cover - compiled
    """:func:`load_shares` of float64 arrays (k, 2), (2,), (k,)."""
    k = availability.shape[0]
    px = feet_xy[:, 0] - com_xy[0]
    py = feet_xy[:, 1] - com_xy[1]
    a = np.minimum(np.maximum(availability, 0.0), 1.0)
    if not np.any(a != 0.0):
        return np.zeros(k)
    shares = _balanced(px, py, a)
    if shares.min() < 0 and np.any(a < 1):  # the partly available feet cannot be spared:
        shares = _balanced(px, py, (a > 0).astype(np.float64))  # every foot down takes its part
    shares = np.maximum(shares, 0.0)
    total = shares.sum()
    return shares / total if total > 0 else a / a.sum()


@numba.njit(cache=True, nogil=True)
def _balanced(px, py, a):  # pragma: no cover - compiled
    """Least ``sum s^2 / a`` shares (k,) with ``sum s = 1``, ``sum s px = sum s py = 0``
    (feet at ``px``, ``py`` [m] from the centre of mass): ``s = a R^T G^+ e1`` with the rows
    ``R = (1, px, py)`` and their Gram matrix ``G = R diag(a) R^T`` (3, 3)."""
    g00 = g01 = g02 = g11 = g12 = g22 = 0.0
    for i in range(a.shape[0]):
        g00 += a[i]
        g01 += a[i] * px[i]
        g02 += a[i] * py[i]
        g11 += a[i] * px[i] * px[i]
        g12 += a[i] * px[i] * py[i]
        g22 += a[i] * py[i] * py[i]
    # G^-1 e1 is G's first adjugate column over its determinant -- while G is well
    # conditioned (three feet or more, not on a line); else the pseudo-inverse: two
    # available feet (or three on a line) balance in the least-squares sense
    c0 = g11 * g22 - g12 * g12
    c1 = g12 * g02 - g01 * g22
    c2 = g01 * g12 - g11 * g02
    det = g00 * c0 + g01 * c1 + g02 * c2
    trace = g00 + g11 + g22
    if det > 1e-6 * trace * trace * trace:
        c0, c1, c2 = c0 / det, c1 / det, c2 / det
    else:
        gram = np.array([[g00, g01, g02], [g01, g11, g12], [g02, g12, g22]])
        inverse = np.linalg.pinv(gram, 1e-9)
        c0, c1, c2 = inverse[0, 0], inverse[1, 0], inverse[2, 0]
    return a * (c0 + px * c1 + py * c2)


def load_offsets(offsets: np.ndarray, measured: np.ndarray, shares: np.ndarray,
                 stance: np.ndarray, gain: float, limit: float) -> np.ndarray:
    """Target height offsets (4,) [m] of the stance feet after one period of load control.

    Each stance foot's offset moves by ``gain`` [m/N] times its load error:
    the vertical force it measures less its share of the stance feet's
    measured total, up (+) for a foot that carries too much. Bounded by
    ``limit`` [m]; legs not in ``stance`` get 0.

    Parameters
    ----------
    offsets : array of shape (4,)
        The offsets [m] so far.
    measured : array of shape (4,)
        Vertical foot forces [N], + for a foot pressed onto the ground.
    shares : array of shape (4,)
        Shares [-] of the weight (:func:`load_shares`; 0 for legs not in stance).
    stance : array of shape (4,), bool
        The legs whose offsets are controlled.
    """
    f = np.where(stance, np.maximum(np.asarray(measured, dtype=np.float64), 0.0), 0.0)
    error = f - shares * f.sum()
    out = np.minimum(np.maximum(np.asarray(offsets, dtype=np.float64) + gain * error, -limit),
                     limit)
    return np.where(stance, out, 0.0)


def support_torques(jacobians: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Joint torques (4, 3) [N m] with which each leg carries a vertical ground force.

    A foot pressed onto the ground with the upward force ``f`` (the ground
    on the foot) is held in balance by the torques ``-J^T (0, 0, f)``: fed
    forward to the position servos, they carry the foot's share of the
    weight, so the servos' stiffness no longer has to, and a loaded leg no
    longer sags by ``torque / kp`` at every joint.

    Parameters
    ----------
    jacobians : array of shape (4, 3, 3)
        World-frame Jacobians [m/rad] of the foot centres with respect to each
        leg's joint angles (:meth:`footfall.sim.simulation.Simulation.foot_jacobians`).
    forces : array of shape (4,)
        Upward ground forces [N] each foot is to carry (0 for a swing leg).
    """
    return -np.asarray(forces, dtype=np.float64)[:, None] * np.asarray(jacobians)[:, 2, :]


def load_held(stance: np.ndarray, elapsed: np.ndarray, hold: float) -> bool:
    """Whether the load control holds its offsets this period: a stance foot touched down
    less than ``hold`` [s] ago.

    Just after a touch-down the force readings are an impact and a foot that
    bounces on and off the ground (the readings swing between 0 and twice the
    foot's part from one period to the next), not the load's distribution;
    the load control, which integrates them, then lowers the other feet and
    lifts the new one. Holding the offsets until the new foot has settled
    keeps that out.

    Parameters
    ----------
    stance : array of shape (4,), bool
        The stance legs.
    elapsed : array of shape (4,)
        Time [s] since each leg's last change of role.
    hold : float
        [s] how long after a touch-down the offsets are held; 0: never.
    """
    return bool(hold > 0 and (np.asarray(stance, dtype=bool)
                              & (np.asarray(elapsed, dtype=np.float64) < hold)).any())


def pressed(offsets: np.ndarray, new: np.ndarray, measured: np.ndarray, owed: np.ndarray,
            step: float, depth: float) -> np.ndarray:
    """Target height offsets (4,) [m] after one period in which the feet just set down are
    pressed onto the ground while they carry less than they are owed.

    A foot stops at the first touch of a few newtons, bounces and hangs a
    millimetre or two above its touch-down point, or touches only now and
    then, while the body shifts; the load control's proportional step is too
    slow to put it back in time, and an unloaded foot is carried along by its
    stiff leg (the "stance foot slipped" of rough ground). Each period, a
    ``new`` foot whose vertical force is below what it is ``owed`` [N] has
    its offset lowered by ``step`` [m], to at most ``depth`` [m] below its
    touch-down point (an offset already lower stays). Other feet keep theirs.

    Parameters
    ----------
    offsets : array of shape (4,)
        The load control's offsets [m] (0 at touch-down).
    new : array of shape (4,), bool
        The feet just set down.
    measured : array of shape (4,)
        Vertical foot forces [N].
    owed : array of shape (4,)
        The force [N] below which a new foot is pressed.
    """
    short = np.asarray(new, dtype=bool) & (np.asarray(measured, dtype=np.float64) <
                                           np.asarray(owed, dtype=np.float64))
    out = np.asarray(offsets, dtype=np.float64).copy()
    out[short] = np.minimum(out[short], np.maximum(out[short] - step, -depth))  # never up
    return out
