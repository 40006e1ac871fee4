"""Footholds a leg should not take, judged over the stance that follows: the planner's checks.

A foothold is held for a whole gait cycle while the body passes over it, and
the leg's posture turns with it: a front foot set just before a bar leans
its shin onto the bar a stride on, a hind foot at the foot of a riser its
shin onto the riser's edge, a leg stretched forward at touch-down reaches
its joint limits as the body leaves it behind. The footstep planner
(:mod:`footfall.control.footstep`) drops from the candidate set F the
footholds that fail a check at touch-down or at the foot's next lift-off --
unless every one fails:

* the joint-limit margin (``FootstepConfig.joint_margin``):
  :func:`~footfall.features.candidates.joint_margins`;
* the leg clearance (``FootstepConfig.leg_clearance``): the knee and shin
  against the terrain, :func:`~footfall.features.candidates.leg_clearances`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, RobotDescription
from footfall.core.state import RobotState
from footfall.features.candidates import joint_margins, leg_clearances

if TYPE_CHECKING:
    from footfall.control.footstep import FootstepConfig


def stride_on(st0: RobotState, legs: Sequence[str], body_xy: np.ndarray,
              grounds: Sequence[float]) -> RobotState:
    """The predicted state a stride after ``st0``, at the swing foot's next lift-off.

    ``legs`` (K,), ``body_xy`` (K, 2) [m] and ``grounds`` (K,) [m] are the
    planner's next K steps (swing leg, body position at touch-down, median ground
    near the path-nominal foothold; NaN: no data), this one first; the last is a
    stride on with the planner's five steps. The body moves along the path to the
    last step's position, and rises or falls by a quarter of the change of
    ground of the three legs stepping in between (the body stands
    ``nominal_height`` above the feet's mean height).
    """
    others = [LEG_NAMES.index(leg) for leg in legs[1:4]]
    ground = np.asarray(grounds[1:1 + len(others)], dtype=np.float64)
    rise = float(np.nan_to_num(ground - st0.feet[others, 2]).sum()) / 4.0  # [m]
    moved = np.r_[np.asarray(body_xy[-1]) - np.asarray(body_xy[0]), rise]
    return replace(st0, body_position=st0.body_position + moved)


def stance_checks(hmap: HeightMap, st0: RobotState, later: RobotState, cand: np.ndarray,
                  keep: np.ndarray, config: FootstepConfig, robot: RobotDescription
                  ) -> np.ndarray:
    """``keep`` (n,) bool less the candidates (n, 3) [m] that fail a check of ``config`` with
    the body at touch-down (``st0``) or at the next lift-off (``later``, :func:`stride_on`);
    each check drops nothing if it would drop every kept candidate. A candidate the leg
    cannot reach at one of the two poses is judged at the other; at neither, it fails."""
    if config.joint_margin is not None:
        least = np.fmin(joint_margins(st0, cand, robot), joint_margins(later, cand, robot))
        keep = unless_none_left(keep, least >= config.joint_margin)
    if config.leg_clearance is not None:
        idx = np.flatnonzero(keep)  # a few hundred IK solutions at two poses, on the kept only
        least = np.full(cand.shape[0], np.nan)
        least[idx] = np.fmin(
            leg_clearances(hmap, st0, cand[idx], robot, config.leg_samples, config.leg_span),
            leg_clearances(hmap, later, cand[idx], robot, config.leg_samples,
                           config.leg_span))
        keep = unless_none_left(keep, least >= config.leg_clearance)
    return keep


def unless_none_left(keep: np.ndarray, passes: np.ndarray) -> np.ndarray:
    """``keep & passes``, or ``keep`` where that would leave nothing."""
    both = keep & passes
    return both if both.any() else keep
