"""A learned model's agreement with the expert on a store's demonstrations (``footfall rank-eval``).

Here, above both, because the measure needs the learner's model and the expert's judgement
(:mod:`footfall.learning.evaluation` explains the measures).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from footfall.core.robot import LITTLEDOG
from footfall.expert.synthetic import SyntheticExpert
from footfall.learning.evaluation import RankScores, rank_scores
from footfall.learning.model import FootholdModel
from footfall.learning.train import store_demonstrations


@dataclass(frozen=True)
class ModelAgreement:
    """How well a model file ranks a store's demonstrations like the expert."""

    model: str  # the model file, as given
    feature_set: str
    learner: str
    scores: RankScores  # top-1, percentile, reward loss, ...

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON: the model, then the scores' keys."""
        return {"model": self.model, "feature_set": self.feature_set, "learner": self.learner,
                **self.scores.as_dict()}


def rank_eval(model_path: str | os.PathLike, store_path: str | os.PathLike, *,
              with_expert: bool = True, source: str | Sequence[str] | None = None
              ) -> ModelAgreement:
    """Score the model at ``model_path`` on the store's demonstrations.

    ``with_expert`` False skips the reward loss (it needs the expert's values;
    it is NaN then, null in ``as_dict``). ``source`` keeps only demonstrations whose source
    starts with it.

    Raises
    ------
    FootfallError
        For an unreadable model or one for another robot (checked first), or a
        store without such demonstrations.
    """
    model = FootholdModel.load(model_path)
    model.check_compatible(robot=LITTLEDOG)  # the robot whose states the store holds
    demos, maps = store_demonstrations(store_path, source=source)
    expert = SyntheticExpert(robot=model.robot) if with_expert else None
    scores = rank_scores(model, demos, maps.__getitem__, expert)
    return ModelAgreement(str(model_path), model.feature_set, model.learner, scores)
