"""The learned foothold model file: ranking functions for front and hind legs.

A model holds, for the front legs and for the hind legs (paper §V: their
properties differ), a linear ranking function over the feature families of
one feature set: per family its learned parameters (the kept templates and
their RBF bandwidths), the weights on its raw columns and the
standardisation the learner used; and the cross-validation record. Stored as
a versioned ``.npz`` with JSON metadata -- never pickled -- together with the
robot description and the feature settings it was trained with; loading it
for another robot or other feature settings fails with a clear error.
Version 1 files (one flat list of feature names per leg group) are still read.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.robot import LITTLEDOG, SERVO_FIELDS, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.features.family import FeatureFamily, family_class, feature_set_families
from footfall.features.reward import LinearReward
from footfall.features.templates import TemplateFeatures, TemplateLibrary

FORMAT = "footfall.model"
VERSION = 2  # 1: one list of names per group; 2: feature families, each with its parameters
LEG_GROUPS = ("front", "hind")


@dataclass(frozen=True, eq=False)
class RankingFunction:
    """A linear ranking function of one leg group over the columns of feature families."""

    families: tuple[FeatureFamily, ...]  # the families, with their learned parameters
    coef: tuple[np.ndarray, ...]  # per family (k_f,) weights on its raw columns
    scale: tuple[np.ndarray, ...]  # per family (k_f,) std of each column over the training pairs
    info: dict = field(default_factory=dict)  # lambda, C, cv error, path, the families' facts

    def __post_init__(self) -> None:
        if not (len(self.families) == len(self.coef) == len(self.scale)):
            raise FootfallError("a ranking function needs weights and scales for every family")
        for f, c, s in zip(self.families, self.coef, self.scale):
            n = len(f.columns())
            if np.shape(c) != (n,) or np.shape(s) != (n,):
                raise FootfallError(f"{f.name} weights do not match its {n} columns")

    @property
    def names(self) -> tuple[str, ...]:
        """Full column names (``family.column``), in column order."""
        return tuple(f"{f.name}.{c}" for f in self.families for c in f.columns())

    def family(self, name: str) -> FeatureFamily | None:
        """The family called ``name``, or None."""
        return next((f for f in self.families if f.name == name), None)

    def weights(self, name: str) -> np.ndarray:
        """The raw-column weights (k_f,) of the family called ``name``; empty if it has none."""
        return next((c for f, c in zip(self.families, self.coef) if f.name == name), np.zeros(0))

    @property
    def library(self) -> TemplateLibrary | None:
        """The kept templates (those with a non-zero weight), if the function has any."""
        templates = self.family(TemplateFeatures.name)
        return templates.library if isinstance(templates, TemplateFeatures) else None

    def reward(self, config: FeatureConfig, name: str = "learned") -> LinearReward:
        """The function as a :class:`LinearReward` over the same families and weights."""
        return LinearReward(self.families, self.coef, config, name)


@dataclass(frozen=True, eq=False)
class FootholdModel:
    """Ranking functions for front and hind legs, with the settings they were trained with."""

    feature_set: str  # a registered feature set ("terrain", "templates", "both") or "a+b+..."
    learner: str  # a registered learner ("l1", "l2", "svm")
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
        """Write the model (atomically) as a versioned ``.npz`` with JSON metadata.

        Arrays are named ``<group>.<family>.coef``, ``<group>.<family>.scale``
        and ``<group>.<family>.<parameter>``.
        """
        arrays: dict[str, np.ndarray] = {}
        groups: dict[str, Any] = {}
        for g, f in self.functions.items():
            families = []
            for fam, coef, scale in zip(f.families, f.coef, f.scale):
                params, meta = fam.params()
                prefix = f"{g}.{fam.name}."
                arrays[prefix + "coef"] = coef
                arrays[prefix + "scale"] = scale
                arrays.update({prefix + k: v for k, v in params.items()})
                families.append({"name": fam.name, "columns": list(fam.columns()),
                                 "params": meta})
            groups[g] = {"families": families, "info": f.info}
        save_npz(path, FORMAT, VERSION, arrays, {
            "feature_set": self.feature_set, "learner": self.learner,
            "config": self.config.to_dict(), "robot": self.robot.to_dict(),
            "map_resolution": self.map_resolution, "groups": groups, "info": self.info,
            "units": {"coef": "reward per unit of each feature", "bandwidths": "1/m^2",
                      "map_resolution": "m/cell"}})

    @classmethod
    def load(cls, path: str | os.PathLike) -> FootholdModel:
        """Read a model written by :meth:`save` (or by footfall's version 1 format)."""
        version, arrays, meta = load_npz(path, FORMAT, VERSION, allow_nonfinite=True)  # NaN:
        # an undefined figure of the training info (an SVM's log loss)
        try:
            config = FeatureConfig.from_dict(meta["config"])
            robot = RobotDescription.from_dict(meta["robot"])
            read = _read_group_v1 if version == 1 else _read_group
            functions = {g: read(g, m, arrays, config, robot, meta["feature_set"])
                         for g, m in meta["groups"].items()}
            feature_set_families(meta["feature_set"])  # a known feature set
            if set(functions) != set(LEG_GROUPS):
                raise FootfallError("the leg groups must be front and hind")
            return cls(meta["feature_set"], meta["learner"], functions, config, robot,
                       float(meta["map_resolution"]), meta.get("info", {}))
        except FootfallError as exc:
            raise FootfallError(f"{path}: malformed model ({exc})") from None
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise FootfallError(f"{path}: malformed model ({exc!r})") from None


def _read_group(group: str, meta: dict, arrays: dict, config: FeatureConfig,
                robot: RobotDescription, feature_set: str) -> RankingFunction:
    """One leg group's ranking function from a version 2 file."""
    families, coef, scale = [], [], []
    for entry in meta["families"]:
        prefix = f"{group}.{entry['name']}."
        params = {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}
        c, s = params.pop("coef"), params.pop("scale")
        family = family_class(entry["name"]).from_params(config, robot, params, entry["params"])
        if list(family.columns()) != list(entry["columns"]):
            raise FootfallError(f"{group} {entry['name']} columns do not match the file's names")
        families.append(family)
        coef.append(np.asarray(c, dtype=np.float64))
        scale.append(np.asarray(s, dtype=np.float64))
    return RankingFunction(tuple(families), tuple(coef), tuple(scale), meta["info"])


_TEMPLATE_NAME = re.compile(r"^[a-z]+\.template_\d+$")


def _read_group_v1(group: str, meta: dict, arrays: dict, config: FeatureConfig,
                   robot: RobotDescription, feature_set: str) -> RankingFunction:
    """One leg group's ranking function from a version 1 file: one flat list of names.

    Version 1 named terrain features ``scale.quantity``, templates
    ``scale.template_k`` and pose features ``pose.name``; its feature set was
    one of the paper's three.
    """
    names = list(meta["names"])
    coef, scale = arrays[f"{group}_coef"], arrays[f"{group}_scale"]
    if coef.shape != (len(names),) or scale.shape != (len(names),):
        raise FootfallError(f"{group} weights do not match its {len(names)} feature names")
    families, coefs, scales = [], [], []
    for name in feature_set_families(feature_set):
        if name == "templates":
            library = TemplateLibrary.from_arrays(arrays, meta["library"], prefix=f"{group}_lib_")
            family: FeatureFamily = TemplateFeatures(config, library, tuple(meta["bandwidths"]))
            pick = [k for k, n in enumerate(names) if _TEMPLATE_NAME.match(n)]
        else:
            family = family_class(name).create(config, robot)
            full = [f"pose.{c}" if name == "pose" else c for c in family.columns()]
            pick = [names.index(n) for n in full]
        if len(pick) != len(family.columns()):
            raise FootfallError(f"{group} {name} weights do not match its columns")
        families.append(family)
        coefs.append(np.asarray(coef[pick], dtype=np.float64))
        scales.append(np.asarray(scale[pick], dtype=np.float64))
    return RankingFunction(tuple(families), tuple(coefs), tuple(scales), meta["info"])
