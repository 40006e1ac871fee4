"""A linear foothold reward R(f) = w^T x over the columns of feature families (paper Eq. 1).

A reward holds feature families (terrain features, templates, pose features,
or any registered family: :mod:`footfall.features.family`) and one weight per
column of each, on the raw features. It is a
:class:`~footfall.features.scorer.FootholdScorer`: the hand-tuned default and
every function a linear learner learns are one (the standardisation a learner
applies is folded into the weights). The *terrain part* sums the families
that read only the terrain (scored densely over a whole board by one matrix
product per scale); the *state part* sums those that need the robot's state
(pose).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.features.config import FeatureConfig
from footfall.features.dense import ScoreGrid, linear_values
from footfall.features.dense_linear import dense_linear
from footfall.features.family import Candidates, FeatureFamily
from footfall.features.scorer import SCORERS, FootholdScorer
from footfall.features.template_library import TemplateLibrary
from footfall.features.templates import TemplateFeatures
from footfall.features.terrain_features import TerrainFeatures


@dataclass(frozen=True, eq=False)
class LinearReward(FootholdScorer):
    """Weights over the columns of feature families: a linear foothold scorer.

    ``weights[k]`` (len(families[k].columns()),) weighs the columns of
    ``families[k]``, in their order; a column's full name is
    ``"<family>.<column>"`` (e.g. ``"terrain.small.std"``, ``"pose.progress"``).
    """

    families: tuple[FeatureFamily, ...] = ()
    weights: tuple[np.ndarray, ...] = ()  # per family (k_f,) reward per unit of each feature
    config: FeatureConfig = field(default_factory=FeatureConfig)
    name: str = "reward"

    def __post_init__(self) -> None:
        families = tuple(self.families)
        if len(self.weights) != len(families):
            raise FootfallError("a reward needs one weight vector per feature family")
        names = [f.name for f in families]
        if len(set(names)) != len(names):
            raise FootfallError(f"a reward holds each feature family once, got {names}")
        weights = []
        for family, w in zip(families, self.weights):
            if not isinstance(family, FeatureFamily):
                raise FootfallError(f"not a feature family: {type(family).__name__}")
            if getattr(family, "config", self.config) != self.config:
                raise FootfallError(f"the {family.name} features and the reward use different "
                                    f"feature settings")
            try:
                w = np.array(w, dtype=np.float64)
            except (TypeError, ValueError):
                raise FootfallError(f"{family.name} weights must be numbers") from None
            n = len(family.columns())
            if w.shape != (n,):
                raise FootfallError(f"{family.name} weights must have shape ({n},), got {w.shape}")
            if not np.isfinite(w).all():
                raise FootfallError("reward weights must be finite")
            w.setflags(write=False)
            weights.append(w)
        object.__setattr__(self, "families", families)
        object.__setattr__(self, "weights", tuple(weights))

    @classmethod
    def from_names(cls, families: Sequence[FeatureFamily], weights: Mapping[str, float],
                   config: FeatureConfig | None = None, name: str = "reward") -> LinearReward:
        """A reward from weights by full column name (``"family.column"``); others are 0."""
        config = config or FeatureConfig()
        vectors = [weights_from_names({k[len(f.name) + 1:]: v for k, v in weights.items()
                                       if k.startswith(f.name + ".")}, f.columns())
                   for f in families]
        known = {f"{f.name}.{c}" for f in families for c in f.columns()}
        unknown = set(weights) - known
        if unknown:
            raise FootfallError(f"unknown feature name(s): {', '.join(sorted(unknown))}")
        return cls(tuple(families), tuple(vectors), config, name)

    # ------------------------------------------------------------------ parts
    def parts(self, state: bool | None = None) -> list[tuple[FeatureFamily, np.ndarray]]:
        """(family, weights) pairs with a non-zero weight; ``state`` picks the state or terrain part."""
        return [(f, w) for f, w in zip(self.families, self.weights)
                if np.any(w != 0) and (state is None or f.needs_state == state)]

    def family(self, name: str) -> tuple[FeatureFamily, np.ndarray] | None:
        """The family called ``name`` with its weights, or None."""
        for f, w in zip(self.families, self.weights):
            if f.name == name:
                return f, w
        return None

    def with_weights(self, family: FeatureFamily, weights: np.ndarray, name: str | None = None
                     ) -> LinearReward:
        """This reward with ``family``'s weights replaced (the family added if it is not here)."""
        fams, ws = list(self.families), list(self.weights)
        for k, f in enumerate(fams):
            if f.name == family.name:
                fams[k], ws[k] = family, weights
                break
        else:
            fams.append(family)
            ws.append(weights)
        return LinearReward(tuple(fams), tuple(ws), self.config, name or self.name)

    def scaled(self, factor: float, state: bool | None = None, name: str | None = None
               ) -> LinearReward:
        """Every weight (or those of the terrain or the state part) times ``factor``."""
        ws = tuple(w * factor if state is None or f.needs_state == state else w
                   for f, w in zip(self.families, self.weights))
        return LinearReward(self.families, ws, self.config, name or self.name)

    @property
    def has_state_part(self) -> bool:
        """Whether a family that needs the robot's state carries weight (pose features)."""
        return bool(self.parts(state=True))

    @property
    def has_templates(self) -> bool:
        """Whether any template carries weight."""
        return any(isinstance(f, TemplateFeatures) for f, _ in self.parts())

    # ----------------------------------------------------------------- values
    def family_names(self) -> tuple[str, ...]:
        """Names of the families it reads: those with a non-zero weight."""
        return tuple(f.name for f, _ in self.parts())

    def terrain_values(self, c: Candidates) -> np.ndarray:
        """The terrain part (families that read only the terrain) of candidates, (n,).

        Footholds that are not valid (no data, too little patch coverage) get -inf.
        """
        return np.where(c.patches.valid, linear_values(c, self.parts(state=False)), -np.inf)

    def state_values(self, c: Candidates) -> np.ndarray:
        """The state part (families that need ``c.state``) of candidates, (n,); 0 without one."""
        return linear_values(c, self.parts(state=True))

    def dense(self, hmap: HeightMap, *, spacing: float = 0.005, yaw: float = 0.0,
              mirror: bool = False, dtype: type = np.float32, fast: bool = True) -> ScoreGrid:
        """The terrain part at every lattice point: one matrix product per scale where the
        lattice lines up with the map (:func:`~footfall.features.dense.dense_linear`)."""
        return dense_linear(hmap, self.parts(state=False), self.config, spacing=spacing, yaw=yaw,
                            mirror=mirror, dtype=dtype, fast=fast)

    def named_weights(self) -> dict[str, float]:
        """Every non-zero weight by full column name."""
        return {f"{f.name}.{n}": float(v) for f, w in zip(self.families, self.weights)
                for n, v in zip(f.columns(), w) if v != 0}

    def key(self, state: bool) -> str:
        """Digest of the terrain part (``state`` False) or the state part: equal parts, equal keys.

        Families without weight do not count, so a reward with zero pose
        weights has the state key of one without pose features.
        """
        digest = hashlib.sha256(repr(self.config.to_dict()).encode())
        for family, w in self.parts(state=state):
            digest.update(family.name.encode())
            digest.update(family.digest().encode())
            digest.update(np.ascontiguousarray(w).tobytes())
        return digest.hexdigest()


def weights_from_names(weights: Mapping[str, float], names: tuple[str, ...]) -> np.ndarray:
    """A weight vector in ``names`` order from a name -> weight mapping (unknown names fail)."""
    unknown = set(weights) - set(names)
    if unknown:
        raise FootfallError(f"unknown feature name(s): {', '.join(sorted(unknown))}")
    return np.array([float(weights.get(n, 0.0)) for n in names])


def analytic_templates(config: FeatureConfig) -> tuple[TemplateLibrary, tuple[str, ...]]:
    """The three footholds of the paper's Fig. 2 as templates on every scale.

    Relative heights [m] around the foothold: ``flat`` (0 everywhere), a
    ``mild_hollow`` (a bowl 4 mm deep at 20 mm from the foothold: the ball
    foot is held and does not slip), and a ``deep_hole`` (a 9 mm radius hole
    25 mm deep: the foot gets stuck). Returns the library and the names.
    """
    names = ("flat", "mild_hollow", "deep_hole")
    templates, sources = [], []
    for grid in config.grids:
        u, v = np.meshgrid(grid.u, grid.v, indexing="ij")
        r = np.hypot(u, v)
        flat = np.zeros_like(r)
        hollow = np.minimum(r, 0.02) ** 2 * (0.004 / 0.02 ** 2)
        hole = np.where(r < 0.009, -0.025, 0.0)
        hole = hole - hole.ravel()[grid.size // 2]  # relative to the foothold (at the bottom)
        templates.append(np.stack([flat.ravel(), hollow.ravel(), hole.ravel()]))
        sources.append(np.full((3, 4), np.nan))
    return TemplateLibrary(config, tuple(templates), tuple(sources), ()), names


# Hand-tuned weights of the default reward. Slopes and roughness cost reward
# (the foot slips, the leg collides); a mild hollow on the small and medium
# scale earns it, a deep narrow hole costs it (Fig. 2 of the paper).
_DEFAULT_TERRAIN_WEIGHTS = {
    **{f"{s}.{q}": w for s, k in (("small", 1.0), ("medium", 1.5), ("large", 0.8))
       for q, w in (("slope_x_pos", -2.0 * k), ("slope_x_neg", -2.0 * k),
                    ("slope_y_pos", -2.0 * k), ("slope_y_neg", -2.0 * k))},
    "small.std": -150.0, "medium.std": -120.0, "large.std": -40.0,
    "small.curv_x_neg": -0.02, "small.curv_y_neg": -0.02,
    "medium.curv_x_neg": -0.03, "medium.curv_y_neg": -0.03,
}
_DEFAULT_TEMPLATE_WEIGHTS = {"flat": 0.0, "mild_hollow": 1.0, "deep_hole": -3.0}
_DEFAULT_TEMPLATE_RMS = 0.004  # [m] RMS height difference at which a template match is exp(-1)


def default_reward(config: FeatureConfig | None = None) -> LinearReward:
    """The hand-tuned foothold reward footfall walks with before it has learned one.

    Terrain features and the Fig. 2 templates; no pose features (the footstep
    planner's path bias does their job).
    """
    config = config or FeatureConfig()
    library, names = analytic_templates(config)
    per_template = np.array([_DEFAULT_TEMPLATE_WEIGHTS[n] for n in names])
    terrain = TerrainFeatures(config)
    templates = TemplateFeatures(config, library).with_rms(
        (_DEFAULT_TEMPLATE_RMS,) * len(config.scales))
    return LinearReward(
        families=(templates, terrain),
        weights=(np.concatenate([per_template for _ in config.scales]),
                 weights_from_names(_DEFAULT_TERRAIN_WEIGHTS, terrain.columns())),
        config=config, name="hand-tuned default")


SCORERS.register("hand-tuned", default_reward)
