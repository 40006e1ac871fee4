"""Teachers: who corrects the robot's runs and who walks as the reference they are imitated by.

A teacher has two faces. As an :class:`~footfall.expert.protocol.Expert` it values a step's
candidate set F and labels a better foothold where the robot fell short (the corrections, the
demonstrations of an offline table); as a walker it chooses every foothold of a run (the
calibration of the test difficulty, the reference line of Table II). Both come from the
expert's settings and the walk's footstep settings, so a run job names a teacher by a string.

* ``"expert"``: the synthetic expert itself (:class:`~footfall.expert.synthetic.SyntheticExpert`),
  walked by the judged footstep planner without a path bias.
* ``"guarded"``: the hand-tuned reward with the expert's veto of severe footholds (short of
  its best by more than :data:`~footfall.expert.corrections.SEVERE_SHORTFALL`;
  :mod:`footfall.expert.guarded`), walked by the ordinary planner with its path bias.
* ``"accepted"``: the same with the veto at the correction margin
  (:data:`~footfall.expert.corrections.REPRODUCTION_MARGIN`): the hand-tuned reward choosing among
  the footholds the expert accepts.
* ``"rollout"``: the simulator (:mod:`footfall.sim.rollout`): at every decision the
  ``accepted`` teacher's best candidates and the expert's best are tried in branches of the run,
  and the one that walked best is taken. It labels a run's states as the run is walked (a
  correcting run job, :func:`footfall.sim.rollout.verdict_demonstrations`; a stored run is
  walked again to be labelled, :mod:`footfall.experiments.relabel`), so its own expert face
  refuses; on a state alone -- an offline table, the candidates it did not try -- its base
  answers (:func:`state_judge`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from footfall.core.errors import FootfallError
from footfall.core.registry import Registry
from footfall.expert.corrections import REPRODUCTION_MARGIN, SEVERE_SHORTFALL
from footfall.expert.guarded import GuardedExpert
from footfall.expert.protocol import Expert
from footfall.expert.scorer import ExpertScorer, judge_name
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.features.reward import default_reward
from footfall.features.scorer import FootholdScorer


@dataclass(frozen=True)
class Walker:
    """How a teacher walks: a judge (the judged planner, no path bias) or a reward (the
    ordinary planner); exactly one is set."""

    judge: FootholdScorer | None = None
    reward: FootholdScorer | None = None
    rollout: bool = False  # the simulator chooses: candidates tried in branches of the run,
    # this walker's choice the base (footfall.sim.rollout; the expert's best is tried too)


@dataclass(frozen=True)
class Teacher:
    """A teacher's two faces, made from the expert's settings, the footstep planner's path bias
    [hand-tuned reward/m] and its gait-nominal lead [m]."""

    expert: Callable[[ExpertConfig, float, float], Expert]  # values and labels F
    walker: Callable[[ExpertConfig, float, float], Walker]  # chooses every foothold
    doc: str
    base: str | None = None  # the teacher whose face answers on a state alone, for one that
    # judges only by walking (the rollout teacher: the teacher it improves on)


TEACHERS: Registry[Teacher] = Registry("teacher")


def _guarded(expert: ExpertConfig, bias_weight: float, lead: float,
             threshold: float = SEVERE_SHORTFALL) -> GuardedExpert:
    """The hand-tuned reward guarded by the expert of ``expert``, its values in the expert's
    units at the rate of the two path preferences (the expert's stance weight [value/m] over
    the planner's bias [reward/m])."""
    if bias_weight <= 0 or expert.w_stance <= 0:
        raise FootfallError("the guarded teacher needs a path bias and an expert with a "
                            "stance weight: its values convert between the two")
    return GuardedExpert(default_reward(), SyntheticExpert(expert), bias_weight, lead,
                         expert.w_stance / bias_weight, threshold)


TEACHERS.register("expert", Teacher(
    lambda expert, bias_weight, lead: SyntheticExpert(expert),
    lambda expert, bias_weight, lead: Walker(judge=ExpertScorer(SyntheticExpert(expert),
                                                       name=judge_name(expert))),
    "the synthetic expert: its own value chooses and corrects"))
def _guarded_teacher(threshold: float, doc: str) -> Teacher:
    """The hand-tuned reward guarded at ``threshold`` [value units], as both faces."""
    return Teacher(lambda expert, bias_weight, lead: _guarded(expert, bias_weight, lead, threshold),
                   lambda expert, bias_weight, lead: Walker(
                       reward=_guarded(expert, bias_weight, lead, threshold).scorer), doc)


TEACHERS.register("guarded", _guarded_teacher(
    SEVERE_SHORTFALL, "the hand-tuned reward with the expert's veto of footholds severely "
                      "short of its best"))
TEACHERS.register("accepted", _guarded_teacher(
    REPRODUCTION_MARGIN, "the hand-tuned reward among the footholds the expert accepts (within "
                         "the margin)"))


def state_judge(name: str, expert: ExpertConfig, bias_weight: float, lead: float) -> Expert:
    """The teacher ``name``'s verdict on a state alone: its own expert face, or its base's for
    a teacher that judges only by walking."""
    teacher = TEACHERS.get(name)
    return TEACHERS.get(teacher.base or name).expert(expert, bias_weight, lead)


def _rollout_labels(expert: ExpertConfig, bias_weight: float, lead: float) -> Expert:
    raise FootfallError("the rollout teacher judges by walking branches of a run, not a state "
                        "alone: its labels come from walking the runs (walk-many --teacher "
                        "rollout, demos correct --teacher rollout, reproduce --teacher rollout)")


TEACHERS.register("rollout", Teacher(
    _rollout_labels,
    lambda expert, bias_weight, lead: Walker(
        reward=_guarded(expert, bias_weight, lead, REPRODUCTION_MARGIN).scorer, rollout=True),
    "the simulator: the accepted teacher's best candidates and the expert's best tried in "
    "branches of the run, the one that walked best taken", base="accepted"))
