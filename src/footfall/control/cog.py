"""The body (COG) trajectory of the crawl gait (paper §IV-B 4).

Each step has a *shift* phase, all four feet down, in which the COG moves
into the support triangle of the coming swing, and a *swing* phase, in which
the COG and the zero-moment point (ZMP) stay inside that triangle inset by a
stability margin while the body keeps moving. The trajectory is planned over
the next 1-5 steps (a receding horizon: the controller uses the first step
and replans at the next).

Shape: one cubic per phase, joined with continuous position and velocity
(the unknowns are the COG's position and velocity at every phase boundary).
The constraints hold exactly, not just at sample times: a cubic lies in the
convex hull of its four Bezier control points, and so does the ZMP,
``p - (h / g) p''``, which is a cubic too; both sets of control points are
kept inside the swing's inset triangle (a convex set), and the ZMP's inside
the four feet's support polygon, inset by the same margin, during the shift.

The boundary states solve a small convex quadratic programme (8 unknowns per
step), solved exactly by one non-negative least-squares solve (see
:func:`~footfall.control.least_squares.least_squares_inequality`): minimise the integrated squared
acceleration of the whole path plus a weak pull of each swing's lift-off and
touch-down positions toward the triangle's incentre. This is the paper's
"continuous forward movement of the COG with optimal, velocity-dependent
sway": the body never has to stop, and how far it sways follows from the
least-acceleration trade-off at the pace the phase durations and foothold
spacing set.

Reach (``CogConfig.reach``): the support triangles alone let the
COG run far past the feet -- after a long stride onto a rock the body
lunged 13 cm in half a second and the hind legs met their joint limits. With
a reach, the COG's Bezier points (hence the whole cubic) stay, in every
phase, in the box that keeps each foot down within ``reach`` of its nominal
place under the body; a plan that cannot keep it is planned without it
(status "out of reach").

Robustness: a swing whose triangle is too thin for the margin (inradius <=
margin: the inset triangle is empty) pins the COG to the incentre, at rest,
for that swing (it "slows down" to a stop there). If the shifts' ZMP
constraints cannot be met, the plan is retried with every shift lengthened
by ``slowdown`` (status "slowed"); if they still cannot, they are dropped
(status "relaxed": the swings stay safe, the shifts may be abrupt); if even
that fails numerically, the COG stops at every incentre (status "fallback").
The COG is taken to be the body origin (centre of the hip roll axes); the
legs' mass moves it by a few millimetres, well inside the margin.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from scipy.interpolate import PPoly
from scipy.spatial import ConvexHull, QhullError

from footfall.control.least_squares import least_squares_inequality
from footfall.control.support import (
    halfplanes,
    incircle,
    support_margin,  # noqa: F401 - imported from here by sim.episode and control.reflexes
    triangle_halfplanes,
)
from footfall.core.errors import FootfallError
from footfall.core.params import Params, above, at_least, param
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription

GRAVITY = 9.81  # [m/s^2] standard gravity, for the ZMP
_SAFETY = 1e-6  # [m] extra inset given to the solver so its tolerance cannot eat the margin
_TIME_TOLERANCE = 1e-9  # [s] how far outside [0, end] a query may be and still be answered


@dataclass(frozen=True)
class CogConfig(Params):
    """Every knob of the COG planner (docs/configuration.md)."""

    margin: float = param(0.02, unit="m", range=at_least(0),
                          doc="inset of the support triangles (and shift polygons) the ZMP keeps")
    swing_duration: float = param(0.3, unit="s", range=above(0), doc="one leg in the air")
    shift_duration: float = param(0.15, unit="s", range=above(0),
                                  doc="four feet down, the COG moving into the next triangle")
    cog_height: float | None = param(None, unit="m", range=above(0),
                                     doc="COG height for the ZMP; None: robot.nominal_height")
    centring: float = param(10.0, unit="1/s^3", range=above(0),
                            doc="weight of the squared distance [m^2] of the COG at each lift-off "
                                "and touch-down from the swing triangle's incentre, against the "
                                "integrated squared acceleration [m^2/s^3]")
    reach: float | None = param(None, unit="m", range=above(0),
                                doc="the COG keeps every foot down within this distance of its "
                                    "nominal place under the body, along x and along y; None: "
                                    "no limit")
    slowdown: float = param(2.0, unit="-", range=at_least(1),
                            doc="factor on every shift's duration when the ZMP cannot be kept in")


@dataclass(frozen=True, eq=False)
class CogTrajectory:
    """The planned horizontal COG path over the next steps, and its phase times.

    Times are in seconds from the start of the first shift phase. Step k
    shifts during ``[shift_start[k], lift_off[k])`` and swings leg
    ``legs[k]`` during ``[lift_off[k], touch_down[k])``; the next shift
    starts at touch-down.
    """

    legs: tuple[str, ...]  # (K,) swing leg of each step
    shift_start: np.ndarray  # (K,) [s] start of each step's shift phase
    lift_off: np.ndarray  # (K,) [s] lift-off of each step's swing leg
    touch_down: np.ndarray  # (K,) [s] touch-down of each step's swing leg
    triangles: np.ndarray  # (K, 3, 2) [m] support triangle (x, y) of each swing
    waypoints: np.ndarray  # (K, 2, 2) [m] COG at lift-off and at touch-down of each swing
    margin: float  # [m] inset of the triangles the COG and ZMP keep during the swings
    cog_height: float  # [m] COG height used for the ZMP
    status: str  # 'optimal', 'out of reach' (reach dropped), 'slowed' (shifts lengthened),
    # 'relaxed' (shift ZMP unconstrained)
    # or 'fallback' (COG stops at every incentre)
    pinned: np.ndarray  # (K,) bool: the inset triangle was empty; the COG stops at the incentre
    _pos: PPoly  # position [m] of time
    _vel: PPoly = field(init=False, repr=False)  # velocity [m/s] of time
    _acc: PPoly = field(init=False, repr=False)  # acceleration [m/s^2] of time

    def __post_init__(self) -> None:
        object.__setattr__(self, "_vel", self._pos.derivative())
        object.__setattr__(self, "_acc", self._pos.derivative(2))

    @property
    def end(self) -> float:
        """Time [s] of the last touch-down."""
        return float(self.touch_down[-1])

    def _check(self, t: np.ndarray) -> np.ndarray:
        t = np.asarray(t, dtype=np.float64)
        if not np.all((t >= -_TIME_TOLERANCE) & (t <= self.end + _TIME_TOLERANCE)):
            raise FootfallError(f"COG trajectory is defined for t in [0, {self.end:.6g}] s")
        return np.clip(t, 0.0, self.end)

    def position(self, t: np.ndarray) -> np.ndarray:
        """COG position [m] (..., 2) at times ``t`` [s] (...)."""
        return self._pos(self._check(t))

    def velocity(self, t: np.ndarray) -> np.ndarray:
        """COG velocity [m/s] (..., 2) at times ``t`` [s] (...)."""
        return self._vel(self._check(t))

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """COG acceleration [m/s^2] (..., 2) at times ``t`` [s] (...); right-continuous at phase changes."""
        return self._acc(self._check(t))

    def zmp(self, t: np.ndarray) -> np.ndarray:
        """Zero-moment point [m] (..., 2): position - (cog_height / g) * acceleration."""
        t = self._check(t)
        return self._pos(t) - (self.cog_height / GRAVITY) * self._acc(t)


def _phase_weights(durations: np.ndarray, zmp_factor: float) -> dict[str, np.ndarray]:
    """Weights on (p0, v0, p1, v1) of cubic phases of ``durations`` (P,) [s], each (P, rows, 4).

    ``bezier``: the four Bezier control points of the position (the curve
    lies in their convex hull); ``acc``: acceleration at the start and end
    (it is linear in time); ``zmp``: the four Bezier control points of
    position - zmp_factor [s^2] * acceleration, also a cubic in time.
    """
    T = np.asarray(durations, dtype=np.float64)[:, None]
    one, zero = np.ones_like(T), np.zeros_like(T)
    bezier = np.stack([np.hstack([one, zero, zero, zero]), np.hstack([one, T / 3, zero, zero]),
                       np.hstack([zero, zero, one, -T / 3]), np.hstack([zero, zero, one, zero])],
                      axis=1)
    acc = np.stack([np.hstack([-6 / T**2, -4 / T, 6 / T**2, -2 / T]),
                    np.hstack([6 / T**2, 2 / T, -6 / T**2, 4 / T])], axis=1)
    elevate = np.array([[1.0, 0.0], [2 / 3, 1 / 3], [1 / 3, 2 / 3], [0.0, 1.0]])  # linear -> cubic
    return {"bezier": bezier, "acc": acc, "zmp": bezier - zmp_factor * elevate @ acc}


def _stances(feet: np.ndarray, steps: Sequence[tuple[str, np.ndarray]]
             ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Feet (K, 4, 2) down at each step's shift and each swing's support triangle (K, 3, 2)."""
    current = feet[:, :2].copy()
    stances, triangles, legs = [], [], []
    for name, foothold in steps:  # the horizon: at most a handful of steps
        k = LEG_NAMES.index(name)
        stances.append(current.copy())
        triangles.append(np.delete(current, k, axis=0))
        legs.append(name)
        current[k] = foothold[:2]
    return np.array(stances), np.array(triangles), tuple(legs)


def _solve(start: np.ndarray, v0: np.ndarray, stances: np.ndarray, triangles: np.ndarray,
           durations: np.ndarray, config: CogConfig, height: float, shift_zmp: bool,
           reach: tuple[np.ndarray, np.ndarray] | None = None
           ) -> tuple[np.ndarray | None, np.ndarray, np.ndarray]:
    """COG states (2K + 1, 2, 2) = (position, velocity) at every phase boundary, or None if infeasible.

    Also returns the swing triangles' incentres (K, 2) and which swings are
    pinned to them (K,). Phase 2k is step k's shift, phase 2k + 1 its swing;
    boundary 0 is the start. Every quantity is linear in the unknowns z (the
    states at boundaries 1 .. 2K, 4 numbers each): it is built as a map
    (..., n) and a constant (...).
    """
    n_phases = 2 * triangles.shape[0]
    inputs = _phase_inputs(start, v0, n_phases)
    w = _phase_weights(durations, height / GRAVITY)
    centres, radii = incircle(triangles)
    pinned = radii <= config.margin + _SAFETY
    G, g = _objective(w, durations, centres, config, inputs)
    C, c = _constraints(w, stances, triangles, pinned, config, shift_zmp, inputs, reach)

    # A pinned swing stands still at the incentre: its boundary states are constants.
    fixed = np.zeros((n_phases, 4))
    fixed[1::2, :2] = fixed[0::2, :2] = centres  # boundaries 2k + 1, 2k + 2: rows 2k, 2k + 1
    free = np.ones((n_phases, 4), dtype=bool)
    free[np.repeat(pinned, 2)] = False
    fixed = np.where(free, 0.0, fixed).ravel()
    free = free.ravel()
    z = fixed.copy()
    if free.any():
        y = least_squares_inequality(G[:, free], G @ fixed + g, C[:, free], C @ fixed + c)
        if y is None:
            return None, centres, pinned
        z[free] = y
    if c.size and np.min(C @ z + c) < -_SAFETY / 2:
        return None, centres, pinned
    states = np.concatenate([np.stack([start, v0])[None], z.reshape(n_phases, 2, 2)])
    return states, centres, pinned


def _phase_inputs(start: np.ndarray, v0: np.ndarray, n_phases: int
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Where each phase's inputs (p0, v0, p1, v1) come from, on each axis.

    Returns the column (P, 4, 2) of each in the unknowns z (n = 4P of them; the start's
    state is a constant and goes to a scratch column n) and the constant inputs (P, 4, 2).
    """
    n = 4 * n_phases
    boundary = np.arange(n_phases)[:, None] + np.array([0, 0, 1, 1])  # (P, 4)
    cols = 4 * (boundary - 1)[..., None] + np.array([0, 2, 0, 2])[:, None] + np.arange(2)
    cols[0, :2] = n  # (P, 4, 2)
    inputs_c = np.zeros((n_phases, 4, 2))
    inputs_c[0, 0], inputs_c[0, 1] = start, v0
    return cols, inputs_c


def _linear(weights: np.ndarray, inputs: tuple[np.ndarray, np.ndarray]
            ) -> tuple[np.ndarray, np.ndarray]:
    """Weights (P, q, 4) on the phases' inputs -> maps (P, q, 2, n) and constants (P, q, 2)."""
    cols, inputs_c = inputs
    n = 4 * cols.shape[0]
    P, q, _ = weights.shape
    m = np.zeros((P, q, 2, n + 1))
    idx = (np.arange(P)[:, None, None, None], np.arange(q)[None, :, None, None],
           np.arange(2)[None, None, :, None], cols.transpose(0, 2, 1)[:, None])
    m[idx] = weights[:, :, None, :]
    return m[..., :n], np.einsum("pqj,pjd->pqd", weights, inputs_c)


def _objective(w: dict[str, np.ndarray], durations: np.ndarray, centres: np.ndarray,
               config: CogConfig, inputs: tuple[np.ndarray, np.ndarray]
               ) -> tuple[np.ndarray, np.ndarray]:
    """The objective as |G z + g|^2: G (r, n), g (r,)."""
    n_steps, n = centres.shape[0], 4 * durations.size
    # Integrated squared acceleration, linear in time within a phase (a0 -> a1):
    # T/3 (a0^2 + a0 a1 + a1^2) = |sqrt(T/3) (a0 + a1/2)|^2 + |sqrt(T/4) a1|^2.
    T = durations[:, None, None]
    root = np.concatenate([np.sqrt(T / 3) * np.array([1.0, 0.5]), np.sqrt(T / 4) * np.array([0.0, 1.0])],
                          axis=1)  # (P, 2, 2): residual rows as combinations of (a0, a1)
    res_m, res_c = _linear(root @ w["acc"], inputs)
    # ... plus the pull of every swing's lift-off and touch-down positions toward the incentre.
    pull_m = np.zeros((n_steps, 2, 2, n))
    k, which, d = np.meshgrid(np.arange(n_steps), np.arange(2), np.arange(2), indexing="ij")
    pull_m[k, which, d, 4 * (2 * k + which) + d] = np.sqrt(config.centring)
    pull_c = -np.sqrt(config.centring) * np.broadcast_to(centres[:, None], (n_steps, 2, 2))
    G = np.vstack([res_m.reshape(-1, n), pull_m.reshape(-1, n)])
    g = np.concatenate([res_c.ravel(), pull_c.ravel()])
    return G, g


def _constraints(w: dict[str, np.ndarray], stances: np.ndarray, triangles: np.ndarray,
                 pinned: np.ndarray, config: CogConfig, shift_zmp: bool,
                 inputs: tuple[np.ndarray, np.ndarray],
                 reach: tuple[np.ndarray, np.ndarray] | None = None
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The constraints as C z + c >= 0: C (m, n), c (m,).

    During each swing not ``pinned``, the COG's and the ZMP's Bezier points inside the inset
    triangle; with ``shift_zmp``, during each shift, the ZMP's inside the inset support polygon;
    with ``reach`` (:func:`_reach_boxes`), in every phase the COG's inside its box.
    """
    n_steps, n = triangles.shape[0], 4 * 2 * triangles.shape[0]
    normals, offsets = triangle_halfplanes(triangles, config.margin + _SAFETY)  # (K, 3, 2), (K, 3)
    points_m, points_c = _linear(np.concatenate([w["bezier"], w["zmp"]], axis=1), inputs)
    points_m, points_c = points_m[1::2], points_c[1::2]  # the swings
    rows_m = np.einsum("ked,kqdn->kqen", normals, points_m)[~pinned]
    rows_c = (np.einsum("ked,kqd->kqe", normals, points_c) - offsets[:, None])[~pinned]
    C, c = [rows_m.reshape(-1, n)], [rows_c.ravel()]
    if shift_zmp:
        zmp_m, zmp_c = _linear(w["zmp"], inputs)
        zmp_m, zmp_c = zmp_m[0::2], zmp_c[0::2]  # the shifts
        for k in range(n_steps):  # the horizon's shifts: a handful of 4-point hulls
            try:
                hull = stances[k][ConvexHull(stances[k]).vertices]
            except QhullError:  # feet in a line: no polygon to keep the ZMP in
                continue
            nrm, off = halfplanes(hull, config.margin + _SAFETY)
            C.append(np.einsum("ed,qdn->qen", nrm, zmp_m[k]).reshape(-1, n))
            c.append((zmp_c[k] @ nrm.T - off).ravel())
    if reach is not None:
        lo, hi = reach  # (P, 2) [m] each phase's box for the COG; lo > hi: no box
        valid = (lo <= hi).all(axis=1)
        bez_m, bez_c = _linear(w["bezier"], inputs)  # (P, 4, 2, n), (P, 4, 2)
        C += [bez_m[valid].reshape(-1, n), -bez_m[valid].reshape(-1, n)]
        c += [(bez_c[valid] - lo[valid, None, :]).ravel(),
              (hi[valid, None, :] - bez_c[valid]).ravel()]
    return np.vstack(C), np.concatenate(c)


def _reach_boxes(stances: np.ndarray, legs: tuple[str, ...], robot: RobotDescription,
                 reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Per phase (shift, swing of each step) the box lo, hi (P, 2) [m] of COG positions that
    keep every foot down within ``reach`` [m], along x and along y, of its nominal place under
    the body (hip_x ahead or behind, nominal_foot_y to the side; the body's axes taken along
    the world's: the walks go straight along x). A phase whose feet are further apart than
    twice the reach on either axis (lo > hi) has no box."""
    home = np.array([[(1 if leg.front else -1) * robot.hip_x, leg.side * robot.nominal_foot_y]
                     for leg in robot.legs])
    rel = stances - home  # (K, 4, 2): the COG that would put each foot at home
    down = np.ones(rel.shape[:2], dtype=bool)
    swing = down.copy()
    swing[np.arange(len(legs)), [LEG_NAMES.index(leg) for leg in legs]] = False
    lo, hi = [], []
    for mask in (down, swing):
        lo.append(np.where(mask[..., None], rel, -np.inf).max(axis=1) - reach)
        hi.append(np.where(mask[..., None], rel, np.inf).min(axis=1) + reach)
    # phases in order: shift 0, swing 0, shift 1, ...
    return (np.stack(lo, axis=1).reshape(-1, 2), np.stack(hi, axis=1).reshape(-1, 2))


def _trajectory(states: np.ndarray, durations: np.ndarray) -> tuple[PPoly, np.ndarray]:
    """Piecewise cubic through boundary states (m + 1, 2, 2), and the boundary times (m + 1,) [s]."""
    p0, v0 = states[:-1, 0], states[:-1, 1]  # (m, 2)
    p1, v1 = states[1:, 0], states[1:, 1]
    T = durations[:, None]
    coeffs = np.stack([(2 * (p0 - p1) / T + v0 + v1) / T**2,
                       (3 * (p1 - p0) / T - 2 * v0 - v1) / T, v0, p0])  # (4, m, 2), highest first
    breaks = np.concatenate([[0.0], np.cumsum(durations)])
    return PPoly(coeffs, breaks), breaks


def plan_cog(feet: np.ndarray, steps: Sequence[tuple[str, np.ndarray]], start_xy: np.ndarray,
             start_velocity: np.ndarray, config: CogConfig | None = None,
             robot: RobotDescription = LITTLEDOG) -> CogTrajectory:
    """Plan the COG over the next steps of the crawl gait.

    Parameters
    ----------
    feet : array of shape (4, 3)
        World contact points [m] of the four feet now (all down), LEG_NAMES order.
    steps : sequence of (leg name, foothold of shape (3,))
        The next 1-5 steps, in the order they are taken (the gait order):
        which leg swings and its foothold [m]. Only x, y matter: the
        support polygons and the ZMP are horizontal.
    start_xy : array of shape (2,)
        COG (body origin) x, y [m] now.
    start_velocity : array of shape (2,)
        COG velocity [m/s] now.
    config : CogConfig, optional
    robot : RobotDescription
        Supplies the default COG height for the ZMP.

    Returns
    -------
    CogTrajectory
    """
    config = config or CogConfig()
    feet = np.asarray(feet, dtype=np.float64)
    start = np.asarray(start_xy, dtype=np.float64)
    v0 = np.asarray(start_velocity, dtype=np.float64)
    if feet.shape != (4, 3) or start.shape != (2,) or v0.shape != (2,):
        raise FootfallError(f"plan_cog needs feet (4, 3), start_xy (2,) and start_velocity (2,), "
                            f"got {feet.shape}, {start.shape} and {v0.shape}")
    if len(steps) == 0:
        raise FootfallError("plan_cog needs at least one step")
    checked = []
    for step in steps:
        try:
            name, foothold = step
        except (TypeError, ValueError):
            raise FootfallError("each step must be a (leg name, foothold) pair") from None
        if name not in LEG_NAMES:
            raise FootfallError(f"unknown leg {name!r}; legs are {', '.join(LEG_NAMES)}")
        foothold = np.asarray(foothold, dtype=np.float64)
        if foothold.shape != (3,):
            raise FootfallError(f"a foothold must be (3,), got {foothold.shape}")
        checked.append((name, foothold))
    arrays = [feet, start, v0] + [f for _, f in checked]
    if not all(np.isfinite(a).all() for a in arrays):
        raise FootfallError("plan_cog: feet, footholds, start_xy and start_velocity must be finite")
    height = robot.nominal_height if config.cog_height is None else config.cog_height

    stances, triangles, legs = _stances(feet, checked)
    n_steps = len(legs)
    durations = np.tile([config.shift_duration, config.swing_duration], n_steps)
    status = "optimal"
    boxes = None if config.reach is None else _reach_boxes(stances, legs, robot, config.reach)
    states, centres, pinned = _solve(start, v0, stances, triangles, durations, config, height,
                                     True, boxes)
    if states is None and boxes is not None:
        status = "out of reach"  # the legs' reach is dropped first
        states, centres, pinned = _solve(start, v0, stances, triangles, durations, config,
                                         height, True)
    if states is None and config.slowdown > 1:
        durations[0::2] *= config.slowdown
        status = "slowed"
        states, centres, pinned = _solve(start, v0, stances, triangles, durations, config, height, True)
    if states is None:
        status = "relaxed"
        states, centres, pinned = _solve(start, v0, stances, triangles, durations, config, height, False)
    if states is None:  # cannot happen in exact arithmetic: standing at the incentres is feasible
        status = "fallback"
        states = np.zeros((2 * n_steps + 1, 2, 2))
        states[0] = start, v0
        states[1:, 0] = np.repeat(centres, 2, axis=0)
    pos, breaks = _trajectory(states, durations)
    return CogTrajectory(legs=legs, shift_start=breaks[0:-1:2], lift_off=breaks[1::2],
                         touch_down=breaks[2::2], triangles=triangles,
                         waypoints=states[1:, 0].reshape(n_steps, 2, 2), margin=config.margin,
                         cog_height=height, status=status, pinned=pinned, _pos=pos)
