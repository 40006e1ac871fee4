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

The surface is :mod:`footfall.core.sphere_surface`, the terms and their units
:mod:`footfall.expert.terms`; this module holds the expert's settings
(:class:`ExpertConfig`) and the judge itself (:class:`SyntheticExpert`). See
docs/expert.md for the reasoning behind every term, unit and weight.
"""

from __future__ import annotations

import math
import weakref
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, above, at_least, param, within
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.expert.memo import MEMO_ROWS, RowMemo
from footfall.expert.terms import (
    EXPERT_TERM_NAMES,
    contributions,
    leg_terms,
    pose_terms,
    worst_placement,
)

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
    roll_back: float | None = param(None, unit="m", range=_NONNEGATIVE,
                                    doc="a placement error that would seat the ball more than "
                                        "this above the foothold's own seat is not counted: the "
                                        "ground falls back toward the foothold, so a ball set "
                                        "there slides back to it (a trough's flank, a hollow's "
                                        "rim); None: every placement counts")
    roll_back_wall: float | None = param(None, unit="-", range=_NONNEGATIVE,
                                         doc="with roll_back: a placement seated higher above "
                                             "the foothold's seat than this times the placement "
                                             "error counts all the same -- the ground between is a "
                                             "wall, whose edge or top the ball lands on, not a "
                                             "flank it slides down; None: no such wall")
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
    crown_radius: float = param(0.02, unit="m", range=above(0),
                                doc="radius of the ring around the foothold whose ball-centre "
                                    "heights the crown is read against (at the foothold itself, "
                                    "not at its placement error)")
    riser_distance: float = param(0.04, unit="m", range=_NONNEGATIVE,
                                  doc="a riser farther ahead of the foothold than this does not "
                                      "catch the swing leaving it")
    w_riser: float = param(0.0, unit="value/m", range=_NONNEGATIVE,
                           doc="penalty per metre of (weighted) riser ahead above riser_free")
    riser_free: float = param(0.0, unit="m", range=_NONNEGATIVE,
                              doc="riser ahead that the swing's lift clears without catching")
    w_crown: float = param(0.0, unit="value/m", range=_NONNEGATIVE,
                           doc="penalty per metre of crown above crown_free (0: a crest is "
                               "judged by its hold alone)")
    crown_free: float = param(0.002, unit="m", range=_NONNEGATIVE,
                              doc="crown that does no harm (a ball sliding over it is caught "
                                  "before the ground falls away)")
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



def check_judges(config: ExpertConfig, what: str) -> ExpertConfig:
    """``config`` as the settings of an expert that judges, or refused: one whose every weight
    is 0 values every foothold alike (the hand-tuned reward would look flawless by it).
    ``what`` names the settings in the message. (An all-zero config is a basis inside the
    grounding's fit, not an expert: the check is where settings come in or go out.)"""
    if not any(getattr(config, f.name) for f in fields(config) if f.name.startswith("w_")):
        raise FootfallError(f"{what}: every weight is 0: an expert that values every foothold "
                            f"alike judges nothing")
    return config


WALKER_PLACEMENT_ERROR: float = 0.007
"""[m] The walking expert's placement error: about the mean slip per foothold of footfall's
walker on flat ground (6.1 +- 1.7 mm over 21 runs, docs/reproduce)."""


WALKER_CROWN_WEIGHT: float = 8000.0
"""[value/m] The walking expert's crown weight (on ``crown_radius``'s 2 cm ring): a crest 10 mm
above the ground around it costs 64 value units. Chosen offline on training runs by a gate
written before, adopted by the ablation's training-suite rule (round 6, docs/terrain-suite.md)."""


WALKER_RISER_WEIGHT: float = 1000.0
"""[value/m] The walking expert's riser weight (on ``riser_ahead`` above ``WALKER_RISER_FREE``): a
mm of riser within 4 cm ahead that the swing's lift cannot clear costs what a mm of drop-off does
(``w_drop``). Written down from a diagnosis of training runs (a hind foot standing within 30 mm
of a riser missed its next foothold in 12 % of the climbs), adopted by the ablation's
training-suite rule (round 8, docs/terrain-suite.md)."""

WALKER_RISER_FREE: float = 0.02
"""[m] The riser the walking expert's swing clears without catching: the swing's straight lift
(``SwingConfig.lift_height``)."""


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
    riser's edge or a pit's rim is judged by the edge or the rim. And it knows that a
    ball set on a crest slides off whichever way it moves: a foothold standing above the
    ground 2 cm around it loses ``WALKER_CROWN_WEIGHT`` a metre of the difference (the crown),
    and that a foot set just before a riser must climb it from there: a foothold with a riser
    within 4 cm ahead loses ``WALKER_RISER_WEIGHT`` a metre of (nearer-weighted) rise above
    ``WALKER_RISER_FREE``, what the swing's lift clears.
    """
    for name, v in (("stance lead", lead), ("placement error", placement_error)):
        if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise FootfallError(f"the {name} must be a number >= 0 [m], got {v!r}")
    base = ExpertConfig()
    return replace(base, w_progress=0.0, w_stance=base.w_progress, stance_lead=float(lead),
                   placement_error=float(placement_error), w_crown=WALKER_CROWN_WEIGHT,
                   w_riser=WALKER_RISER_WEIGHT, riser_free=WALKER_RISER_FREE)


_SEAT = "seat"  # the memo's name for the seated ball-centre height [m]
MEMO_HEADINGS = 4  # [-] headings per map whose footholds' terrain terms an expert remembers
# (and at most MEMO_ROWS footholds in all: beyond, only the memo in use is kept)


def _summed(parts: dict[str, np.ndarray]) -> np.ndarray:
    """The value (n,): the terms' shares summed in their order."""
    return np.sum(np.stack(list(parts.values())), axis=0)


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
        # The terrain terms of every foothold judged, per map and heading: a walk's look-ahead
        # judges the same footholds again from the next steps (5 in 6 on rocks).
        self._memos: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

    def _terrain(self, hmap: HeightMap, f: np.ndarray, yaw: float
                 ) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """:func:`worst_placement` of candidates ``f`` at heading ``yaw``, remembered per
        foothold (each foothold's terms are a function of it alone)."""
        per_map = self._memos.setdefault(hmap, OrderedDict())
        memo = per_map.get(float(yaw))
        if memo is None:
            board = weakref.ref(hmap)  # the memo must not keep its map alive

            def compute(rows: np.ndarray, heading: float = float(yaw)) -> dict[str, np.ndarray]:
                terms, seat = worst_placement(board(), rows, heading, self.config, self.robot)
                return {**terms, _SEAT: seat}
            memo = per_map[float(yaw)] = RowMemo(compute)
            if len(per_map) > MEMO_HEADINGS:
                per_map.popitem(last=False)
        else:
            per_map.move_to_end(float(yaw))
        terms = memo(f)
        if sum(len(m) for per in list(self._memos.values()) for m in per.values()) > MEMO_ROWS:
            self._memos = weakref.WeakKeyDictionary({hmap: OrderedDict({float(yaw): memo})})
        seat = terms.pop(_SEAT)
        return terms, seat

    def _check(self, candidates: np.ndarray) -> np.ndarray:
        f = np.asarray(candidates, dtype=np.float64)
        if f.ndim != 2 or f.shape[1] != 3:
            raise FootfallError(f"candidates must have shape (n, 3), got {f.shape}")
        if not np.isfinite(f[:, :2]).all():
            raise FootfallError("candidate x, y must be finite (a height may be NaN)")
        return f

    def terms(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray
              ) -> dict[str, np.ndarray]:
        """The expert's raw judgement terms of each candidate, named as in
        :data:`~footfall.expert.terms.EXPERT_TERMS`.

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
            Finite values in the units of :data:`~footfall.expert.terms.EXPERT_TERMS`, in its
            order.
        """
        f = self._check(candidates)
        if f.shape[0] == 0:
            return {name: np.zeros(0) for name in EXPERT_TERM_NAMES}
        terrain, seat = self._terrain(hmap, f, state.yaw)
        return self._with_state(hmap, state, f, terrain, seat)

    def _with_state(self, hmap: HeightMap, state: RobotState, f: np.ndarray,
                    terrain: dict[str, np.ndarray], seat: np.ndarray) -> dict[str, np.ndarray]:
        """The terms of candidates ``f`` (n, 3) [m] in ``state``, their terrain terms and the
        ball's seat heights (n,) [m] given."""
        cfg, robot = self.config, self.robot
        out = {**terrain, **leg_terms(hmap, state, f, seat, cfg, robot),
               **pose_terms(state, f, cfg, robot)}
        return {name: out[name] for name in EXPERT_TERM_NAMES}

    def utilities(self, terms: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Each term's share of the value [value units, 1 = 1 cm of progress], shapes (n,).

        ``terms`` as returned by :meth:`terms`. The utilities, with
        phi = atan(foot_friction) and m the slip margin:

        * slip_margin: ``w_hold * clip(m - phi, 0, hold_cap) - w_slope * clip(phi - m, 0, phi)
          - w_cone * max(-m, 0)``: concave -- a hollow earns a capped bonus, a slanted face
          a penalty, a face beyond the friction cone a much steeper one.
        * pinch, trap_depth, drop_off, riser_ahead: ``-w * max(term - free, 0)`` (harmless up to ``free``;
          pinch counted up to ``pinch_cap``).
        * leg_clearance: ``-w_leg * max(leg_safe - c, 0) - w_leg_collision * max(-c, 0)``.
        * unknown: ``-w_unknown * fraction``.
        * progress: ``w_progress * progress``; stance_offset: ``-w_stance * offset``; stability: ``w_stability * min(margin, cap)``.
        * reach_margin, joint_margin: ``-w * max(safe - margin, 0)``.

        The terrain utilities are 0 on flat, open, fully scanned ground.
        """
        return contributions(terms, self.config, self.robot)

    def contributions(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray
                      ) -> dict[str, np.ndarray]:
        """Each term's share of the value of each candidate (see :meth:`utilities`)."""
        return self.utilities(self.terms(hmap, state, candidates))

    def values(self, hmap: HeightMap, state: RobotState, candidates: np.ndarray) -> np.ndarray:
        """Noiseless value of each candidate, shape (n,), higher is better, always finite."""
        return _summed(self.contributions(hmap, state, candidates))

    def values_each(self, hmap: HeightMap, states: Sequence[RobotState], candidates: np.ndarray
                    ) -> np.ndarray:
        """:meth:`values` of the same candidates in each of ``states`` (one heading: a
        planner's rollouts), (len(states), n): the terrain terms looked up once."""
        f = self._check(candidates)
        if not states or f.shape[0] == 0 or any(s.yaw != states[0].yaw for s in states):
            return np.stack([self.values(hmap, s, f) for s in states]) if states else \
                np.zeros((0, f.shape[0]))
        terrain, seat = self._terrain(hmap, f, states[0].yaw)
        return np.stack([_summed(self.utilities(self._with_state(hmap, s, f, terrain, seat)))
                         for s in states])

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
