"""The synthetic expert: a physically grounded judge of footholds that demonstrates choices.

The learners never see its judgement, only its demonstrations (a state, the
candidate set F, the chosen index), exactly like the human expert of the paper
(§II-B). Its preference is deliberately non-linear in terrain shape (Fig. 2):
a mild hollow beats flat ground because it holds the ball foot, but a hole
that pinches or swallows the foot is worse than flat ground.

Terrain is judged at full map resolution from the *ball-centre surface*
``B(x, y)``: the height of the ball foot's centre when it is lowered at
(x, y) until it touches the terrain,

    B(x, y) = max over cells c with d_c <= r of  h_c + sqrt(r^2 - d_c^2),

with r the foot radius and d_c the horizontal distance of cell c (a grey-scale
dilation of the map by the ball). The one-sided slopes of B around a foothold
*are* the ball's contact normals: the slope of B in direction u equals the
tangent of the tilt of the contact normal that resists a push toward u, so
kinks of B (several contacts, e.g. in a pit) and slanted faces (one tilted
contact) are both read from B along a few ray directions. Clearance of the
lower leg and knee is judged the same way, with a chain of spheres of the
shin's radius along the leg as the inverse kinematics places it.

See docs/expert.md for the reasoning behind every term, unit and weight.
"""

from __future__ import annotations

import math
import weakref
from collections import OrderedDict
from dataclasses import dataclass, replace

import numpy as np

from footfall.core.ball import ball_centre_surface
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import (
    body_to_world,
    inverse_kinematics,
    joint_limit_margin,
    knee_position,
    world_to_body,
)
from footfall.core.params import Params, above, at_least, param, within
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.features.pose_features import triangle_margins

EXPERT_TERMS: dict[str, str] = {
    "slip_margin": "[rad] friction margin of the ball in its weakest direction: "
                   "atan(foot_friction) + atan(least, over ray directions, of the steepest secant "
                   "slope of the ball-centre surface between slip_distance/2 and slip_distance); "
                   "< 0: the ball slides off under its own load; > atan(foot_friction): held by "
                   "rising ground on every side (a hollow)",
    "pinch": "[-] wedging of the ball between opposing contacts: foot_friction * tan(tilt of the "
             "less tilted of two opposite contact normals), the most pinching pair of ray "
             "directions (slopes of the ball-centre surface over pinch_distance); >= 1: self-locking",
    "trap_depth": "[m] escape height: how far the ball centre must rise to leave a pit whose rim "
                  "lies within trap_radius in every ray direction (least over directions of the "
                  "highest rise along the ray)",
    "drop_off": "[m] worst drop-off near the foot: largest fall of the ball-centre surface below "
                "a cone falling at walkable_slope from the ball centre, at slip distance s along "
                "any ray, weighted by (1 - s / edge_radius)",
    "leg_clearance": "[m] least vertical clearance of the knee and lower leg (spheres of "
                     "lower_leg_radius along the leg, inverse kinematics at the state's body pose, "
                     "foot seated at the ball-centre height) above the terrain, capped at "
                     "leg_clearance_cap; < 0: the leg would cut into the terrain",
    "unknown": "[-] fraction of map samples without data (NaN or off the map) within "
               "unknown_radius of the foothold, the foothold's own cell included",
    "progress": "[m] advance of the swing foot toward the goal: (f - current foot) . goal direction",
    "stance_offset": "[m] horizontal distance of the foothold from the leg's gait-nominal "
                     "position: its default stance position around the body (heading frame), "
                     "moved stance_lead ahead along the heading",
    "stability": "[m] stability margin: the smaller inradius of the support triangles of the next "
                 "two swings of the crawl gait, with the swing foot at f",
    "reach_margin": "[m] distance of the seated ball centre inside the leg's maximal reach from "
                    "its hip, at the state's body pose",
    "joint_margin": "[rad] smallest distance of any joint from its limit, inverse kinematics of the "
                    "seated ball centre at the state's body pose (-unreachable_joint_margin where "
                    "no solution exists)",
}
"""Every term of the expert's judgement: name -> unit and meaning (see :meth:`SyntheticExpert.terms`)."""

EXPERT_TERM_NAMES: tuple[str, ...] = tuple(EXPERT_TERMS)


_NONNEGATIVE = at_least(0)  # the expert's numbers are all finite and >= 0 but for a few


def _even(n: int) -> bool:
    return n % 2 == 0


@dataclass(frozen=True)
class ExpertConfig(Params):
    """Every knob of the synthetic expert: imperfection, geometry of the analysis, utilities.

    Values are in *value units*; one value unit is worth 1 cm of progress
    (``w_progress = 100`` per metre). Each term enters the value through a
    piecewise-linear utility (hinges and caps: see :meth:`SyntheticExpert.utilities`).
    docs/expert.md gives the reasoning behind every number, docs/configuration.md the table.
    """

    # --- imperfection of the demonstrations
    noise: float = param(0.0, unit="value", range=_NONNEGATIVE,
                         doc="std of Gaussian noise added to each candidate's value when "
                             "choosing")
    second_best_prob: float = param(0.0, unit="-", range=within(0, 1),
                                    doc="probability of choosing the second-best (noisy) "
                                        "candidate")
    # --- geometry of the terrain analysis
    directions: int = param(16, unit="-", range=at_least(4), check=_even,
                            must="an even integer >= 4",
                            doc="ray directions around the foothold (even: opposite pairs)")
    ray_step: float = param(0.001, unit="m", range=above(0),
                            doc="spacing of the ray samples out to slip_distance (scan "
                                "resolution)")
    far_step: float = param(0.002, unit="m", range=above(0),
                            doc="spacing of the ray samples beyond (edges and rims are "
                                "ball-smooth)")
    slip_distance: float = param(0.008, unit="m", range=above(0),
                                 doc="how far a slipping ball is followed when judging its hold")
    pinch_distance: float = param(0.001, unit="m", range=above(0),
                                  doc="run over which the contact-normal slopes are read")
    trap_radius: float = param(0.02, unit="m", range=above(0),
                               doc="a pit whose rim lies within this radius traps the foot")
    edge_radius: float = param(0.04, unit="m", range=above(0),
                               doc="slip distance at which a drop-off stops counting")
    walkable_slope: float = param(0.5, unit="-", range=_NONNEGATIVE,
                                  doc="terrain falling away no faster than this is not a drop-off")
    unknown_radius: float = param(0.015, unit="m", range=_NONNEGATIVE,
                                  doc="radius checked for missing data")
    leg_samples: int = param(10, unit="-", range=at_least(2),
                             doc="spheres along the lower leg, knee included")
    leg_clearance_cap: float = param(0.05, unit="m", range=_NONNEGATIVE,
                                     doc="clearances above this count as fully clear")
    placement_error: float = param(0.0, unit="m", range=_NONNEGATIVE,
                                   doc="the terrain terms are read where the foot would fare "
                                       "worst: at the foothold or this far ahead of or behind it "
                                       "along the heading")
    # --- utilities of the terrain terms
    w_hold: float = param(20.0, unit="value/rad", range=_NONNEGATIVE,
                          doc="bonus per radian of slip margin above flat ground's")
    hold_cap: float = param(0.2, unit="rad", range=_NONNEGATIVE,
                            doc="the hold bonus saturates this far above flat ground's margin")
    w_slope: float = param(10.0, unit="value/rad", range=_NONNEGATIVE,
                           doc="penalty per radian of slip margin lost to a slanted face")
    w_cone: float = param(60.0, unit="value/rad", range=_NONNEGATIVE,
                          doc="further penalty per radian beyond the friction cone")
    w_pinch: float = param(20.0, unit="value", range=_NONNEGATIVE,
                           doc="penalty per unit of pinch above pinch_free")
    pinch_free: float = param(0.25, unit="-", range=_NONNEGATIVE, doc="pinch that does no harm")
    pinch_cap: float = param(2.0, unit="-", range=_NONNEGATIVE,
                             doc="pinch beyond this (twice self-locking) costs no more")
    w_trap: float = param(500.0, unit="value/m", range=_NONNEGATIVE,
                          doc="penalty per metre of escape height above trap_free")
    trap_free: float = param(0.008, unit="m", range=_NONNEGATIVE,
                             doc="escape height the swing's lift-off clears without catching")
    w_drop: float = param(1000.0, unit="value/m", range=_NONNEGATIVE,
                          doc="penalty per metre of drop-off depth above drop_free")
    drop_free: float = param(0.005, unit="m", range=_NONNEGATIVE,
                             doc="drop-off depth that does no harm (ball compliance, texture)")
    w_leg: float = param(300.0, unit="value/m", range=_NONNEGATIVE,
                         doc="penalty per metre of leg clearance below leg_safe")
    leg_safe: float = param(0.01, unit="m", range=_NONNEGATIVE,
                            doc="leg clearance wanted for placement errors and the swing")
    w_leg_collision: float = param(1500.0, unit="value/m", range=_NONNEGATIVE,
                                   doc="further penalty per metre of leg in the terrain")
    w_unknown: float = param(10.0, unit="value", range=_NONNEGATIVE,
                             doc="penalty for a foothold surrounded by missing data")
    # --- utilities of the pose terms
    w_progress: float = param(100.0, unit="value/m", range=_NONNEGATIVE,
                              doc="reward per metre of progress toward the goal")
    w_stance: float = param(0.0, unit="value/m", range=_NONNEGATIVE,
                            doc="penalty per metre of stance offset (0: the foot goes wherever "
                                "reach, stability and progress allow)")
    stance_lead: float = param(0.0, unit="m", range=_NONNEGATIVE,
                               doc="how far ahead of its default stance position (body frame) the "
                                   "gait-nominal foothold lies")
    w_stability: float = param(100.0, unit="value/m", range=_NONNEGATIVE,
                               doc="reward per metre of stability margin, up to stability_cap")
    stability_cap: float = param(0.05, unit="m", range=_NONNEGATIVE,
                                 doc="stability margins above this earn nothing more")
    w_reach: float = param(200.0, unit="value/m", range=_NONNEGATIVE,
                           doc="penalty per metre of reach margin below reach_safe")
    reach_safe: float = param(0.02, unit="m", range=_NONNEGATIVE,
                              doc="reach margin wanted (the body moves during the step)")
    w_joint: float = param(20.0, unit="value/rad", range=_NONNEGATIVE,
                           doc="penalty per radian of joint margin below joint_safe")
    joint_safe: float = param(0.15, unit="rad", range=_NONNEGATIVE, doc="joint margin wanted")
    unreachable_joint_margin: float = param(0.5, unit="rad", range=_NONNEGATIVE,
                                            doc="joint margin assigned where IK has no solution")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.slip_distance < self.ray_step:
            raise FootfallError("expert config: slip_distance must be at least ray_step")


# ----------------------------------------------------------------- geometry
@dataclass(frozen=True, eq=False)
class _Surface:
    """A sphere's centre-height surface on a window of map cells (see :func:`_sphere_surface`)."""

    filled: np.ndarray  # (wx, wy) [m] centre heights, 0 where unknown
    known: np.ndarray  # (wx, wy) 1.0 where the height is known, else 0.0
    origin: np.ndarray  # (2,) [m] position of window cell (0, 0)
    resolution: float  # [m/cell]
    complete: bool  # every height in the window is known

    def at(self, points: np.ndarray) -> np.ndarray:
        """Bilinear height [m] at points (..., 2); NaN outside the window or where unknown.

        The weights of corners with a known height are renormalised (as in
        :meth:`HeightMap.height_at`), but a point whose nearest cell is unknown is NaN.
        """
        f = (points - self.origin) / self.resolution
        wx, wy = self.filled.shape
        fi, fj = f[..., 0], f[..., 1]
        inside = (fi >= 0) & (fi <= wx - 1) & (fj >= 0) & (fj <= wy - 1)
        fi = np.where(inside, fi, 0.0)
        fj = np.where(inside, fj, 0.0)
        i0 = np.minimum(fi.astype(np.intp), wx - 2)
        j0 = np.minimum(fj.astype(np.intp), wy - 2)
        ti, tj = fi - i0, fj - j0
        flat = i0 * wy + j0
        corners = ((0, (1 - ti) * (1 - tj)), (wy, ti * (1 - tj)), (1, (1 - ti) * tj),
                   (wy + 1, ti * tj))
        num = np.zeros(fi.shape)
        for step, w in corners:
            num += w * np.take(self.filled, flat + step)
        out = np.full(fi.shape, np.nan)
        if self.complete:  # the common case: every height in the window is known
            return np.where(inside, num, out)
        den = np.zeros(fi.shape)
        for step, w in corners:
            den += w * np.take(self.known, flat + step)
        nearest = np.take(self.known,
                          np.rint(fi).astype(np.intp) * wy + np.rint(fj).astype(np.intp))
        good = inside & (nearest > 0) & (den > 0)
        np.divide(num, den, out=out, where=good)
        return out


_BOARD_SURFACES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
# map -> {radius [m]: (filled, known)}: each map's sphere surface, dilated once over the whole map


def _board_surface(hmap: HeightMap, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The sphere's centre-height surface over the whole map: (heights [m], 0 where unknown;
    1.0 where known), computed once per map and radius (a map's heights are read-only)."""
    per_map = _BOARD_SURFACES.setdefault(hmap, {})
    if radius not in per_map:
        surface = ball_centre_surface(hmap.heights, hmap.resolution, radius)
        known = np.isfinite(surface)
        filled = np.where(known, surface, 0.0)
        filled.setflags(write=False)
        per_map[radius] = (filled, known)
    return per_map[radius]


def _sphere_surface(hmap: HeightMap, lo: np.ndarray, hi: np.ndarray, radius: float
                    ) -> _Surface | None:
    """Centre height [m] of a sphere of ``radius`` [m] lowered onto the map, on a window of cells.

    ``B(c) = max over cells c' within radius of h(c') + sqrt(radius^2 - |c - c'|^2)``, a
    grey-scale dilation of the heights by the sphere. Covers at least the positions
    in [lo, hi] (x, y) [m] that lie on the map; the window is padded by the
    sphere's reach, so every value sampled inside [lo, hi] is the whole map's
    (:func:`_board_surface`, dilated once per map: the maximum over the same cells,
    bit for bit), and only the map's own border truncates (beyond it there is nothing
    to touch). Cells are points at their centres; cells without data give no
    support; where no cell with data lies within ``radius``, the height is
    unknown. ``None`` if nothing in the window is known.
    """
    res = hmap.resolution
    reach = int(math.ceil(radius / res))
    nx, ny = hmap.shape
    lo_idx = np.floor((np.asarray(lo) - hmap.origin) / res).astype(int) - reach - 1
    hi_idx = np.ceil((np.asarray(hi) - hmap.origin) / res).astype(int) + reach + 2
    i0, j0 = max(lo_idx[0], 0), max(lo_idx[1], 0)
    i1, j1 = min(hi_idx[0], nx), min(hi_idx[1], ny)
    if i1 - i0 < 2 or j1 - j0 < 2:
        return None
    filled, known = _board_surface(hmap, radius)
    known = known[i0:i1, j0:j1]
    if not known.any():
        return None
    return _Surface(filled[i0:i1, j0:j1], known.astype(np.float64),
                    np.array([hmap.origin[0] + i0 * res, hmap.origin[1] + j0 * res]), res,
                    bool(known.all()))


def _sample(surface: _Surface | None, points: np.ndarray) -> np.ndarray:
    """Height [m] of a sphere surface at points (..., 2); NaN where unknown."""
    if surface is None:
        return np.full(points.shape[:-1], np.nan)
    return surface.at(points)


def _no_data(hmap: HeightMap, points: np.ndarray) -> np.ndarray:
    """Whether the map has no data at points (..., 2) [m]: off the map or a NaN cell."""
    idx = hmap.position_to_index(points)
    nx, ny = hmap.shape
    inside = (idx[..., 0] >= 0) & (idx[..., 0] < nx) & (idx[..., 1] >= 0) & (idx[..., 1] < ny)
    i = np.clip(idx[..., 0], 0, nx - 1)
    j = np.clip(idx[..., 1], 0, ny - 1)
    return ~inside | np.isnan(hmap.heights[i, j])


def _terrain_terms(hmap: HeightMap, f: np.ndarray, cfg: ExpertConfig, robot: RobotDescription
                   ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The ball-foot terms of candidates f (n, 3) and the seated ball-centre heights (n,) [m]."""
    n = f.shape[0]
    r = robot.foot_radius
    k = int(cfg.directions)
    angles = 2 * np.pi * np.arange(k) / k
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])  # (K, 2); dirs[k + K/2] = -dirs[k]
    longest = max(cfg.slip_distance, cfg.pinch_distance, cfg.trap_radius, cfg.edge_radius,
                  cfg.unknown_radius)
    near_reach = max(cfg.slip_distance, cfg.pinch_distance)
    s_near = cfg.ray_step * np.arange(1, int(math.floor(near_reach / cfg.ray_step + 1e-9)) + 1)
    s_far = np.arange(s_near[-1] + cfg.far_step, longest + cfg.far_step - 1e-12, cfg.far_step)
    s = np.concatenate([s_near, s_far])  # (J,) [m] distances of the samples along each ray

    xy = f[:, :2]
    ball = _sphere_surface(hmap, xy.min(axis=0) - longest, xy.max(axis=0) + longest, r)
    seat = _sample(ball, xy)  # (n,) [m] seated ball-centre height
    # A ball with no data under it at all sits one radius above the candidate's given
    # height, or above 0 if that is unknown too (its `unknown` term is then 1).
    seat = np.where(np.isnan(seat), np.nan_to_num(f[:, 2], nan=0.0) + r, seat)
    rays = xy[:, None, None, :] + s[None, None, :, None] * dirs[None, :, None, :]  # (n, K, J, 2)
    rise = _sample(ball, rays) - seat[:, None, None]  # (n, K, J) [m]
    # Samples with no ball surface (no data) count as level ground: neither wall nor drop.
    rise = np.nan_to_num(rise, nan=0.0)
    secant = rise / s  # [-]

    # Slip: the weakest direction's steepest secant within the slip distance.
    near = (s >= 0.5 * cfg.slip_distance - 1e-12) & (s <= cfg.slip_distance + 1e-12)
    if not near.any():
        near = s == s[0]
    hold = secant[:, :, near].max(axis=2).min(axis=1)  # (n,) [-]
    phi = math.atan(robot.foot_friction)
    slip_margin = phi + np.arctan(hold)

    # Pinch: opposite contact normals, both tilted; the most pinching pair.
    jp = int(np.argmin(np.abs(s - cfg.pinch_distance)))
    tilt = secant[:, :, jp]  # (n, K) tan of the contact normal resisting a push along each ray
    pair = np.minimum(tilt[:, : k // 2], tilt[:, k // 2:])
    pinch = robot.foot_friction * np.clip(pair.max(axis=1), 0.0, None)

    # Trap: the least, over directions, of the highest rise within the trap radius.
    in_trap = s <= cfg.trap_radius + 1e-12
    trap_depth = np.clip(rise[:, :, in_trap].max(axis=2).min(axis=1), 0.0, None)

    # Drop-off: the ball-centre surface falling below a cone of the walkable slope, weighted
    # by how likely a slip that far is (linearly less likely, to nothing at the edge radius).
    in_edge = s < cfg.edge_radius
    fall = -rise[:, :, in_edge] - cfg.walkable_slope * s[in_edge]
    drop_off = np.clip((fall * (1.0 - s[in_edge] / cfg.edge_radius)).max(axis=(1, 2)), 0.0, None)

    # Missing data around the foothold (its own cell included).
    in_unknown = s <= cfg.unknown_radius + 1e-12
    probe = np.concatenate([xy[:, None, :], rays[:, :, in_unknown].reshape(n, -1, 2)], axis=1)
    unknown = _no_data(hmap, probe).mean(axis=1)

    terms = {"slip_margin": slip_margin, "pinch": pinch, "trap_depth": trap_depth,
             "drop_off": drop_off, "unknown": unknown}
    return terms, seat


def _leg_terms(hmap: HeightMap, state: RobotState, f: np.ndarray, seat: np.ndarray,
               cfg: ExpertConfig, robot: RobotDescription) -> dict[str, np.ndarray]:
    """Reach, joint margin and knee/shin clearance with the ball seated at ``seat`` (n,) [m]."""
    leg = robot.leg(state.swing_leg)
    centre = np.column_stack([f[:, :2], seat])  # (n, 3) world [m]
    local = world_to_body(centre, state.body_position, state.body_rpy)
    q, _ = inverse_kinematics(leg, local, robot)
    reach_margin = robot.max_reach - np.linalg.norm(local - np.asarray(leg.hip), axis=1)
    joint_margin = joint_limit_margin(leg, q)
    solved = np.isfinite(joint_margin)
    joint_margin = np.where(solved, joint_margin, -cfg.unreachable_joint_margin)

    # Where the seated ball is out of reach, the leg posture at the candidate's own height
    # (which the candidate generator checked) stands in for the clearance check.
    nominal_world = np.column_stack([centre[:, :2], np.nan_to_num(f[:, 2], nan=0.0)
                                     + robot.foot_radius])
    nominal = world_to_body(nominal_world, state.body_position, state.body_rpy)
    q_nominal, _ = inverse_kinematics(leg, nominal, robot)
    q_leg = np.where(solved[:, None], q, q_nominal)
    knee = body_to_world(knee_position(leg, q_leg, robot), state.body_position, state.body_rpy)
    foot = np.where(solved[:, None], centre, nominal_world)
    rho = robot.lower_leg_radius
    end = 1.0 - (robot.foot_radius + rho) / robot.lower_leg  # stop where the shin meets the ball
    t = np.linspace(0.0, end, int(cfg.leg_samples))
    spheres = knee[:, None, :] + t[None, :, None] * (foot - knee)[:, None, :]  # (n, S, 3)
    ok = np.isfinite(spheres).all(axis=(1, 2))
    if ok.any():
        pts = spheres[ok].reshape(-1, 3)
        shin = _sphere_surface(hmap, pts[:, :2].min(axis=0), pts[:, :2].max(axis=0), rho)
    else:
        shin = None
    ground = _sample(shin, np.nan_to_num(spheres[..., :2]))
    # No data under a sphere: no obstacle (as in the pose features).
    gap = np.where(np.isnan(ground), np.inf, spheres[..., 2] - ground).min(axis=1)
    # No posture at all (neither seated nor nominal solvable): counted as touching.
    leg_clearance = np.where(ok, np.minimum(gap, cfg.leg_clearance_cap), 0.0)
    return {"leg_clearance": leg_clearance, "reach_margin": reach_margin,
            "joint_margin": joint_margin}


def _pose_terms(state: RobotState, f: np.ndarray, cfg: ExpertConfig, robot: RobotDescription
                ) -> dict[str, np.ndarray]:
    """Progress toward the goal, offset from the gait-nominal stance, and the stability margin."""
    n = f.shape[0]
    s = state.swing_index
    xy = f[:, :2]
    body_xy = state.body_position[:2]
    to_goal = state.goal - body_xy
    dist = np.linalg.norm(to_goal)
    goal_dir = to_goal / dist if dist > 1e-9 else np.array([np.cos(state.yaw), np.sin(state.yaw)])
    progress = (xy - state.feet[s, :2]) @ goal_dir
    c, sn = math.cos(state.yaw), math.sin(state.yaw)
    nominal = np.asarray(robot.nominal_foot(state.swing_leg)[:2]) + (cfg.stance_lead, 0.0)
    target = body_xy + np.array([c * nominal[0] - sn * nominal[1], sn * nominal[0] + c * nominal[1]])
    stance_offset = np.linalg.norm(xy - target, axis=1)
    after = np.broadcast_to(state.feet[:, :2], (n, 4, 2)).copy()
    after[:, s] = xy
    order = list(robot.gait_order)
    margins = []
    for ahead in (1, 2):  # the next two swings of the crawl gait
        lifted = LEG_NAMES.index(order[(order.index(state.swing_leg) + ahead) % 4])
        inradius, _ = triangle_margins(after[:, [j for j in range(4) if j != lifted]], body_xy)
        margins.append(inradius)
    return {"progress": progress, "stance_offset": stance_offset,
            "stability": np.minimum(*margins)}


def _terrain_utilities(terms: dict[str, np.ndarray], cfg: ExpertConfig, robot: RobotDescription
                       ) -> dict[str, np.ndarray]:
    """The terrain terms' shares of the value [value units]; 0 on flat, open, scanned ground."""
    phi = math.atan(robot.foot_friction)
    m = terms["slip_margin"]
    return {
        "slip_margin": (cfg.w_hold * np.clip(m - phi, 0.0, cfg.hold_cap)
                        - cfg.w_slope * np.clip(phi - m, 0.0, phi)
                        - cfg.w_cone * np.clip(-m, 0.0, None)),
        "pinch": -cfg.w_pinch * np.clip(np.minimum(terms["pinch"], cfg.pinch_cap) - cfg.pinch_free,
                                        0.0, None),
        "trap_depth": -cfg.w_trap * np.clip(terms["trap_depth"] - cfg.trap_free, 0.0, None),
        "drop_off": -cfg.w_drop * np.clip(terms["drop_off"] - cfg.drop_free, 0.0, None),
        "unknown": -cfg.w_unknown * terms["unknown"],
    }


def _contributions(terms: dict[str, np.ndarray], cfg: ExpertConfig, robot: RobotDescription
                   ) -> dict[str, np.ndarray]:
    """Each term's share of the value [value units], in the order of :data:`EXPERT_TERM_NAMES`."""
    leg = terms["leg_clearance"]
    parts = {
        **_terrain_utilities(terms, cfg, robot),
        "leg_clearance": (-cfg.w_leg * np.clip(cfg.leg_safe - leg, 0.0, None)
                          - cfg.w_leg_collision * np.clip(-leg, 0.0, None)),
        "progress": cfg.w_progress * terms["progress"],
        "stance_offset": -cfg.w_stance * terms["stance_offset"],
        "stability": cfg.w_stability * np.minimum(terms["stability"], cfg.stability_cap),
        "reach_margin": -cfg.w_reach * np.clip(cfg.reach_safe - terms["reach_margin"], 0.0, None),
        "joint_margin": -cfg.w_joint * np.clip(cfg.joint_safe - terms["joint_margin"], 0.0, None),
    }
    return {name: parts[name] for name in EXPERT_TERM_NAMES}


def _worst_placement(hmap: HeightMap, f: np.ndarray, yaw: float, cfg: ExpertConfig,
                     robot: RobotDescription) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Terrain terms where the foot fares worst, and the seat (n,) [m] at the foothold itself.

    The terrain terms of candidates f (n, 3) are computed, in one pass, at f and
    at f shifted ``placement_error`` [m] forward and backward along the heading
    ``yaw`` [rad]; for each candidate, all of them are taken from the placement
    whose terrain utilities sum lowest (ties: the foothold itself, then forward).
    """
    n = f.shape[0]
    if cfg.placement_error == 0:
        return _terrain_terms(hmap, f, cfg, robot)
    shift = cfg.placement_error * np.array([math.cos(yaw), math.sin(yaw), 0.0])
    # A shifted ball without data under it falls back to the candidate's own height.
    terms, seat = _terrain_terms(hmap, np.concatenate([f, f + shift, f - shift]), cfg, robot)
    score = sum(_terrain_utilities(terms, cfg, robot).values()).reshape(3, n)
    worst = np.argmin(score, axis=0)  # first minimum: the foothold itself on ties
    cols = np.arange(n)
    return {name: v.reshape(3, n)[worst, cols] for name, v in terms.items()}, seat[:n]


WALKER_PLACEMENT_ERROR: float = 0.007
"""[m] The walking expert's placement error: about the mean slip per foothold of footfall's
walker on flat ground (6.1 +- 1.7 mm over 21 runs, docs/reproduce)."""


def walking_expert(lead: float, placement_error: float = WALKER_PLACEMENT_ERROR) -> ExpertConfig:
    """The synthetic expert as it judges a fixed-advance gait's steps: the foot where the gait needs it.

    The default expert values every centimetre of progress toward the goal,
    so among a step's candidate set (everything the leg can reach) it picks the
    farthest good foothold, and reaches inward to find one. footfall's walking
    controller advances the body a fixed distance per step whatever the
    foothold, so a long step gains nothing: it leaves the foot far ahead of its
    hip and the next support triangles long and thin. A human expert
    correcting this robot would know its gait. This expert values no progress,
    and instead loses one value unit per centimetre a foothold lies from the
    leg's gait-nominal position (its default stance around the body, ``lead``
    [m] ahead: where the footstep planner aims), traded against the terrain
    terms, stability and reach as before.

    It also knows that this robot's feet do not land exactly where they are
    sent: it judges the terrain where the foot would fare worst within
    ``placement_error`` [m] ahead of or behind the foothold along the heading
    (see :attr:`ExpertConfig.placement_error`), so a foothold a few mm from a
    riser's edge or a pit's rim is judged by the edge or the rim.
    """
    for name, v in (("stance lead", lead), ("placement error", placement_error)):
        if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise FootfallError(f"the {name} must be a number >= 0 [m], got {v!r}")
    base = ExpertConfig()
    return replace(base, w_progress=0.0, w_stance=base.w_progress, stance_lead=float(lead),
                   placement_error=float(placement_error))


RECENT_CANDIDATE_SETS = 64  # [-] candidate sets whose terrain terms an expert keeps


class SyntheticExpert:
    """A hand-made foothold judge whose choices serve as expert demonstrations.

    Parameters
    ----------
    config : ExpertConfig
        Weights, thresholds and the imperfection of the choices.
    robot : RobotDescription
        The robot whose foot radius, friction, leg geometry and gait are used.
    """

    def __init__(self, config: ExpertConfig = ExpertConfig(), robot: RobotDescription = LITTLEDOG):
        self.config = config
        self.robot = robot
        # The terrain terms of recent candidate sets: a walk's look-ahead judges the same
        # footholds again from the next steps (about 45 % of the calls on rocks).
        self._recent: OrderedDict = OrderedDict()

    def _terrain(self, hmap: HeightMap, f: np.ndarray, yaw: float
                 ) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """:func:`_worst_placement` of candidates ``f`` at heading ``yaw``, remembered."""
        key = (id(hmap), float(yaw), f.tobytes())
        hit = self._recent.get(key)
        if hit is not None and hit[0] is hmap:
            self._recent.move_to_end(key)
        else:
            hit = (hmap, _worst_placement(hmap, f, yaw, self.config, self.robot))
            self._recent[key] = hit
            if len(self._recent) > RECENT_CANDIDATE_SETS:
                self._recent.popitem(last=False)
        terms, seat = hit[1]
        return {name: v.copy() for name, v in terms.items()}, seat.copy()

    def _check(self, candidates: np.ndarray) -> np.ndarray:
        f = np.asarray(candidates, dtype=np.float64)
        if f.ndim != 2 or f.shape[1] != 3:
            raise FootfallError(f"candidates must have shape (n, 3), got {f.shape}")
        if not np.isfinite(f[:, :2]).all():
            raise FootfallError("candidate x, y must be finite (a height may be NaN)")
        return f

    def terms(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray
              ) -> dict[str, np.ndarray]:
        """The expert's raw judgement terms of each candidate, named as in :data:`EXPERT_TERMS`.

        Parameters
        ----------
        hmap : HeightMap
            The terrain (any resolution; 1 mm scans are judged cell by cell).
        state : RobotState
            Feet, body pose, swing leg and goal.
        candidates : array of shape (n, 3)
            Candidate contact points [m]: x, y, terrain height. The height is
            only a fallback (the ball's seat is found from the map) and may
            be NaN; x and y must be finite.

        Returns
        -------
        dict of str -> array of shape (n,)
            Finite values in the units of :data:`EXPERT_TERMS`, in its order.
        """
        f = self._check(candidates)
        cfg, robot = self.config, self.robot
        if f.shape[0] == 0:
            return {name: np.zeros(0) for name in EXPERT_TERM_NAMES}
        terrain, seat = self._terrain(hmap, f, state.yaw)
        out = {**terrain, **_leg_terms(hmap, state, f, seat, cfg, robot),
               **_pose_terms(state, f, cfg, robot)}
        return {name: out[name] for name in EXPERT_TERM_NAMES}

    def utilities(self, terms: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Each term's share of the value [value units, 1 = 1 cm of progress], shapes (n,).

        ``terms`` as returned by :meth:`terms`. The utilities, with
        phi = atan(foot_friction) and m the slip margin:

        * slip_margin: ``w_hold * clip(m - phi, 0, hold_cap) - w_slope * clip(phi - m, 0, phi)
          - w_cone * max(-m, 0)``: concave -- a hollow earns a capped bonus, a slanted face
          a penalty, a face beyond the friction cone a much steeper one.
        * pinch, trap_depth, drop_off: ``-w * max(term - free, 0)`` (harmless up to ``free``;
          pinch counted up to ``pinch_cap``).
        * leg_clearance: ``-w_leg * max(leg_safe - c, 0) - w_leg_collision * max(-c, 0)``.
        * unknown: ``-w_unknown * fraction``.
        * progress: ``w_progress * progress``; stance_offset: ``-w_stance * offset``; stability: ``w_stability * min(margin, cap)``.
        * reach_margin, joint_margin: ``-w * max(safe - margin, 0)``.

        The terrain utilities are 0 on flat, open, fully scanned ground.
        """
        return _contributions(terms, self.config, self.robot)

    def contributions(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray
                      ) -> dict[str, np.ndarray]:
        """Each term's share of the value of each candidate (see :meth:`utilities`)."""
        return self.utilities(self.terms(hmap, state, candidates))

    def values(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray) -> np.ndarray:
        """Noiseless value of each candidate, shape (n,), higher is better, always finite."""
        parts = self.contributions(hmap, state, candidates)
        return np.sum(np.stack(list(parts.values())), axis=0)

    def choose(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray,
               rng: np.random.Generator) -> int:
        """Index of the demonstrated foothold in ``candidates``, with the expert's imperfection.

        Draws, in this order, one uniform number and one standard normal per
        candidate from ``rng`` (always, so the stream advances the same way
        whatever the settings); adds ``noise`` times the normals to the
        values; returns the best of the noisy values, or with probability
        ``second_best_prob`` the second best. Ties go to the lower index.
        """
        v = self.values(hmap, state, candidates)
        if v.shape[0] == 0:
            raise FootfallError("the expert cannot choose from an empty candidate set")
        u = rng.random()
        noisy = v + self.config.noise * rng.standard_normal(v.shape[0])
        order = np.argsort(-noisy, kind="stable")
        if v.shape[0] > 1 and u < self.config.second_best_prob:
            return int(order[1])
        return int(order[0])
