"""The footstep planner of a judge: the synthetic expert choosing every foothold."""

from __future__ import annotations

from dataclasses import replace

from footfall.control.body_path import BodyPath
from footfall.control.footstep import FootstepConfig, FootstepPlanner
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.features.dense import ScoreGrid
from footfall.features.scorer import FootholdScorer


class JudgedFootstepPlanner(FootstepPlanner):
    """The footstep planner with a judge in place of the reward function and the path bias.

    The judge -- the synthetic expert wrapped as a scorer
    (:class:`footfall.expert.scorer.ExpertScorer`), say -- values every
    candidate of every step, the look-ahead included; it carries its own
    preference for the path (the walking expert's stance term), so there is no
    separate bias. Walking with the expert as its own footstep chooser bounds
    what a function learned from its demonstrations can do. Which lattice
    points are usable is the judge's terrain part (for the expert: data, inside
    the map, feature patches covered, as for the hand-tuned reward, so the
    candidate sets are the reward planner's). Every candidate is judged
    (``pose_candidates`` and ``lookahead_candidates`` do not apply): about
    0.5 s per step with the synthetic expert, a hundred times the reward
    planner's time.
    """

    def __init__(self, hmap: HeightMap, judge: FootholdScorer, path: BodyPath,
                 robot: RobotDescription = LITTLEDOG, config: FootstepConfig = FootstepConfig(),
                 grids: dict[str, ScoreGrid] | None = None) -> None:
        if not isinstance(judge, FootholdScorer):
            raise FootfallError(f"a judged footstep planner needs a FootholdScorer, "
                                f"got {type(judge).__name__}")
        config = replace(config, pose_candidates=None, lookahead_candidates=1 << 30)
        self.judge = judge
        super().__init__(hmap, lambda leg: judge, path, robot, config, grids)
        self._posed = {name: True for name in LEG_NAMES}  # every candidate judged whole

    def _bias_weights(self) -> dict[str, float]:
        """No path bias: the judge carries its own preference for the path."""
        return {name: 0.0 for name in LEG_NAMES}
