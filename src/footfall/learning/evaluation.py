"""How well a ranking function agrees with the expert on demonstrations.

For each demonstration, the model ranks the whole candidate set F; the
measures are top-1 agreement (the model's best is the expert's choice), the
percentile rank of the expert's choice among the candidates (1.0 = ranked
first), the share of picks within ``NEAR`` (1 cm) of the expert's choice
(candidates are 5 mm apart, so an exact match is a strict test), and the
reward loss: the expert's own value of its best candidate minus its value
of the candidate the model picks (in the expert's value units, 1 unit = 1 cm
of progress), with a bootstrap confidence interval over demonstrations. The
loss needs the expert's judgement: evaluation may ask the expert, the learner
never does.

**Ties are ties.** A scorer that values several candidates alike at its best
(a forest's leaves, a constant function) picks any of them with equal
probability: top-1, within 1 cm and the reward loss are their expectations
over the tied best, and the percentile counts a candidate valued like the
expert's choice as half above it. The shares of decisions whose best is tied
and whose candidates are all valued alike (a scorer that cannot tell them
apart) are reported with the measures. With it come the shares of decisions whose loss is above the
correction margin and above the severe threshold (the numbers the walking
experiment's verdict on the robot's own choices reports).

Any scorer is measured the same way: a learned model (one scorer per leg
group), the hand-tuned reward or the expert's own value (the ceiling; its
loss is zero by construction) -- :class:`EveryLeg` gives a single scorer a
model's shape.

**As the planner picks.** The footstep planner never walks with a scorer alone: it adds a
path bias, ``bias_weight`` per metre from the swing leg's gait-nominal foothold, scaled to
the scorer's spread (:func:`~footfall.features.spread.path_bias_weight`; the hand-tuned
reward, which has no pose features, leaves the pull toward the path to it). With a
:class:`PathBias` every scorer is ranked as the planner's first step would rank it: its
values less that bias (the look-ahead and the pose finder's short list aside; the planner
measures from the path-nominal position at mid-stance, a decision without a body path from
its swing leg's gait-nominal foothold, :func:`~footfall.core.state.stance_target`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import stance_target
from footfall.core.stats import bootstrap_ci
from footfall.features.family import Candidates
from footfall.features.scorer import FootholdScorer
from footfall.features.spread import path_bias_weight

NEAR = 0.01  # [m] a pick this close (horizontally) to the expert's choice counts as "near"


@dataclass(frozen=True)
class PathBias:
    """The footstep planner's pull toward the path, added when a decision is ranked as the
    planner would pick: a candidate loses ``weight`` (scaled to the scorer's spread) per metre
    it lies from the swing leg's gait-nominal foothold, ``lead`` ahead of its default stance."""

    weight: float  # [hand-tuned reward/m] the planner's bias_weight (the reproduction walks 60)
    lead: float  # [m] how far ahead of the default stance the gait-nominal foothold lies

    def __post_init__(self) -> None:
        for name in ("weight", "lead"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise FootfallError(f"the path bias's {name} must be a finite number >= 0, "
                                    f"got {v!r}")

    def values(self, scorer: FootholdScorer, state, candidates: np.ndarray,
               robot: RobotDescription) -> np.ndarray:
        """The bias (n,) [the scorer's reward units] each candidate (n, 3) [m] loses (none for a
        scorer with its own path preference: the expert walks without the bias)."""
        target = stance_target(state, robot, self.lead)
        return path_bias_weight(scorer, self.weight) * np.hypot(*(candidates[:, :2] - target).T)


@dataclass(frozen=True)
class RankScores:
    """Agreement of a model with the expert on a set of demonstrations."""

    n: int  # demonstrations
    top1: float  # fraction whose chosen candidate the model ranks first
    percentile: float  # mean fraction of other candidates the chosen one outranks
    reward_loss: float  # mean expert value of its best minus of the model's pick [value units]
    reward_loss_std: float  # standard deviation of the above over demonstrations
    top1_near: float = float("nan")  # fraction of picks within NEAR [m] of the expert's choice
    reward_loss_ci: tuple[float, float] = (float("nan"), float("nan"))  # 95 % bootstrap CI
    losses: tuple[float, ...] = ()  # per-demonstration reward loss, in demonstration order
    above_margin: float = float("nan")  # fraction of decisions whose loss is above ``margin``
    severe: float = float("nan")  # fraction of decisions whose loss is above ``severe_above``
    margin: float = float("nan")  # [value units] the correction margin the shares count above
    severe_above: float = float("nan")  # [value units] the severe threshold
    tied: float = float("nan")  # fraction of decisions whose best value several candidates share
    constant: float = float("nan")  # fraction of decisions whose candidates all have one value

    def as_dict(self) -> dict:
        """Plain data for JSON (the per-demonstration losses included).

        A measure that is not defined -- the reward loss without the expert's
        values -- is None (JSON null), not NaN.
        """
        d = {k: _defined(v) for k, v in vars(self).items()}
        d["reward_loss_ci"] = [_defined(v) for v in self.reward_loss_ci]
        d["losses"] = [_defined(v) for v in self.losses]
        return d


def _defined(value: Any) -> Any:
    """``value``, or None for a float that is not finite (a measure with no value)."""
    return None if isinstance(value, float) and not math.isfinite(value) else value


def expert_values(demos: Sequence, terrain: Callable[[str], object], expert) -> list[np.ndarray]:
    """The expert's noiseless values of every candidate of each demonstration."""
    return [expert.values(terrain(d.terrain_hash), d.state, d.candidates) for d in demos]


@dataclass(frozen=True)
class EveryLeg:
    """One scorer for every leg, in the shape of a model (``reward_for(leg)``, ``robot``): how
    the hand-tuned reward or the expert's value is ranked against a learned model."""

    scorer: FootholdScorer
    robot: RobotDescription = LITTLEDOG

    def reward_for(self, leg: str) -> FootholdScorer:
        """The scorer, whichever leg swings."""
        return self.scorer

    def check_compatible(self, **_: Any) -> None:
        """A single scorer reads any map (its features are computed at the map's resolution)."""


def rank_scores(model, demos: Sequence, terrain: Callable[[str], object],
                expert=None, values: Sequence[np.ndarray] | None = None, *,
                margin: float = float("nan"), severe_above: float = float("nan"),
                path_bias: PathBias | None = None) -> RankScores:
    """Score ``model`` on demonstrations; ``terrain(hash)`` returns each map.

    ``model`` is anything with ``reward_for(leg)`` (a scorer per leg),
    ``robot`` and ``check_compatible(map_resolution=...)``: a
    :class:`~footfall.learning.model.FootholdModel`, or :class:`EveryLeg`.
    The reward loss uses the expert's ``values`` of each demonstration's
    candidates (computed with ``expert`` when not given; NaN without either);
    ``above_margin`` and ``severe`` count the losses above ``margin`` and
    ``severe_above`` [value units] (NaN where those are not given). With ``path_bias`` the
    model is ranked as the footstep planner picks (its values less the path bias).
    """
    return rank_scores_many({"model": model}, demos, terrain, expert, values, margin=margin,
                            severe_above=severe_above, path_bias=path_bias)["model"]


def rank_scores_many(models: dict, demos: Sequence, terrain: Callable[[str], object],
                     expert=None, values: Sequence[np.ndarray] | None = None, *,
                     margin: float = float("nan"), severe_above: float = float("nan"),
                     path_bias: PathBias | None = None) -> dict[str, RankScores]:
    """:func:`rank_scores` of several models on the same demonstrations, by name: each
    demonstration's candidates (their terrain patches, the costly part) are prepared once for
    every model with the same feature settings."""
    if values is None and expert is not None:
        values = expert_values(demos, terrain, expert)
    if not demos:
        raise FootfallError("no demonstrations to evaluate on")
    return {name: scores_of_rows(rows, margin, severe_above)
            for name, rows in decision_rows(models, demos, terrain, values, path_bias).items()}


def decision_rows(models: dict, demos: Sequence, terrain: Callable[[str], object],
                  values: Sequence[np.ndarray] | None = None, path_bias: PathBias | None = None
                  ) -> dict[str, list[tuple]]:
    """Each model's (by name) figures of each demonstration, in order: the rows
    :func:`scores_of_rows` summarises. Rows of consecutive slices of the demonstrations,
    concatenated, are the rows of all (so the slices may be scored in separate processes)."""
    found: dict[str, list] = {name: [] for name in models}
    for k, d, name, r in _scored(models, demos, terrain, path_bias):
        found[name].append(_decision(r, d, None if values is None else values[k]))
    return found


def best_picks(model, demos: Sequence, terrain: Callable[[str], object],
               path_bias: PathBias | None = None) -> list[np.ndarray]:
    """The candidates (indices) ``model`` values best in each demonstration, ties all given
    (its pick is any of them), ranked as :func:`decision_rows` ranks them."""
    return [np.flatnonzero(r == r.max())
            for _, _, _, r in _scored({"model": model}, demos, terrain, path_bias)]


def _scored(models: dict, demos: Sequence, terrain: Callable[[str], object],
            path_bias: PathBias | None) -> Iterator[tuple[int, Any, str, np.ndarray]]:
    """(index, demonstration, model name, its values (n,) of the candidates) for every
    demonstration and model: one demonstration at a time, its candidates' patches made once
    for every model with the same feature settings."""
    for k, d in enumerate(demos):
        hmap = terrain(d.terrain_hash)
        prepared: dict = {}
        for name, model in models.items():
            model.check_compatible(map_resolution=hmap.resolution)
            reward = model.reward_for(d.state.swing_leg)
            key = (model.robot, repr(reward.config.to_dict()))  # equal settings: one set
            if key not in prepared:
                prepared[key] = Candidates.of_state(hmap, d.state, d.candidates, reward.config,
                                                    model.robot)
            r = reward.values(prepared[key])
            if not np.isfinite(r).all():
                raise FootfallError(f"demonstration {d.id}: a candidate has no valid features")
            if path_bias is not None:
                r = r - path_bias.values(reward, d.state, d.candidates, model.robot)
            yield k, d, name, r


def _decision(r: np.ndarray, d, values: np.ndarray | None) -> tuple[float, ...]:
    """Top-1, near, percentile, reward loss (NaN without values), tied best and all alike, of
    one decision whose candidates the scorer valued ``r``: the expectations over the
    candidates tied at the best (the scorer picks any of them)."""
    picks = np.flatnonzero(r == r.max())
    top1 = float(r[d.chosen] == r.max()) / picks.size
    gaps = np.hypot(*(d.candidates[picks, :2] - d.candidates[d.chosen, :2]).T)
    near = float(np.mean(gaps <= NEAR + 1e-9))
    others = np.delete(r, d.chosen)
    pct = (float(np.mean((others < r[d.chosen]) + 0.5 * (others == r[d.chosen])))
           if others.size else 1.0)
    loss = float("nan") if values is None else float(values.max() - np.mean(values[picks]))
    return top1, near, pct, loss, float(picks.size > 1), float(picks.size == r.size > 1)


def scores_of_rows(rows: list[tuple[float, ...]], margin: float = float("nan"),
                   severe_above: float = float("nan")) -> RankScores:
    """The measures of a model's rows (:func:`decision_rows`): shares above ``margin`` and
    ``severe_above`` [value units] of its losses."""
    top1, near, pct, loss, tied, constant = (np.array(c, dtype=float) for c in zip(*rows))
    has_loss = not np.isnan(loss).any()
    losses = loss if has_loss else np.zeros(0)
    return RankScores(len(rows), float(np.mean(top1)), float(np.mean(pct)),
                      float(np.mean(loss)) if has_loss else float("nan"),
                      float(np.std(loss)) if has_loss else float("nan"),
                      top1_near=float(np.mean(near)),
                      reward_loss_ci=bootstrap_ci(losses) if has_loss else (float("nan"),) * 2,
                      losses=tuple(float(v) for v in losses),
                      above_margin=_share_above(losses, margin),
                      severe=_share_above(losses, severe_above), margin=float(margin),
                      severe_above=float(severe_above), tied=float(np.mean(tied)),
                      constant=float(np.mean(constant)))


def _share_above(losses: np.ndarray, threshold: float) -> float:
    """The fraction of ``losses`` above ``threshold`` (NaN without losses or a threshold)."""
    if losses.size == 0 or not math.isfinite(threshold):
        return float("nan")
    return float(np.mean(losses > threshold))
