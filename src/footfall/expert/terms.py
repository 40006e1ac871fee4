"""The synthetic expert's terms: each a small vectorised function of the candidates, with its unit.

:data:`EXPERT_TERMS` names every term of the judgement with its unit and
meaning; the terrain terms are read from the ball-centre surface
(:mod:`footfall.core.sphere_surface`), the leg terms from the inverse kinematics,
the pose terms from the state; :func:`contributions` turns the terms into
each one's share of the value [value units]. The weights and thresholds are an
:class:`~footfall.expert.synthetic.ExpertConfig`; docs/expert.md explains
every number.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from footfall.core.clearance import leg_gaps
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import (
    body_to_world,
    inverse_kinematics,
    joint_limit_margin,
    knee_position,
    world_to_body,
)
from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.core.sphere_surface import board_sphere, sample_surface
from footfall.core.state import RobotState, stance_target
from footfall.expert.rays import RaySamples, no_data_share, ray_terms
from footfall.features.pose_features import triangle_margins

if TYPE_CHECKING:  # the settings live with the expert, which computes its terms here
    from footfall.expert.synthetic import ExpertConfig

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
    "crown": "[m] how far the seated ball centre stands above the mean height of the ball-centre "
             "surface on a ring of crown_radius around the foothold (16 directions, samples "
             "without data skipped; 0 where none has data): > 0 on a crest or a rock's top, where "
             "the ground falls away whichever way the ball slides and falls faster the farther it "
             "goes; < 0 in a hollow. Read at the foothold itself, never at a placement error",
    "riser_ahead": "[m] the riser the swing leaving the foothold must climb at once: largest "
                   "rise of the ball-centre surface ahead along the heading at distance s up to "
                   "riser_distance, weighted by (1 - s / riser_distance) (the swing lifts "
                   "nearly straight up, and a ball beside a wall catches its edge)",
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


def ray_directions(cfg: ExpertConfig) -> np.ndarray:
    """The ``cfg.directions`` unit ray directions (K, 2) around a foothold; dirs[k + K/2] = -dirs[k]."""
    k = int(cfg.directions)
    angles = 2 * np.pi * np.arange(k) / k
    return np.column_stack([np.cos(angles), np.sin(angles)])


def crown_term(hmap: HeightMap, xy: np.ndarray, seat: np.ndarray, cfg: ExpertConfig,
               robot: RobotDescription) -> np.ndarray:
    """The crown (n,) [m] of footholds xy (n, 2) [m] whose seated ball centres are ``seat`` (n,)
    [m]: the seat less the mean of the ball-centre surface on the ring of ``crown_radius``
    (samples without data skipped; 0 where none has data)."""
    ring = xy[:, None, :] + cfg.crown_radius * ray_directions(cfg)[None, :, :]  # (n, K, 2) [m]
    around = sample_surface(board_sphere(hmap, robot.foot_radius), ring)
    seen = np.isfinite(around).any(axis=1)
    mean = np.nanmean(np.where(seen[:, None], around, 0.0), axis=1)
    return np.where(seen, seat - mean, 0.0)


def terrain_terms(hmap: HeightMap, f: np.ndarray, cfg: ExpertConfig, robot: RobotDescription,
                  yaw: float = 0.0) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The ball-foot terms of candidates f (n, 3) and the seated ball-centre heights (n,) [m];
    ``yaw`` [rad] is the heading the swing leaving a foothold takes (the riser term)."""
    n = f.shape[0]
    r = robot.foot_radius
    dirs = ray_directions(cfg)
    xy = f[:, :2]
    ball = board_sphere(hmap, r)
    seat = sample_surface(ball, xy)  # (n,) [m] seated ball-centre height
    # A ball with no data under it at all sits one radius above the candidate's given
    # height, or above 0 if that is unknown too (its `unknown` term is then 1).
    seat = np.where(np.isnan(seat), np.nan_to_num(f[:, 2], nan=0.0) + r, seat)
    rays = RaySamples.of(cfg)
    hold, pair, trap, drop = ray_terms(ball, xy, seat, dirs, rays)
    slip_margin = math.atan(robot.foot_friction) + np.arctan(hold)
    pinch = robot.foot_friction * np.clip(pair, 0.0, None)
    trap_depth = np.clip(trap, 0.0, None)
    drop_off = np.clip(drop, 0.0, None)

    # Riser ahead: the ball-centre surface rising along the heading, nearer counting more.
    ahead = np.arange(1, int(math.floor(cfg.riser_distance / cfg.far_step + 1e-9)) + 1) * cfg.far_step
    if ahead.size:
        heading = np.array([math.cos(yaw), math.sin(yaw)])
        up = sample_surface(ball, xy[:, None, :] + ahead[None, :, None] * heading) - seat[:, None]
        riser_ahead = np.clip((np.nan_to_num(up, nan=0.0)
                               * (1.0 - ahead / cfg.riser_distance)).max(axis=1), 0.0, None)
    else:
        riser_ahead = np.zeros(n)

    # Missing data around the foothold (its own cell included).
    unknown = no_data_share(hmap.heights, hmap.origin[0], hmap.origin[1], hmap.resolution,
                            np.ascontiguousarray(xy), dirs, rays.unknown)

    terms = {"slip_margin": slip_margin, "pinch": pinch, "trap_depth": trap_depth,
             "drop_off": drop_off, "riser_ahead": riser_ahead, "unknown": unknown}
    return terms, seat


def leg_terms(hmap: HeightMap, state: RobotState, f: np.ndarray, seat: np.ndarray,
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
    # No data under a sphere: no obstacle (as in the pose features).
    gap = leg_gaps(hmap, knee, foot, robot, cfg.leg_samples)
    # No posture at all (neither seated nor nominal solvable): counted as touching.
    ok = np.isfinite(knee).all(axis=1) & np.isfinite(foot).all(axis=1)
    leg_clearance = np.where(ok, np.minimum(gap, cfg.leg_clearance_cap), 0.0)
    return {"leg_clearance": leg_clearance, "reach_margin": reach_margin,
            "joint_margin": joint_margin}


def pose_terms(state: RobotState, f: np.ndarray, cfg: ExpertConfig, robot: RobotDescription
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
    stance_offset = np.linalg.norm(xy - stance_target(state, robot, cfg.stance_lead), axis=1)
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


def terrain_utilities(terms: dict[str, np.ndarray], cfg: ExpertConfig, robot: RobotDescription
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
        "riser_ahead": -cfg.w_riser * np.clip(terms["riser_ahead"] - cfg.riser_free, 0.0, None),
        "unknown": -cfg.w_unknown * terms["unknown"],
    }


def contributions(terms: dict[str, np.ndarray], cfg: ExpertConfig, robot: RobotDescription
                   ) -> dict[str, np.ndarray]:
    """Each term's share of the value [value units], in the order of :data:`EXPERT_TERM_NAMES`."""
    leg = terms["leg_clearance"]
    parts = {
        **terrain_utilities(terms, cfg, robot),
        "crown": -cfg.w_crown * np.clip(terms["crown"] - cfg.crown_free, 0.0, None),
        "leg_clearance": (-cfg.w_leg * np.clip(cfg.leg_safe - leg, 0.0, None)
                          - cfg.w_leg_collision * np.clip(-leg, 0.0, None)),
        "progress": cfg.w_progress * terms["progress"],
        "stance_offset": -cfg.w_stance * terms["stance_offset"],
        "stability": cfg.w_stability * np.minimum(terms["stability"], cfg.stability_cap),
        "reach_margin": -cfg.w_reach * np.clip(cfg.reach_safe - terms["reach_margin"], 0.0, None),
        "joint_margin": -cfg.w_joint * np.clip(cfg.joint_safe - terms["joint_margin"], 0.0, None),
    }
    return {name: parts[name] for name in EXPERT_TERM_NAMES}


def worst_placement(hmap: HeightMap, f: np.ndarray, yaw: float, cfg: ExpertConfig,
                     robot: RobotDescription) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Terrain terms where the foot fares worst, and the seat (n,) [m] at the foothold itself.

    The terrain terms of candidates f (n, 3) are computed, in one pass, at f and
    at f shifted ``placement_error`` [m] forward and backward along the heading
    ``yaw`` [rad]; for each candidate, all of them are taken from the placement whose
    terrain utilities sum lowest (ties: the foothold itself, then forward). The crown
    (:func:`crown_term`) is read at f alone and plays no part in that choice: it reads the
    ground 2 cm around, where a placement a few mm off would only move it onto a wall's edge.
    With ``roll_back`` [m] set, a shifted placement whose seat is more than that
    above the foothold's own does not count: the ground between falls toward the
    foothold, and a ball set there slides back to it -- unless, with ``roll_back_wall``
    [-], it rises more than that times the placement error: a wall, whose edge or top the
    ball lands on.
    """
    n = f.shape[0]
    if cfg.placement_error == 0:
        terms, seat = terrain_terms(hmap, f, cfg, robot, yaw)
        return {**terms, "crown": crown_term(hmap, f[:, :2], seat, cfg, robot)}, seat
    shift = cfg.placement_error * np.array([math.cos(yaw), math.sin(yaw), 0.0])
    # A shifted ball without data under it falls back to the candidate's own height.
    terms, seat = terrain_terms(hmap, np.concatenate([f, f + shift, f - shift]), cfg, robot, yaw)
    score = sum(terrain_utilities(terms, cfg, robot).values()).reshape(3, n)
    if cfg.roll_back is not None:
        rise = seat.reshape(3, n)[1:] - seat[:n]  # (2, n) [m] of the shifted seats over f's
        back = rise > cfg.roll_back
        if cfg.roll_back_wall is not None:
            back &= rise <= cfg.roll_back_wall * cfg.placement_error
        score[1:] = np.where(back, np.inf, score[1:])
    worst = np.argmin(score, axis=0)  # first minimum: the foothold itself on ties
    cols = np.arange(n)
    out = {name: v.reshape(3, n)[worst, cols] for name, v in terms.items()}
    return {**out, "crown": crown_term(hmap, f[:, :2], seat[:n], cfg, robot)}, seat[:n]
