"""An expert as a foothold scorer: its judgement of F, the ceiling a learned scorer aims at.

:class:`ExpertScorer` wraps any expert (:class:`footfall.expert.protocol.Expert`,
the synthetic one by default) in the :class:`~footfall.features.scorer.FootholdScorer`
contract, so that an evaluation can rank, score and walk with the expert's own
values wherever a reward goes: walking with it as the footstep chooser
(``walk(..., judge=ExpertScorer(...))``) bounds what a function learned from
its demonstrations can do. Its terrain part only marks the footholds that are
not valid (as for the hand-tuned reward: no data, too little patch coverage,
so the candidate sets are the reward planner's); its state part is the
expert's whole value.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.expert.protocol import Expert, expert_settings, values_each
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.features.config import FeatureConfig
from footfall.features.dense import ScoreGrid
from footfall.features.family import Candidates
from footfall.features.reward import LinearReward, default_reward
from footfall.features.scorer import SCORERS, FootholdScorer


@dataclass(frozen=True, eq=False)
class ExpertScorer(FootholdScorer):
    """An expert's values of F as a scorer (the state part; the terrain part: validity only)."""

    expert: Expert  # values (hmap, state, candidates (n, 3) [m]) -> (n,), higher is better
    config: FeatureConfig = field(default_factory=FeatureConfig)  # patch coverage of validity
    name: str = "synthetic expert"
    own_path_preference: bool = True  # its stance term: walked and ranked without a path bias

    @cached_property
    def _usable(self) -> LinearReward:
        """The hand-tuned reward, whose valid footholds are the expert's candidates."""
        return default_reward(self.config)

    def family_names(self) -> tuple[str, ...]:
        """None: the expert reads the terrain itself."""
        return ()

    def terrain_values(self, c: Candidates) -> np.ndarray:
        """0 where the foothold is usable, -inf where not (n,)."""
        usable = self._usable.terrain_values(c)
        return np.where(np.isfinite(usable), 0.0, usable)

    @property
    def has_state_part(self) -> bool:
        return True

    def state_values(self, c: Candidates) -> np.ndarray:
        """The expert's value (n,) of each candidate for ``c.state``."""
        return self.state_values_each([c])[0]

    def state_values_each(self, sets: Sequence[Candidates]) -> np.ndarray:
        """The expert's values of the same footholds in each set's state (:func:`values_each`:
        its terrain analysis made once for them all), (len(sets), n)."""
        if any(c.state is None for c in sets):
            raise FootfallError("the expert values footholds for a robot state; none was given")
        if not sets or sets[0].n == 0:
            return np.zeros((len(sets), 0))
        return values_each(self.expert, sets[0].hmap, [c.state for c in sets], sets[0].footholds)

    def dense(self, hmap: HeightMap, *, spacing: float = 0.005, yaw: float = 0.0,
              mirror: bool = False, dtype: type = np.float32, fast: bool = True) -> ScoreGrid:
        """Usable lattice points (0) and the others (-inf), from the hand-tuned reward's grid."""
        grid = self._usable.dense(hmap, spacing=spacing, yaw=yaw, mirror=mirror, dtype=dtype,
                                  fast=fast)
        return ScoreGrid(grid.x, grid.y, np.where(np.isfinite(grid.reward), 0.0, grid.reward),
                         grid.valid)

    def key(self, state: bool) -> str:
        """The validity of the hand-tuned reward's footholds (terrain), or the expert's settings."""
        if state:
            text = json.dumps(expert_settings(self.expert), sort_keys=True)
        else:
            text = "usable:" + self._usable.key(state=False)
        return hashlib.sha256(f"expert-scorer:{text}".encode()).hexdigest()


def judge_name(config: ExpertConfig) -> str:
    """How a run log names the expert that chose its footholds: "synthetic expert" for the
    walking expert (:func:`~footfall.expert.synthetic.walking_expert` at the config's stance
    lead), else that followed by the first 8 hex digits of a hash of the settings."""
    if config == walking_expert(config.stance_lead):
        return "synthetic expert"
    return f"synthetic expert {settings_hash(config)}"


def settings_hash(config: ExpertConfig) -> str:
    """The first 8 hex digits of the SHA-256 of the expert's settings (sorted JSON)."""
    text = json.dumps(config.to_dict(), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def synthetic_expert_scorer(config: FeatureConfig | None = None) -> ExpertScorer:
    """The synthetic expert's own value as a scorer (``"expert"`` in :data:`SCORERS`): the
    ceiling of an offline evaluation, where its loss against itself is zero."""
    return ExpertScorer(SyntheticExpert(), config or FeatureConfig())


SCORERS.register("expert", synthetic_expert_scorer)
