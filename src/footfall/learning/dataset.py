"""Demonstrations as learning data: template libraries and candidate feature matrices.

Turns demonstrations (a terrain, a state, the candidate set F, the chosen
index) into the features a ranking function is learned on, for each of the
paper's three feature sets -- terrain features only, templates only,
templates + terrain features -- each with the pose features (§V). Template
features are kept as squared patch distances, which do not depend on the
RBF bandwidth, so the bandwidth can be chosen by cross-validation without
recomputing patches.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.features.patches import foothold_patches
from footfall.features.pose_features import POSE_FEATURE_NAMES, pose_features
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.core.state import RobotState
from footfall.features.templates import TemplateLibrary, extract_templates, merge_libraries, \
    squared_distances
from footfall.features.terrain_features import feature_names, terrain_features_from_patches

FEATURE_SETS = ("terrain", "templates", "both")  # the paper's (a), (b), (c)
DEFAULT_LIBRARY_SIZE = 1000  # templates over the three scales (the paper had 946)
DEFAULT_TRAINING_CANDIDATES = 100  # other candidates per demonstration used for training pairs


def check_feature_set(feature_set: str) -> str:
    """Validate a feature-set name."""
    if feature_set not in FEATURE_SETS:
        raise FootfallError(f"unknown feature set {feature_set!r}; use one of {', '.join(FEATURE_SETS)}")
    return feature_set


@dataclass(frozen=True)
class Example:
    """One demonstration's candidates with their bandwidth-free features."""

    terrain: np.ndarray  # (n, 27) terrain features
    pose: np.ndarray  # (n, 26) pose features
    distances: tuple[np.ndarray, ...]  # per scale (n, T_s) [m^2] squared distances to templates
    chosen: int  # index of the demonstrated foothold among the n rows
    front: bool  # a front-leg demonstration
    rows: np.ndarray  # (n,) indices of these rows in the demonstration's full candidate set


def build_library(maps: Sequence[HeightMap], states: Sequence[RobotState],
                  candidates: Sequence[np.ndarray], chosen: Sequence[int], config: FeatureConfig,
                  rng: np.random.Generator, size: int = DEFAULT_LIBRARY_SIZE,
                  robot: RobotDescription = LITTLEDOG) -> TemplateLibrary:
    """A template library from training demonstrations (paper §III-A).

    Every chosen foothold, then a random sample of the other reachable ones
    up to ``size / 3`` per scale (so more than ``size`` templates when there
    are more demonstrations than that); right-leg footholds are mirrored.
    Footholds whose patch on a scale is incomplete give no template there.
    ``maps[k]`` is the terrain of demonstration k.
    """
    if not states:
        raise FootfallError("no demonstrations to build a template library from")
    per_scale = max(1, size // len(config.scales))
    n_demo = len(states)
    chosen_rows = [(k, int(chosen[k])) for k in range(n_demo)]
    sizes = np.array([c.shape[0] for c in candidates])
    extra = max(0, per_scale - n_demo)
    # Sample "other" candidates uniformly over all demonstrations, without a
    # Python loop over candidates: draw flat indices and map them back.
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    flat = rng.choice(offsets[-1], size=min(offsets[-1], extra + n_demo), replace=False)
    demo = np.searchsorted(offsets, flat, side="right") - 1
    row = flat - offsets[demo]
    keep = row != np.asarray(chosen)[demo]
    picks = chosen_rows + list(zip(demo[keep][:extra].tolist(), row[keep][:extra].tolist()))
    libraries = []
    by_map: dict[int, list[tuple[int, int]]] = {}
    for k, j in picks:
        by_map.setdefault(id(maps[k]), []).append((k, j))
    for group in by_map.values():  # one extraction per terrain map
        k0 = group[0][0]
        pos = np.array([candidates[k][j, :2] for k, j in group])
        yaw = np.array([states[k].yaw for k, _ in group])
        mirror = np.array([robot.leg(states[k].swing_leg).mirrored for k, _ in group])
        libraries.append(extract_templates(maps[k0], pos, yaw, mirror, config))
    return merge_libraries(libraries)


def make_example(hmap: HeightMap, state: RobotState, candidates: np.ndarray, chosen: int,
                 library: TemplateLibrary | None, config: FeatureConfig,
                 rows: np.ndarray | None = None, robot: RobotDescription = LITTLEDOG) -> Example:
    """Bandwidth-free features of (a subset ``rows`` of) a demonstration's candidates."""
    rows = np.arange(candidates.shape[0]) if rows is None else np.asarray(rows)
    if not 0 <= chosen < candidates.shape[0] or chosen not in rows:
        raise FootfallError("the chosen candidate must be among the rows")
    f = candidates[rows]
    leg = robot.leg(state.swing_leg)
    fp = foothold_patches(hmap, f, state.yaw, leg.mirrored, config)
    if not fp.valid.all():
        raise FootfallError("a candidate has too little terrain data for its features")
    terrain = terrain_features_from_patches(fp.relative, config)
    pose = pose_features(hmap, state, f, robot)
    distances = () if library is None else tuple(
        squared_distances(rel, t) for rel, t in zip(fp.relative, library.templates))
    return Example(terrain, pose, distances, int(np.flatnonzero(rows == chosen)[0]),
                   leg.front, rows)


def training_rows(n: int, chosen: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """The chosen row and up to ``k`` other rows drawn at random, sorted."""
    others = np.delete(np.arange(n), chosen)
    if others.size > k:
        others = rng.choice(others, size=k, replace=False)
    return np.sort(np.append(others, chosen))


def design_matrix(example: Example, feature_set: str, bandwidths: Sequence[float] | None
                  ) -> np.ndarray:
    """The feature matrix (n, d) of an example for a feature set, in :func:`column_names` order."""
    parts = []
    if feature_set in ("terrain", "both"):
        parts.append(example.terrain)
    if feature_set in ("templates", "both"):
        parts.extend(np.exp(-h * d) for h, d in zip(bandwidths, example.distances))
    parts.append(example.pose)
    return np.concatenate(parts, axis=1)


def column_names(feature_set: str, library: TemplateLibrary | None,
                 config: FeatureConfig) -> tuple[str, ...]:
    """Names of the design matrix's columns."""
    names: list[str] = []
    if feature_set in ("terrain", "both"):
        names += feature_names(config)
    if feature_set in ("templates", "both"):
        names += library.names()
    return tuple(names) + tuple(f"pose.{n}" for n in POSE_FEATURE_NAMES)


def stack(examples: Sequence[Example], feature_set: str, bandwidths: Sequence[float] | None
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stacked X (N, d), y (N,) (1 = chosen) and groups (N,) of examples."""
    X = np.concatenate([design_matrix(e, feature_set, bandwidths) for e in examples])
    y = np.concatenate([np.eye(1, e.terrain.shape[0], e.chosen, dtype=int)[0] for e in examples])
    groups = np.concatenate([np.full(e.terrain.shape[0], k) for k, e in enumerate(examples)])
    return X, y, groups
