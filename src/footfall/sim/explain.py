"""Why a run failed, in terms a locomotion engineer can act on (``footfall walk --explain``).

:func:`explain_run` reads the flight recorder of a run (:mod:`footfall.sim.trace`,
the last seconds at the control rate) and its outcome and says:

* which stance foot moved, how far from where it was put down, how long
  before the end it started to move, and how much of its stance until then it
  was on the ground at all (a foot whose touch-down did not take is carried
  through the air by its stiff leg: it "moves" without sliding);
* the support margin of the measured centre of mass over the last seconds
  (its signed distance inside the convex hull of the stance feet);
* the trunk's roll and pitch, and when the tilt began;
* the vertical contact forces on the stance feet (an unloaded stance foot);
* joints at their position or torque limits;

and sorts the failure into one cause of the :data:`CAUSES` taxonomy by the
first rule that holds (the order is the order of :data:`CAUSES`). All
numerics are pure functions of arrays; the thresholds are the module's
constants, named and in SI units.
"""

from __future__ import annotations

import numpy as np

from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.data.outcomes import STANCE_SLID
from footfall.sim.trace import TraceSeries

# What a failed run is put down to, in the order the rules are tried.
CAUSES = {
    "touch-down did not take": "a stance foot moved more than SLIP_MOVED from where it was put "
                               "down before the trunk tilted, but was on the ground (its force "
                               "above UNLOADED) less than UNTAKEN of the time from its touch-down "
                               "until then: a foot in the air carried by its leg, not a slide",
    "stance foot slipped": "a stance foot moved more than SLIP_MOVED from where it was put down "
                           "before the trunk tilted",
    "centre of mass left the support": "the centre of mass was outside the stance feet's "
                                       "support polygon for more than OUTSIDE_TIME",
    "joint at its limit": "a joint sat at its torque or position limit for more than "
                          "SATURATION_TIME before the end",
    "no progress": "the robot stood still (stuck, no foothold, or out of time)",
    "other": "none of the above",
}
SLIP_MOVED = STANCE_SLID  # [m] a stance foot this far from its touch-down point has slipped (the
# ball rolls a few mm as the body passes over it); the run's outcome labels use the same distance
TILT_BEGUN = 0.15  # [rad] roll or pitch beyond this: the trunk has started to tip
OUTSIDE_TIME = 0.1  # [s]
SATURATION_TIME = 0.2  # [s] of the last second
TORQUE_SATURATED = 0.98  # share of the torque limit that counts as saturated
POSITION_SATURATED = 0.02  # [rad] this close to a joint limit counts as at the limit
UNLOADED = 1.0  # [N] a stance foot pressing less than this carries nothing
UNTAKEN = 0.5  # [-] share of its stance on the ground below which a touch-down did not take
JOINTS = ("hip roll", "hip pitch", "knee")


def hull_margin(points: np.ndarray, active: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Signed distance [m] of ``query`` inside the convex hull of the active ``points``.

    Parameters
    ----------
    points : array of shape (..., n, 2)
        Candidate vertices [m] (n small: the feet).
    active : array of shape (..., n), bool
        Which points count (the stance feet).
    query : array of shape (..., 2)
        The points to measure [m] (the centre of mass).

    Returns
    -------
    ndarray of shape (...)
        Inside the hull: the distance to its nearest edge (> 0); outside: the
        most negative signed distance to an edge line (< 0, at most the
        distance to the hull). NaN with fewer than three active points.

    Every pair of active points whose line has all other active points on one
    side is a hull edge; the margin is the smallest signed distance to those
    lines, oriented so the others lie on the positive side.
    """
    p = np.asarray(points, dtype=np.float64)
    act = np.asarray(active, dtype=bool)
    q = np.asarray(query, dtype=np.float64)
    n = p.shape[-2]
    i, j = np.triu_indices(n, 1)
    a, b = p[..., i, :], p[..., j, :]  # (..., pairs, 2)
    edge = b - a
    length = np.hypot(edge[..., 0], edge[..., 1])
    rel = p[..., None, :, :] - a[..., :, None, :]  # (..., pairs, n, 2): every point from a
    side = edge[..., :, None, 0] * rel[..., 1] - edge[..., :, None, 1] * rel[..., 0]
    others = act[..., None, :] & (np.arange(n) != i[:, None]) & (np.arange(n) != j[:, None])
    tol = 1e-12
    pos = np.where(others, side > tol, True).all(axis=-1)
    neg = np.where(others, side < -tol, True).all(axis=-1)
    is_edge = act[..., i] & act[..., j] & (pos | neg) & (length > 0)
    qrel = q[..., None, :] - a
    signed = (edge[..., 0] * qrel[..., 1] - edge[..., 1] * qrel[..., 0]) / np.where(
        length > 0, length, 1.0)
    signed = np.where(neg & ~pos, -signed, signed)
    margin = np.where(is_edge, signed, np.inf).min(axis=-1)
    enough = act.sum(axis=-1) >= 3
    return np.where(enough & np.isfinite(margin), margin, np.nan)


def stance_slips(trace: TraceSeries) -> np.ndarray:
    """How far (n, 4) [m] each stance foot's centre is from where it was put down (NaN: swing)."""
    return np.linalg.norm(trace.feet - trace.anchor, axis=-1)


def com_margin(trace: TraceSeries) -> np.ndarray:
    """Support margin (n,) [m] of the centre of mass over the stance feet (:func:`hull_margin`)."""
    return hull_margin(trace.feet[..., :2], trace.stance, trace.com[:, :2])


def saturated_joints(trace: TraceSeries, robot: RobotDescription) -> np.ndarray:
    """(n, 4, 3) bool: joints at their torque limit or within POSITION_SATURATED of a limit."""
    lower = np.array([[lim[0] for lim in leg.limits] for leg in robot.legs])
    upper = np.array([[lim[1] for lim in leg.limits] for leg in robot.legs])
    torque = np.abs(trace.torque) >= TORQUE_SATURATED * robot.max_joint_torque
    position = (trace.q <= lower + POSITION_SATURATED) | (trace.q >= upper - POSITION_SATURATED)
    return torque | position


def contact_share(trace: TraceSeries, leg: int, row: int) -> float | None:
    """Share [-] of the rows from ``leg``'s last touch-down up to ``row`` in which its vertical
    contact force was above UNLOADED (None: not a stance foot at ``row``)."""
    stance = trace.stance[: row + 1, leg]
    if not stance[-1]:
        return None
    lifted = np.flatnonzero(~stance)
    start = int(lifted[-1]) + 1 if lifted.size else 0
    return float((trace.forces[start: row + 1, leg, 2] > UNLOADED).mean())


def _slip_summary(trace: TraceSeries, first: int, end: int) -> dict:
    """The stance foot that moved most between rows ``first`` and ``end`` of the trace, how far
    [m], since when [s before the trace's end] -- the onset looked for in the whole trace, also
    before row ``first`` -- and its share of that stance on the ground until then."""
    moved = np.nan_to_num(stance_slips(trace), nan=0.0)
    leg = int(np.argmax(moved[first: end + 1].max(axis=0)))
    worst = float(moved[first: end + 1, leg].max())
    over = moved[:, leg] > SLIP_MOVED
    began = share = None
    if over[first: end + 1].any():
        row = first + int(np.argmax(over[first: end + 1]))
        within = np.flatnonzero(~over[:row])  # the onset: back to the last row not past it
        row = int(within[-1]) + 1 if within.size else 0
        began = float(trace.time[-1] - trace.time[row])
        if row > 0:  # at the recorder's first row the onset, and the stance before it, are unseen
            share = contact_share(trace, leg, row)
    return {"leg": LEG_NAMES[leg], "moved_mm": 1e3 * worst, "began_s_before_end": began,
            "on_ground_share": share}


def explain_run(trace: TraceSeries, result: dict, robot: RobotDescription,
                window: float = 3.0) -> dict:
    """What happened in the last ``window`` [s] of a run, and the cause of a failure.

    Returns a plain-JSON dict: ``cause`` (a key of :data:`CAUSES`, None for a
    success), ``swing_leg`` at the end, the stance foot that moved most
    (``slip``), the centre of mass's support margin (least and at the end
    [mm], and how long it was outside [s]), roll and pitch at the end [rad]
    and when the tilt began, unloaded stance feet, and the joints at their
    limits.
    """
    if len(trace) == 0:
        return {"cause": None if result.get("success") else "other", "window_s": 0.0}
    keep = trace.time >= trace.time[-1] - window
    t = trace.time[keep]
    sub = TraceSeries(**{name: getattr(trace, name)[keep] for name in trace.__dataclass_fields__})
    tilt = np.abs(sub.body_rpy[:, :2]).max(axis=1)
    tilted = np.flatnonzero(tilt > TILT_BEGUN)
    tilt_row = int(tilted[0]) if tilted.size else len(sub) - 1
    first = int(np.flatnonzero(keep)[0])  # the window's first row in the whole trace
    slip = _slip_summary(trace, first, first + tilt_row)
    margin = com_margin(sub)
    outside = np.nan_to_num(margin, nan=np.inf) < 0
    period = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    sat = saturated_joints(sub, robot)
    last_second = t >= t[-1] - 1.0
    sat_time = sat[last_second].sum(axis=0) * period  # (4, 3) [s]
    at_limit = [f"{LEG_NAMES[k]} {JOINTS[j]}" for k, j in zip(*np.nonzero(sat_time
                                                                         > SATURATION_TIME))]
    fz = sub.forces[-1, :, 2]
    unloaded = [LEG_NAMES[k] for k in range(4) if sub.stance[-1, k] and fz[k] < UNLOADED]
    swing = int(sub.swing[-1])
    out = {
        "window_s": float(t[-1] - t[0]),
        "swing_leg": LEG_NAMES[swing] if swing >= 0 else None,
        "slip": slip,
        "com_margin_min_mm": _mm(np.nanmin(margin)) if np.isfinite(margin).any() else None,
        "com_margin_end_mm": _mm(margin[-1]),
        "com_outside_s": float(outside.sum() * period),
        "roll_pitch_end_rad": [float(v) for v in sub.body_rpy[-1, :2]],
        "tilt_began_s_before_end": (float(t[-1] - t[tilted[0]]) if tilted.size else None),
        "stance_force_end_n": {LEG_NAMES[k]: float(fz[k]) for k in range(4) if sub.stance[-1, k]},
        "unloaded_stance_feet": unloaded,
        "joints_at_limit": at_limit,
    }
    out["cause"] = None if result.get("success") else _cause(result, out)
    return out


def _mm(value: float) -> float | None:
    return 1e3 * float(value) if np.isfinite(value) else None


def _cause(result: dict, facts: dict) -> str:
    """The first cause of :data:`CAUSES` whose rule holds."""
    reason = str(result.get("reason", ""))
    if not reason.startswith("fall"):
        return "no progress" if reason.startswith(("stuck", "time")) else "other"
    if facts["slip"]["moved_mm"] > 1e3 * SLIP_MOVED:
        share = facts["slip"].get("on_ground_share")
        return ("touch-down did not take" if share is not None and share < UNTAKEN
                else "stance foot slipped")
    if facts["com_outside_s"] > OUTSIDE_TIME:
        return "centre of mass left the support"
    if facts["joints_at_limit"]:
        return "joint at its limit"
    return "other"


def explanation_lines(explanation: dict) -> list[str]:
    """The explanation as a few lines of text for the terminal."""
    e = explanation
    if "slip" not in e:
        return [f"cause: {e.get('cause')} (nothing recorded)"]
    s = e["slip"]
    began = ("" if s["began_s_before_end"] is None
             else f", from {s['began_s_before_end']:.2f} s before the end")
    if s.get("on_ground_share") is not None:
        began += f", on the ground {100 * s['on_ground_share']:.0f} % of its stance until then"
    roll, pitch = e["roll_pitch_end_rad"]
    tilt = ("" if e["tilt_began_s_before_end"] is None
            else f"; tilt past {TILT_BEGUN} rad {e['tilt_began_s_before_end']:.2f} s before")
    least = e["com_margin_min_mm"]
    lines = [
        f"cause: {e['cause'] or 'none (success)'}",
        f"stance foot that moved most: {s['leg']}, {s['moved_mm']:.1f} mm from its touch-down "
        f"point{began}",
        f"centre-of-mass support margin over the last {e['window_s']:.1f} s: least "
        f"{'-' if least is None else f'{least:.1f}'} mm, outside for {e['com_outside_s']:.2f} s",
        f"trunk at the end: roll {roll:+.2f} rad, pitch {pitch:+.2f} rad{tilt}",
        f"swing leg at the end: {e['swing_leg'] or 'none'}; stance feet unloaded: "
        f"{', '.join(e['unloaded_stance_feet']) or 'none'}",
        f"joints at a limit in the last second: {', '.join(e['joints_at_limit']) or 'none'}",
    ]
    return lines
