"""A linear foothold reward R(f) = w^T x over named features (paper Eq. 1).

The features of a foothold are the 27 terrain features, the template
features of a library (Eq. 4) and the pose features of the robot's state.
Learned ranking functions and the hand-tuned default are both a
:class:`LinearReward`; the standardisation a learner applies is folded into
the weights, so a reward is always evaluated on raw features.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from footfall.core.errors import FootfallError
from footfall.features.patches import FootholdPatches
from footfall.features.pose_features import POSE_FEATURE_NAMES
from footfall.features.config import FeatureConfig
from footfall.features.templates import TemplateLibrary, bandwidth_for_rms
from footfall.features.terrain_features import feature_names, terrain_features_from_patches


@dataclass(frozen=True, eq=False)
class LinearReward:
    """Weights over terrain, template and pose features.

    ``terrain_weights`` follow :func:`footfall.features.terrain_features.feature_names`,
    ``pose_weights`` follow :data:`footfall.features.pose_features.POSE_FEATURE_NAMES`,
    ``template_weights[s]`` the templates of scale s in ``library``;
    ``bandwidths[s]`` is the RBF bandwidth h [1/m^2] of scale s.
    """

    config: FeatureConfig = field(default_factory=FeatureConfig)
    terrain_weights: np.ndarray = field(default_factory=lambda: np.zeros(27))  # (27,)
    pose_weights: np.ndarray = field(default_factory=lambda: np.zeros(len(POSE_FEATURE_NAMES)))
    library: TemplateLibrary | None = None
    template_weights: tuple[np.ndarray, ...] = ()  # per scale (T_s,)
    bandwidths: tuple[float, ...] = ()  # per scale [1/m^2]
    name: str = "reward"

    def __post_init__(self) -> None:
        n_terrain = len(feature_names(self.config))
        tw = np.asarray(self.terrain_weights, dtype=np.float64)
        pw = np.asarray(self.pose_weights, dtype=np.float64)
        if tw.shape != (n_terrain,):
            raise FootfallError(f"terrain weights must have shape ({n_terrain},), got {tw.shape}")
        if pw.shape != (len(POSE_FEATURE_NAMES),):
            raise FootfallError(f"pose weights must have shape ({len(POSE_FEATURE_NAMES)},)")
        if self.library is None:
            object.__setattr__(self, "template_weights", ())
        else:
            if self.library.config != self.config:
                raise FootfallError("template library and reward use different feature settings")
            tws = tuple(np.asarray(w, dtype=np.float64) for w in self.template_weights)
            if tuple(w.shape for w in tws) != tuple((c,) for c in self.library.counts):
                raise FootfallError("template weights must match the library's template counts")
            if len(self.bandwidths) != len(self.config.scales) or min(self.bandwidths) <= 0:
                raise FootfallError("need one bandwidth h > 0 per scale")
            object.__setattr__(self, "template_weights", tws)
            object.__setattr__(self, "bandwidths", tuple(float(h) for h in self.bandwidths))
        if not (np.isfinite(tw).all() and np.isfinite(pw).all()
                and all(np.isfinite(w).all() for w in self.template_weights)):
            raise FootfallError("reward weights must be finite")
        object.__setattr__(self, "terrain_weights", tw)
        object.__setattr__(self, "pose_weights", pw)

    @property
    def has_templates(self) -> bool:
        """Whether any template carries weight."""
        return self.library is not None and any(np.any(w != 0) for w in self.template_weights)

    def terrain_reward(self, patches: FootholdPatches) -> np.ndarray:
        """Terrain part of the reward (terrain features + templates) of footholds, (n,).

        Footholds that are not valid (no data, too little coverage) get -inf.
        """
        r = terrain_features_from_patches(patches.relative, self.config) @ self.terrain_weights
        if self.library is not None:
            x = self.library.features(patches.relative, self.bandwidths)
            r = r + x @ np.concatenate(self.template_weights)
        return np.where(patches.valid, r, -np.inf)

    def named_weights(self) -> dict[str, float]:
        """Every non-zero weight by feature name."""
        names = list(feature_names(self.config)) + list(POSE_FEATURE_NAMES)
        values = list(self.terrain_weights) + list(self.pose_weights)
        if self.library is not None:
            names += list(self.library.names())
            values += list(np.concatenate(self.template_weights))
        return {n: float(v) for n, v in zip(names, values) if v != 0}


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
_DEFAULT_POSE_WEIGHTS: dict[str, float] = {}


def default_reward(config: FeatureConfig | None = None) -> LinearReward:
    """The hand-tuned foothold reward footfall walks with before it has learned one."""
    config = config or FeatureConfig()
    library, names = analytic_templates(config)
    per_template = np.array([_DEFAULT_TEMPLATE_WEIGHTS[n] for n in names])
    return LinearReward(
        config=config,
        terrain_weights=weights_from_names(_DEFAULT_TERRAIN_WEIGHTS, feature_names(config)),
        pose_weights=weights_from_names(_DEFAULT_POSE_WEIGHTS, POSE_FEATURE_NAMES),
        library=library,
        template_weights=tuple(per_template.copy() for _ in config.scales),
        bandwidths=tuple(bandwidth_for_rms(_DEFAULT_TEMPLATE_RMS, g) for g in config.grids),
        name="hand-tuned default")
