"""The learned foothold model file: ranking functions for front and hind legs.

A model holds, for the front legs and for the hind legs (paper §V: their
properties differ), a linear ranking function over one feature set: weights
on raw features, the standardisation the learner used, the kept templates
(those with a non-zero weight) and their RBF bandwidths, and the
cross-validation record. Stored as a versioned ``.npz`` with JSON metadata --
never pickled -- together with the robot description and the feature
settings it was trained with; loading it for another robot or other feature
settings fails with a clear error.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.learning.dataset import FEATURE_SETS
from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.features.pose_features import POSE_FEATURE_NAMES
from footfall.features.reward import LinearReward
from footfall.core.robot import SERVO_FIELDS, LITTLEDOG, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.features.templates import TemplateLibrary
from footfall.features.terrain_features import feature_names

FORMAT = "footfall.model"
VERSION = 1
LEG_GROUPS = ("front", "hind")


@dataclass(frozen=True, eq=False)
class RankingFunction:
    """A linear ranking function of one leg group over named features."""

    names: tuple[str, ...]  # (d,) feature names, in column order
    coef: np.ndarray  # (d,) weights on the raw features
    scale: np.ndarray  # (d,) standard deviation of each feature over the training pairs
    library: TemplateLibrary | None  # the kept templates (non-zero weight), in column order
    bandwidths: tuple[float, ...]  # per scale [1/m^2]
    info: dict = field(default_factory=dict)  # lambda, C, cv error, path, library sizes, counts

    def reward(self, config: FeatureConfig, name: str = "learned") -> LinearReward:
        """The function as a :class:`LinearReward` (templates, terrain and pose weights)."""
        w = dict(zip(self.names, self.coef))
        terrain = np.array([w.get(n, 0.0) for n in feature_names(config)])
        pose = np.array([w.get(f"pose.{n}", 0.0) for n in POSE_FEATURE_NAMES])
        if self.library is None:
            return LinearReward(config=config, terrain_weights=terrain, pose_weights=pose,
                                name=name)
        tw = tuple(np.array([w[n] for n in names]) for names in _library_names(self.library))
        return LinearReward(config=config, terrain_weights=terrain, pose_weights=pose,
                            library=self.library, template_weights=tw,
                            bandwidths=self.bandwidths, name=name)


def _library_names(library: TemplateLibrary) -> list[list[str]]:
    names = list(library.names())
    out, start = [], 0
    for c in library.counts:
        out.append(names[start:start + c])
        start += c
    return out


@dataclass(frozen=True, eq=False)
class FootholdModel:
    """Ranking functions for front and hind legs, with the settings they were trained with."""

    feature_set: str  # "terrain", "templates" or "both"
    learner: str  # "l1", "l2" or "svm"
    functions: dict  # {"front": RankingFunction, "hind": RankingFunction}
    config: FeatureConfig
    robot: RobotDescription = LITTLEDOG
    map_resolution: float = 0.001  # [m/cell] of the terrains it was trained on
    info: dict = field(default_factory=dict)  # training summary (demonstrations, seed, times)

    def function_for(self, leg: str) -> RankingFunction:
        """The ranking function of a leg (LF, RF -> front; LH, RH -> hind)."""
        return self.functions["front" if self.robot.leg(leg).front else "hind"]

    def reward_for(self, leg: str) -> LinearReward:
        """The reward a leg's footholds are ranked by."""
        group = "front" if self.robot.leg(leg).front else "hind"
        return self.functions[group].reward(self.config, name=f"{self.feature_set}/{self.learner}/{group}")

    def check_compatible(self, robot: RobotDescription | None = None,
                         config: FeatureConfig | None = None,
                         map_resolution: float | None = None) -> None:
        """Fail with a clear error if the model cannot be used in this setting."""
        mine = {k: v for k, v in self.robot.to_dict().items() if k not in SERVO_FIELDS}
        diff = [] if robot is None else sorted(
            k for k, v in robot.to_dict().items() if k not in SERVO_FIELDS and mine.get(k) != v)
        if diff:
            raise FootfallError(f"model was trained for robot {self.robot.name!r} with other "
                                f"numbers ({', '.join(diff[:4])}{'...' if len(diff) > 4 else ''})")
        if config is not None and config != self.config:
            raise FootfallError(f"model was trained with other feature settings "
                                f"({self.config.to_dict()} vs {config.to_dict()})")
        if map_resolution is not None and map_resolution > self.config.template_resolution + 1e-12:
            raise FootfallError(f"map resolution {map_resolution * 1000:g} mm is coarser than the "
                                f"model's template resolution "
                                f"{self.config.template_resolution * 1000:g} mm")

    def templates_kept(self) -> dict[str, dict[str, list[int]]]:
        """Table I: per leg group, templates kept per scale and the library size per scale."""
        out = {}
        for g, f in self.functions.items():
            kept = list(f.library.counts) if f.library is not None else [0] * len(self.config.scales)
            out[g] = {"kept": kept, "library": list(f.info.get("library_counts", kept))}
        return out

    # --------------------------------------------------------------------- I/O
    def save(self, path: str | os.PathLike) -> None:
        """Write the model (atomically) as a versioned ``.npz`` with JSON metadata."""
        arrays: dict[str, np.ndarray] = {}
        groups: dict[str, Any] = {}
        for g, f in self.functions.items():
            arrays[f"{g}_coef"] = f.coef
            arrays[f"{g}_scale"] = f.scale
            meta: dict[str, Any] = {"names": list(f.names), "bandwidths": list(f.bandwidths),
                                    "info": f.info, "library": None}
            if f.library is not None:
                arrays.update(f.library.arrays(prefix=f"{g}_lib_"))
                meta["library"] = f.library.meta()
            groups[g] = meta
        save_npz(path, FORMAT, VERSION, arrays, {
            "feature_set": self.feature_set, "learner": self.learner,
            "config": self.config.to_dict(), "robot": self.robot.to_dict(),
            "map_resolution": self.map_resolution, "groups": groups, "info": self.info,
            "units": {"coef": "reward per unit of each feature", "bandwidths": "1/m^2",
                      "map_resolution": "m/cell"}})

    @classmethod
    def load(cls, path: str | os.PathLike) -> "FootholdModel":
        """Read a model written by :meth:`save`."""
        _, arrays, meta = load_npz(path, FORMAT, VERSION)
        try:
            config = FeatureConfig.from_dict(meta["config"])
            robot = RobotDescription.from_dict(meta["robot"])
            functions = {}
            for g, m in meta["groups"].items():
                lib = None if m["library"] is None else TemplateLibrary.from_arrays(
                    arrays, m["library"], prefix=f"{g}_lib_")
                names = tuple(m["names"])
                coef, scale = arrays[f"{g}_coef"], arrays[f"{g}_scale"]
                if coef.shape != (len(names),) or scale.shape != (len(names),):
                    raise FootfallError(f"{g} weights do not match its {len(names)} feature names")
                functions[g] = RankingFunction(names, coef, scale, lib,
                                               tuple(m["bandwidths"]), m["info"])
            if meta["feature_set"] not in FEATURE_SETS or set(functions) != set(LEG_GROUPS):
                raise FootfallError("unknown feature set or leg groups")
            return cls(meta["feature_set"], meta["learner"], functions, config, robot,
                       float(meta["map_resolution"]), meta.get("info", {}))
        except FootfallError as exc:
            raise FootfallError(f"{path}: malformed model ({exc})") from None
        except (KeyError, TypeError, ValueError) as exc:
            raise FootfallError(f"{path}: malformed model ({exc!r})") from None
