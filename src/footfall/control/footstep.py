"""The footstep planner (paper §IV-B.2): the next foothold, with a five-step look-ahead.

Footholds are ranked by a foothold scorer (:mod:`footfall.features.scorer`:
its terrain part from dense grids computed once per map, its state part --
pose features, say -- for the predicted state) biased toward the body path: a candidate loses ``bias_weight`` reward
per metre it lies from its *path-nominal* position, the leg's default stance
position around the body as it will be in the middle of the foot's stance.
The planner predicts the body pose at the touch-down of each of the next
five steps of the crawl gait by advancing along the :class:`BodyPath`, and
picks the first foothold of the five-step sequence with the largest summed
reward (see :meth:`FootstepPlanner.plan` for the approximation).

With ``friction_safety`` set, every step's candidates lose the footholds where
a ball foot would not hold (:class:`~footfall.features.footing.FrictionCheck`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from footfall.control.body_path import BodyPath
from footfall.control.grids import grid_spacing, grid_values, terrain_grids
from footfall.control.stance_checks import stance_checks, stride_on, unless_none_left
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, above, at_least, param
from footfall.core.robot import DEFAULT_STRIDE, LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.core.sphere_surface import seen_under_sphere
from footfall.core.state import RobotState, feet_pitch
from footfall.core.validate import require_int
from footfall.features.candidates import lattice, reachable_footholds, reaches
from footfall.features.dense import ScoreGrid
from footfall.features.family import Candidates
from footfall.features.footing import FrictionCheck
from footfall.features.scorer import RewardFor
from footfall.features.spread import path_bias_weight

GRID_YAW = 0.0  # [rad] heading the planner's dense reward grids are computed for (+x)


class NoFootholdError(FootfallError):
    """The swing leg has no candidate foothold: the robot is stuck."""


@dataclass(frozen=True)
class FootstepConfig(Params):
    """Every knob of the footstep planner (docs/configuration.md)."""

    lookahead: int = param(5, unit="steps", range=at_least(1),
                           doc="steps planned ahead, the current one included (paper: five)")
    step_advance: float = param(DEFAULT_STRIDE / 4, unit="m", range=above(0),
                                doc="body advance along the path per step (stride / 4)")
    foot_lead: float | None = param(None, unit="m", range=at_least(0),
                                    doc="path distance from touch-down to the body pose whose "
                                        "default stance is the path-nominal foothold; None: "
                                        "half a stride (2 * step_advance)")
    bias_weight: float = param(30.0, unit="reward/m", range=at_least(0),
                               doc="reward lost per metre from the path-nominal position, in "
                                   "units of the hand-tuned default reward")
    spacing: float = param(0.005, unit="m", range=above(0),
                           doc="candidate lattice spacing (and of the reward grids)")
    beam_width: int = param(2, unit="-", range=at_least(1),
                            doc="best first steps compared by rolling out the look-ahead")
    root_separation: float = param(0.02, unit="m", range=at_least(0),
                                   doc="the first steps compared lie at least this far apart "
                                       "(3-D)")
    search_radius: float | None = param(None, unit="m", range=above(0),
                                        doc="the candidate set F: reachable footholds within "
                                            "this of the path-nominal position (None: every "
                                            "reachable one)")
    pose_candidates: int | None = param(128, unit="-", range=at_least(1),
                                        doc="first step: pose features of this many best by "
                                            "terrain + bias (None: of every candidate)")
    lookahead_radius: float = param(0.05, unit="m", range=above(0),
                                    doc="later steps consider footholds this close to their "
                                        "target")
    target_radius: float = param(0.02, unit="m", range=above(0),
                                 doc="a step's body is predicted over the terrain's median "
                                     "height within this of the swing foot's path-nominal "
                                     "position")
    lookahead_candidates: int = param(32, unit="-", range=at_least(1),
                                      doc="later steps: pose features of this many best by "
                                          "terrain + bias")
    heading_horizon: float = param(0.3, unit="m", range=above(0),
                                   doc="the body faces the path point this far ahead (about a "
                                       "body length)")
    heading_tolerance: float = param(0.25, unit="rad", range=above(0),
                                     doc="body headings within this of GRID_YAW score footholds "
                                         "from the grids; beyond it, exact patches (slow)")
    friction_safety: float | None = param(None, unit="-", range=at_least(1),
                                          doc="friction check: a foothold whose ball-foot "
                                              "contact tilts more than atan(foot friction / this) "
                                              "anywhere within footing_margin is dropped from F "
                                              "(unless none holds); None: no check")
    seen_footing: float | None = param(None, unit="m", range=above(0),
                                       doc="seen footing: a foothold within this of a place "
                                           "where the ball foot has no map data under it (a "
                                           "hole in a scan wider than the ball) is dropped from "
                                           "F (unless every one is); None: no check")
    joint_margin: float | None = param(None, unit="rad", range=above(0),
                                       doc="joint-limit margin: a foothold whose swing leg has "
                                           "a joint nearer its limit than this at touch-down or "
                                           "with the body at the look-ahead's last step (a "
                                           "stride on: its next lift-off) is dropped from F "
                                           "(unless every one is); None: no check")
    leg_clearance: float | None = param(None, unit="m",
                                        doc="leg clearance over the stance: a foothold whose "
                                            "swing leg's knee or shin would come nearer than "
                                            "this to the terrain at touch-down or with the body a "
                                            "stride on (its next lift-off) is dropped from F "
                                            "(unless every one is); None: no check")
    leg_samples: int = param(10, unit="-", range=at_least(2),
                             doc="the leg clearance's spheres along the lower leg, from the knee")
    leg_span: float | None = param(None, unit="-", range=above(0),
                                   doc="the leg clearance checks the lower leg from the knee "
                                       "down to this share of the way to the ball's centre; "
                                       "None: down to the ball")
    footing_margin: float = param(0.005, unit="m", range=at_least(0),
                                  doc="the friction check's footholds hold within this of them "
                                      "(one lattice spacing: the tilt between lattice points)")

    @property
    def lead(self) -> float:
        """The foot lead [m] in effect."""
        return 2.0 * self.step_advance if self.foot_lead is None else self.foot_lead


@dataclass(frozen=True, eq=False)
class FootstepPlan:
    """The planner's choice for the current swing leg, with its candidates and the steps after it."""

    leg: str  # the swing leg
    index: int  # index of the chosen foothold in candidates
    foothold: np.ndarray  # (3,) [m] chosen contact point: x, y, terrain height
    candidates: np.ndarray  # (n, 3) [m] the candidate set F of this step
    reward: np.ndarray  # (n,) reward of each candidate as the reward function defines it;
    # NaN where its pose part was not evaluated (outside the pose_candidates best)
    total: np.ndarray  # (n,) reward plus path bias (NaN like reward)
    value: np.ndarray  # (n,) total plus the totals of its look-ahead rollout; -inf: not rolled out
    legs: tuple[str, ...]  # (m,) legs of the planned steps, this one first (m <= lookahead)
    footholds: np.ndarray  # (m, 3) [m] planned footholds, footholds[0] == foothold
    body_xy: np.ndarray  # (m, 2) [m] predicted body position at each planned touch-down
    body_yaw: np.ndarray  # (m,) [rad] predicted body heading at each planned touch-down
    targets: np.ndarray  # (m, 2) [m] path-nominal position of each planned foothold
    state: RobotState | None = None  # the state F was computed for: the feet as they stand, the
    # body as predicted at this step's touch-down (every candidate is reachable from it)

    @property
    def steps(self) -> list[tuple[str, np.ndarray]]:
        """The planned steps as (leg, foothold (3,)) pairs, this one first."""
        return list(zip(self.legs, self.footholds))


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _diverse_best(score: np.ndarray, points: np.ndarray, count: int, separation: float) -> np.ndarray:
    """Indices of up to ``count`` best finite scores whose points (n, d) [m] lie ``separation`` apart."""
    ok = np.isfinite(score)
    ranked = np.argsort(-np.where(ok, score, -np.inf), kind="stable")[:int(ok.sum())]
    chosen: list[int] = []
    free = np.ones(ranked.size, dtype=bool)
    while len(chosen) < count and free.any():  # count (a few) picks, each vectorised
        k = int(np.argmax(free))
        chosen.append(int(ranked[k]))
        free &= np.sum((points[ranked] - points[ranked[k]]) ** 2, axis=1) >= separation ** 2
        free[k] = False
    return np.array(chosen, dtype=np.int64)


def path_heading(path: BodyPath, s: np.ndarray, horizon: float) -> np.ndarray:
    """Body heading [rad] at arc length s [m] (...): toward the path point ``horizon`` [m] ahead.

    Within ``horizon`` of the path's end, the heading of the last chord that
    long (of the path's end segment if the path is shorter).
    """
    s = np.asarray(s, dtype=np.float64)
    h = min(horizon, path.length)
    a = np.clip(s, 0.0, path.length - h)
    d = path.point_at(a + h) - path.point_at(a)
    return np.arctan2(d[..., 1], d[..., 0])


@dataclass(frozen=True, eq=False)
class _Horizon:
    """The planner's prediction of the next ``lookahead`` steps (K of them), this one first."""

    legs: list[str]  # (K,) swing leg of each step, in gait order
    body_xy: np.ndarray  # (K, 2) [m] body position on the path at each touch-down
    body_yaw: np.ndarray  # (K,) [rad] body heading at each touch-down
    targets: np.ndarray  # (K, 2) [m] path-nominal foothold of each step
    grounds: list[float]  # (K,) [m] median terrain height near each target; NaN: no data


class FootstepPlanner:
    """Plans footholds along a body path with a reward function.

    Parameters
    ----------
    hmap : HeightMap
        The terrain.
    reward_for : callable
        ``reward_for(leg_name) -> FootholdScorer``; called once per leg here.
    path : BodyPath
        The body path to follow.
    robot : RobotDescription
        Stance, gait order and kinematics.
    config : FootstepConfig
        The planner's knobs.
    grids : dict, optional
        :func:`~footfall.control.body_path.terrain_grids` of the map at
        ``config.spacing`` and heading ``GRID_YAW`` (e.g. shared with the body
        path planner); computed here if not given.
    """

    def __init__(self, hmap: HeightMap, reward_for: RewardFor, path: BodyPath,
                 robot: RobotDescription = LITTLEDOG, config: FootstepConfig = FootstepConfig(),
                 grids: dict[str, ScoreGrid] | None = None) -> None:
        if not isinstance(hmap, HeightMap):
            raise FootfallError(f"the footstep planner needs a HeightMap, got {type(hmap).__name__}")
        if not isinstance(path, BodyPath):
            raise FootfallError(f"the footstep planner needs a BodyPath, got {type(path).__name__}")
        self.hmap = hmap
        self.path = path
        self.robot = robot
        self.config = config
        self.rewards_ = {name: reward_for(name) for name in LEG_NAMES}
        if grids is None:
            grids = terrain_grids(hmap, self.rewards_.__getitem__, robot, config.spacing, GRID_YAW)
        for name in LEG_NAMES:
            if name not in grids or abs(grid_spacing(grids[name]) - config.spacing) > 1e-9:
                raise FootfallError(f"the reward grids must cover every leg at spacing "
                                    f"{config.spacing} m")
        self.grids_ = dict(grids)
        self._posed = {name: r.has_state_part for name, r in self.rewards_.items()}
        self.bias_ = self._bias_weights()
        self.friction_ = None if config.friction_safety is None else FrictionCheck.of(
            hmap, config.spacing, robot, config.friction_safety, config.footing_margin)

    def _bias_weights(self) -> dict[str, float]:
        """Path bias [reward/m] per leg: ``bias_weight`` scaled to each reward's spread
        (:func:`~footfall.features.spread.path_bias_weight`)."""
        return {name: path_bias_weight(r, self.config.bias_weight)
                for name, r in self.rewards_.items()}

    # -------------------------------------------------------------- pieces
    def _terrain(self, leg: str, footholds: np.ndarray, yaw: float) -> np.ndarray:
        """Terrain reward (n,) of footholds (n, 3) at body heading yaw [rad]; -inf: invalid."""
        if abs(_wrap(yaw - GRID_YAW)) <= self.config.heading_tolerance:
            return grid_values(self.grids_[leg], footholds[:, :2], self.config.spacing)
        reward = self.rewards_[leg]
        return reward.terrain_values(Candidates(self.hmap, footholds, yaw,
                                                self.robot.leg(leg).mirrored, reward.config))

    def _holding(self, footholds: np.ndarray, usable: np.ndarray) -> np.ndarray:
        """``usable`` (n,) bool less the footholds (n, 3) [m] the friction check drops."""
        return usable if self.friction_ is None else self.friction_.keep(footholds, usable)

    def _pose(self, state: RobotState, footholds: np.ndarray) -> np.ndarray:
        """State part of the swing leg's reward (n,) for the state (0 if it has no pose weights)."""
        return self._pose_each([state], footholds)[0]

    def _pose_each(self, states: list[RobotState], footholds: np.ndarray) -> np.ndarray:
        """:meth:`_pose` of the same footholds (n, 3) [m] in each of ``states`` (one heading and
        swing leg): (len(states), n), the footholds' patches and terrain columns computed once."""
        leg = states[0].swing_leg
        if not self._posed[leg] or footholds.shape[0] == 0:
            return np.zeros((len(states), footholds.shape[0]))
        reward = self.rewards_[leg]
        first = Candidates.of_state(self.hmap, states[0], footholds, reward.config, self.robot)
        return reward.state_values_each([first] + [first.with_state(s) for s in states[1:]])

    def _near(self, state: RobotState, target: np.ndarray) -> np.ndarray:
        """Candidates (m, 3) of the swing leg within lookahead_radius of target (2,) [m]: the
        rule of :func:`~footfall.features.candidates.reachable_footholds` (lattice point with
        data, ball-foot centre reachable within the joint limits) on a small window."""
        r = self.config.lookahead_radius
        pts = lattice(self.hmap, (target[0] - r, target[0] + r), (target[1] - r, target[1] + r),
                      self.config.spacing)
        pts = pts[np.sum((pts - target) ** 2, axis=1) <= r * r]
        z = self.hmap.height_at(pts)
        out = np.column_stack([pts, z])[~np.isnan(z)]
        return out[reaches(state, out, self.robot)]

    def _state(self, feet: np.ndarray, xy: np.ndarray, yaw: float, leg: str,
               goal: np.ndarray, target: np.ndarray, ground: float) -> RobotState:
        """The predicted state at the touch-down of ``leg``: the feet as they stand, the body on
        the path at ``xy`` heading ``yaw``, no roll.

        The body stands ``nominal_height`` above the mean height of the feet,
        pitched along them (:func:`~footfall.core.state.feet_pitch`) -- unless from
        there the swing leg cannot reach its path-nominal foothold ``target``
        (2,) [m] on the ground at height ``ground`` [m] (:meth:`_ground`; NaN: no
        data there, the mean height of the feet): then it is posed so over the
        feet of the stance *after* the step, the
        swing foot at ``target``, as the pose finder will pose it. The first
        pose would hold a front hip a whole riser too high to reach down a step,
        every foothold below the edge out of reach, and the robot would shuffle
        at the edge; the second, used on every step, makes rough ground worse
        (rocky 0.5, six boards of 21 runs, hand-tuned reward: 111 / 126
        crossings against 121 / 126).
        """
        state = self._posed_over(feet, feet, xy, yaw, leg, goal)
        foothold = np.array([target[0], target[1],
                             feet[:, 2].mean() if math.isnan(ground) else ground])
        if reaches(state, foothold[None], self.robot)[0]:
            return state
        after = np.array(feet, dtype=np.float64, copy=True)
        after[LEG_NAMES.index(leg)] = foothold
        return self._posed_over(feet, after, xy, yaw, leg, goal)

    def _posed_over(self, feet: np.ndarray, support: np.ndarray, xy: np.ndarray, yaw: float,
                    leg: str, goal: np.ndarray) -> RobotState:
        """State with the feet ``feet`` and the body ``nominal_height`` above the mean height of
        ``support`` (4, 3) [m], pitched along it."""
        body = np.array([xy[0], xy[1], support[:, 2].mean() + self.robot.nominal_height])
        return RobotState(feet, body, np.array([0.0, feet_pitch(support, self.robot), yaw]), leg,
                          goal)

    def _ground(self, target: np.ndarray) -> float:
        """Median terrain height [m] within target_radius of target (2,) [m] (where the swing
        foot will most likely land); NaN where the map has no data there."""
        r = self.config.target_radius
        pts = lattice(self.hmap, (target[0] - r, target[0] + r), (target[1] - r, target[1] + r),
                      self.config.spacing)
        z = self.hmap.height_at(pts[np.sum((pts - target) ** 2, axis=1) <= r * r])
        z = z[~np.isnan(z)]
        return float(np.median(z)) if z.size else math.nan

    # ---------------------------------------------------------------- plan
    def plan(self, state: RobotState, first: int | None = None) -> FootstepPlan:
        """The foothold of ``state.swing_leg`` that maximises the reward over the next steps.

        ``state`` is the robot as the swing leg lifts off: its feet, and its
        body, whose nearest path point gives the arc length ``s0``. Step k
        (k = 0 is this one; legs follow ``robot.gait_order``) touches down
        with the body on the path at ``s0 + (k + 1) * step_advance`` (clamped
        to the path's end), heading as :func:`path_heading` says. Its path-nominal
        foothold is the leg's default stance position around the body pose
        ``foot_lead`` further along the path; the body is posed for the stance
        after the step, with the swing foot at that foothold (see :meth:`_state`).

        Look-ahead (an approximation of the best five-step sequence): the
        ``beam_width`` best first steps by reward plus bias, at least
        ``root_separation`` apart, are each rolled out greedily over the
        remaining steps, and the first step of the best rollout is chosen.
        Step 0 scores the whole candidate set F (the pose part of the reward
        for its ``pose_candidates`` best by terrain reward plus bias); later
        steps consider the candidates within ``lookahead_radius`` of
        their path-nominal position (computed for the body height of the
        best rollout), and evaluate pose features only for the
        ``lookahead_candidates`` best of them by terrain reward plus bias.
        Headings more than ``heading_tolerance`` from ``GRID_YAW`` score
        terrain from exact patches: step 0 all of F (about 0.5 ms per
        candidate: slow), later steps the ``2 * lookahead_candidates``
        candidates nearest their target.
        For rewards without pose weights the steps do not interact, the
        rollouts coincide and the choice is exactly the greedy one. The
        rollouts stop early where a step has no candidates (e.g. at the end
        of the map).

        ``first``: the index in F to take instead (:mod:`footfall.sim.branch`), rolled out.

        Raises
        ------
        NoFootholdError
            If the swing leg has no candidate foothold.
        """
        if not isinstance(state, RobotState):
            raise FootfallError(f"plan needs a RobotState, got {type(state).__name__}")
        ahead = self._horizon(state)
        st0, cand, reward, total, roots = self._first_step(state, ahead)
        if first is not None:  # the candidate a branch of the run tries
            roots = np.array([require_int(first, "first", 0, below=cand.shape[0])])
        value, chosen = self._rollouts(state, ahead, cand[roots], total[roots])
        best = int(np.argmax(value))  # ties: the better first step (roots are ranked)
        index = int(roots[best])
        values = np.full(cand.shape[0], -np.inf)
        values[roots] = value
        m = len(chosen)
        return FootstepPlan(
            leg=ahead.legs[0], index=index, foothold=cand[index].copy(), candidates=cand,
            reward=reward, total=total, value=values, legs=tuple(ahead.legs[:m]),
            footholds=np.array([c_[best] for c_ in chosen]), body_xy=ahead.body_xy[:m],
            body_yaw=ahead.body_yaw[:m], targets=ahead.targets[:m], state=st0)

    def _horizon(self, state: RobotState) -> _Horizon:
        """The next ``lookahead`` steps from ``state``, as the path predicts them (:meth:`plan`)."""
        cfg, robot, path = self.config, self.robot, self.path
        order = list(robot.gait_order)
        first = order.index(state.swing_leg)
        legs = [order[(first + k) % len(order)] for k in range(cfg.lookahead)]
        s0 = float(path.closest(state.body_position[:2]))
        s = np.minimum(s0 + cfg.step_advance * np.arange(1, cfg.lookahead + 1), path.length)
        body_xy = path.point_at(s)
        body_yaw = path_heading(path, s, cfg.heading_horizon)
        s_mid = np.minimum(s + cfg.lead, path.length)
        mid_xy, mid_yaw = path.point_at(s_mid), path_heading(path, s_mid, cfg.heading_horizon)
        nominal = np.array([robot.nominal_foot(leg)[:2] for leg in legs])  # (K, 2)
        c, sn = np.cos(mid_yaw), np.sin(mid_yaw)
        targets = mid_xy + np.column_stack([c * nominal[:, 0] - sn * nominal[:, 1],
                                            sn * nominal[:, 0] + c * nominal[:, 1]])
        grounds = [self._ground(t) for t in targets]  # lookahead (five) targets
        return _Horizon(legs, body_xy, body_yaw, targets, grounds)

    def _first_step(self, state: RobotState, ahead: _Horizon
                    ) -> tuple[RobotState, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Step 0: the whole candidate set F, scored as the reward defines it.

        Returns the state F is computed for, F (n, 3) [m], its reward (n,) (NaN: pose part not
        evaluated), reward less path bias (n,), and the roots of the rollouts (r,) [index in F].
        """
        cfg = self.config
        leg0, target = ahead.legs[0], ahead.targets[0]
        yaw0 = float(ahead.body_yaw[0])
        st0 = self._state(state.feet, ahead.body_xy[0], yaw0, leg0, state.goal, target,
                          ahead.grounds[0])
        exact = abs(_wrap(yaw0 - GRID_YAW)) > cfg.heading_tolerance
        cand = reachable_footholds(self.hmap, st0, self.robot, cfg.spacing,
                                   self.rewards_[leg0].config if exact else None)
        terrain = self._terrain(leg0, cand, yaw0)
        keep = self._holding(cand, np.isfinite(terrain))
        if cfg.seen_footing is not None:  # beside a hole in the scan the ball could drop into
            keep = unless_none_left(keep, seen_under_sphere(
                self.hmap, cand[:, :2], self.robot.foot_radius, cfg.seen_footing))
        if cfg.search_radius is not None:  # F: the footholds near the gait-nominal position, or,
            # where none near it is usable (a step edge, a gap), every reachable one
            near = np.sum((cand[:, :2] - target) ** 2, axis=1) <= cfg.search_radius ** 2
            if np.any(keep & near):
                keep &= near
        if cfg.joint_margin is not None or cfg.leg_clearance is not None:  # within F: a check
            # that fails every foothold of F leaves F as it is, rather than stepping far off it
            later = stride_on(st0, ahead.legs, ahead.body_xy, ahead.grounds)
            keep = stance_checks(self.hmap, st0, later, cand, keep, cfg, self.robot)
        cand, terrain = cand[keep], terrain[keep]
        if cand.shape[0] == 0:
            raise NoFootholdError(f"leg {leg0} has no candidate foothold at body "
                                  f"({ahead.body_xy[0, 0]:.3f}, {ahead.body_xy[0, 1]:.3f}) m")
        bias = self.bias_[leg0] * np.linalg.norm(cand[:, :2] - target, axis=1)
        reward = terrain
        if self._posed[leg0]:
            short = np.arange(cand.shape[0])
            if cfg.pose_candidates is not None and cand.shape[0] > cfg.pose_candidates:
                short = np.sort(np.argsort(bias - terrain, kind="stable")[:cfg.pose_candidates])
            reward = np.full(cand.shape[0], np.nan)
            reward[short] = terrain[short] + self._pose(st0, cand[short])
        total = reward - bias
        roots = _diverse_best(total, cand, cfg.beam_width, cfg.root_separation)
        if roots.size == 0:
            raise NoFootholdError(f"leg {leg0} has no candidate foothold with a finite reward")
        return st0, cand, reward, total, roots

    def _rollouts(self, state: RobotState, ahead: _Horizon, first: np.ndarray, value: np.ndarray
                  ) -> tuple[np.ndarray, list[np.ndarray]]:
        """Roll each first step (R, 3) [m] of summed value (R,) out greedily over the later steps.

        Returns the summed values (R,) and the chosen footholds, one (R, 3) [m] per step taken.
        """
        cfg = self.config
        n_roots = first.shape[0]
        feet = np.broadcast_to(state.feet, (n_roots, 4, 3)).copy()  # (R, 4, 3) [m]
        feet[:, LEG_NAMES.index(ahead.legs[0])] = first
        value = value.copy()
        chosen = [first]
        for k in range(1, cfg.lookahead):  # a handful of steps, not a loop over candidates
            leg, yaw = ahead.legs[k], float(ahead.body_yaw[k])
            xy, target, ground = ahead.body_xy[k], ahead.targets[k], ahead.grounds[k]
            best_so_far = self._state(feet[0], xy, yaw, leg, state.goal, target, ground)
            near = self._near(best_so_far, target)
            if abs(_wrap(yaw - GRID_YAW)) > cfg.heading_tolerance:  # exact patches: few of them
                dist = np.linalg.norm(near[:, :2] - target, axis=1)
                near = near[np.argsort(dist, kind="stable")[:2 * cfg.lookahead_candidates]]
            t = self._terrain(leg, near, yaw)
            keep = self._holding(near, np.isfinite(t))
            near, t = near[keep], t[keep]
            if near.shape[0] == 0:
                break
            t = t - self.bias_[leg] * np.linalg.norm(near[:, :2] - target, axis=1)
            if self._posed[leg]:
                top = np.argsort(-t, kind="stable")[:cfg.lookahead_candidates]
                near, t = near[top], t[top]
                scores = t + self._pose_each([self._state(feet[r], xy, yaw, leg, state.goal,
                                                          target, ground)
                                              for r in range(n_roots)], near)  # beam_width rollouts
            else:
                scores = np.broadcast_to(t, (n_roots, t.size))
            # A candidate out of reach at a rollout's own body height has NaN pose features.
            scores = np.where(np.isnan(scores), -np.inf, scores)
            pick = np.argmax(scores, axis=1)
            value += scores[np.arange(n_roots), pick]
            feet[:, LEG_NAMES.index(leg)] = near[pick]
            chosen.append(near[pick])
        return value, chosen

