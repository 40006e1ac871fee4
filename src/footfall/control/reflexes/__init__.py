"""Reflexes on top of the planned gait: what the robot does when the terrain does not hold.

The planner and the trajectories of §IV-B assume that a foot stays where it
is put. On rough terrain it does not always: a stance foot slides off a
rock rim, a foot lands on a steep face, the trunk tips. As the LittleDog
teams did (CMU: "re-planning of the full trajectory, augmented by reflexes
and feedback control"; slip detection and recovery after Focchi et al.),
the controller watches the measured state every control period and reacts.
Each reflex is a part of the controller in a module of this package, with
its own settings (fields of :class:`ReflexConfig`, ``WalkConfig.reflexes``)
and its own test, and logs an event in the run log when it acts:

* **lift-off gate** (``lift_off_gate``, :mod:`~footfall.control.reflexes.gate`): a leg lifts only when the measured
  centre of mass lies inside the triangle of the other three feet, where
  they actually stand, by ``gate_margin``; until then the body keeps moving
  toward the triangle's incentre, for at most ``gate_timeout``, after which
  the step is planned anew from where the feet stand;
* **stance slip reflex** (``slip_reflex``, :mod:`~footfall.control.reflexes.slip`): a loaded stance foot (its force
  sensor reads more than the walk's ``touchdown_force``) more than
  ``slip_distance`` (horizontally) from where it was put down, the ball's
  rolling allowed for, and moving faster than ``slip_speed``, is sliding.
  The body stops, a swinging foot comes down at once; once the slipped foot
  has stopped it is taken to stand where it now is (its leg no longer drags
  it back), and the
  step is planned anew from the feet as they stand; if the slipped foot is
  more than ``replace_distance`` from where it was put, it steps first, to a
  new foothold;
* **touch-down check** (``touchdown_check``,
  :mod:`~footfall.control.reflexes.touchdown`): a foot that lands more than
  ``touchdown_tolerance`` from its foothold, or finds no ground within
  reach, is lifted again and put on the next-best candidate of F at least
  ``replace_separation`` away (at most ``max_replacements`` times a step);
* **tilt reflex** (``tilt_reflex``, :mod:`~footfall.control.reflexes.tilt`): trunk roll or pitch more than
  ``tilt_threshold`` from the planned attitude stops the body and brings a
  swinging foot down at once; the gait goes on once the error is below
  ``tilt_recovered`` (or after ``recover_timeout``; the recovery after
  either alarm is :mod:`~footfall.control.reflexes.recovery`);
* **re-basing** (``rebase_distance``, :mod:`~footfall.control.reflexes.rebase`): a recovery after which the body is
  still more than ``rebase_distance`` from where it is wanted -- the whole
  robot has slid, and the legs push on feet that are no longer where they
  were put -- takes the stance as it now is: every stance foot is
  re-anchored where it stands, the body is wanted where it is, and the next
  step is planned from there.

This module holds the settings and the numerics every part uses, pure
functions of measured arrays; the parts act through the controller
(:mod:`footfall.control.controller`), which wires them in.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from footfall.control.cog import incircle, support_margin
from footfall.core.params import Params, param, within

_POSITIVE = within(0, math.inf, low_open=True)
REFLEXES = ("lift_off_gate", "slip_reflex", "touchdown_check", "tilt_reflex")  # the switches


@dataclass(frozen=True)
class ReflexConfig(Params):
    """Which reflexes act, and their thresholds (docs/configuration.md)."""

    lift_off_gate: bool = param(True, doc="lift a leg only with the measured centre of mass "
                                          "inside the other three feet's triangle")
    slip_reflex: bool = param(False, doc="a slipping stance foot stops the body and re-plans the "
                                        "support from where the feet stand")
    touchdown_check: bool = param(True, doc="a foot landing far off its foothold, or on nothing, "
                                            "is put on the next-best candidate")
    tilt_reflex: bool = param(True, doc="a tipping trunk brings the swing foot down at once and "
                                        "recovers the posture first")
    gate_margin: float = param(0.015, unit="m", range=within(0, math.inf),
                               doc="least distance of the measured centre of mass inside the "
                                   "triangle of the three feet that stay down, at lift-off")
    gate_timeout: float = param(1.0, unit="s", range=_POSITIVE,
                                doc="longest wait at the lift-off gate before re-planning")
    gate_speed: float = param(0.05, unit="m/s", range=_POSITIVE,
                              doc="how fast the body moves toward the triangle's incentre while "
                                  "it waits at the gate")
    slip_distance: float = param(0.012, unit="m", range=_POSITIVE,
                                 doc="a loaded stance foot this far (horizontally) from where it "
                                     "was put down has slipped")
    slip_speed: float = param(0.05, unit="m/s", range=_POSITIVE,
                              doc="...and moving faster than this: it is sliding (a leg giving "
                                  "under load stops within a period or two)")
    replace_distance: float = param(0.025, unit="m", range=_POSITIVE,
                                    doc="a slipped foot this far from where it was put down "
                                        "steps to a new foothold first")
    touchdown_tolerance: float = param(0.02, unit="m", range=_POSITIVE,
                                       doc="a foot landing farther than this from its foothold "
                                           "(horizontally) is re-placed")
    replace_separation: float = param(0.012, unit="m", range=within(0, math.inf),
                                      doc="a re-placed foot goes to a candidate at least this far "
                                          "from where it failed")
    max_replacements: int = param(2, unit="-", range=within(0, 10),
                                  doc="most re-placements of one step's foot")
    tilt_threshold: float = param(0.12, unit="rad", range=_POSITIVE,
                                  doc="trunk roll or pitch error that sets off the tilt reflex")
    tilt_recovered: float = param(0.05, unit="rad", range=_POSITIVE,
                                  doc="roll and pitch errors below this: posture recovered")
    recover_timeout: float = param(1.5, unit="s", range=_POSITIVE,
                                   doc="longest posture recovery before the gait goes on")
    rebase_distance: float | None = param(None, unit="m", range=_POSITIVE,
                                          doc="after a recovery, a body farther than this "
                                              "(horizontally) from where it is wanted re-bases "
                                              "the stance: the stance feet re-anchored where they "
                                              "stand, the body wanted where it is, the "
                                              "horizontal correction cleared; None: never")

    def without(self, reflex: str) -> ReflexConfig:
        """This configuration with one reflex (a name of :data:`REFLEXES`) switched off."""
        if reflex not in REFLEXES:
            raise ValueError(f"unknown reflex {reflex!r}; reflexes are {', '.join(REFLEXES)}")
        return replace(self, **{reflex: False})


def com_in_triangle(com_xy: np.ndarray, feet_xy: np.ndarray, margin: float) -> bool:
    """Whether the centre of mass (2,) [m] lies at least ``margin`` [m] inside the triangle (3, 2)."""
    return bool(support_margin(feet_xy, com_xy) >= margin)


def gate_step(com_xy: np.ndarray, desired_xy: np.ndarray, feet_xy: np.ndarray, speed: float,
              period: float) -> np.ndarray:
    """Next desired body position (2,) [m] while waiting at the lift-off gate.

    The body moves from ``desired_xy`` toward the incentre of the support
    triangle ``feet_xy`` (3, 2) [m] at ``speed`` [m/s] for one ``period`` [s],
    so that the measured centre of mass ``com_xy`` (2,) [m] (which lags the
    command) comes inside; the command moves by the offset of the centre of
    mass from the body origin as well.
    """
    centre, _ = incircle(np.asarray(feet_xy, dtype=np.float64))
    goal = centre - (np.asarray(com_xy) - np.asarray(desired_xy))  # body origin for COM there
    gap = goal - desired_xy
    dist = float(np.hypot(*gap))
    step = speed * period
    return goal.copy() if dist <= step else desired_xy + gap * (step / dist)


def slipped(feet_xy: np.ndarray, targets_xy: np.ndarray, loaded: np.ndarray,
            distance: float) -> np.ndarray:
    """Which loaded stance feet (4,) bool are more than ``distance`` [m] from their targets.

    ``feet_xy`` (4, 2) [m]: measured foot centres; ``targets_xy`` (4, 2) [m]:
    where they were put down, moved on by the ball's rolling; ``loaded`` (4,)
    bool: stance feet that have taken their load.
    """
    gap = np.hypot(*(np.asarray(feet_xy) - np.asarray(targets_xy)).T)
    return np.asarray(loaded, dtype=bool) & (gap > distance)


def tilt_error(measured_rpy: np.ndarray, desired_rpy: np.ndarray) -> float:
    """Largest roll or pitch error [rad] of the trunk from its desired attitude."""
    err = (np.asarray(measured_rpy[:2]) - np.asarray(desired_rpy[:2]) + np.pi) % (2 * np.pi) - np.pi
    return float(np.abs(err).max())


def next_best_candidate(candidates: np.ndarray, score: np.ndarray, avoid: np.ndarray,
                        separation: float) -> int | None:
    """Index of the best-scoring candidate at least ``separation`` [m] from every ``avoid`` point.

    ``candidates`` (n, 3) [m], ``score`` (n,) (NaN or -inf: not usable),
    ``avoid`` (m, 2 or 3) [m] (only x, y count). None if no candidate qualifies.
    """
    cand = np.asarray(candidates, dtype=np.float64)
    s = np.asarray(score, dtype=np.float64)
    pts = np.asarray(avoid, dtype=np.float64).reshape(-1, np.shape(avoid)[-1])[:, :2]
    dist = np.sqrt(((cand[:, None, :2] - pts[None]) ** 2).sum(axis=-1)).min(axis=1)
    usable = np.isfinite(s) & (dist >= separation)
    if not usable.any():
        return None
    return int(np.argmax(np.where(usable, s, -np.inf)))
