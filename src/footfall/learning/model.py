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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.robot import LITTLEDOG, SERVO_FIELDS, RobotDescription
from footfall.core.validate import (
    require_float_array,
    require_int,
    require_keys,
    require_number,
    require_str_list,
    require_type,
    shown,
)
from footfall.features.config import FeatureConfig
from footfall.features.family import FeatureFamily, family_class, feature_set_families
from footfall.features.reward import LinearReward
from footfall.features.templates import TemplateFeatures, TemplateLibrary, check_bandwidths

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
        """Read a model written by :meth:`save` (or by footfall's version 1 format).

        Every field and array is checked (:func:`read_model`): a malformed file
        fails with one :class:`FootfallError` naming the file and the field.
        """
        version, arrays, meta = load_npz(path, FORMAT, VERSION, allow_nonfinite=True)  # NaN:
        # an undefined figure of the training info (an SVM's log loss)
        try:
            return read_model(version, arrays, meta)
        except FootfallError as exc:
            raise FootfallError(f"{path}: malformed model: {exc}") from None


MAX_WEIGHT = 1e20
"""Largest |weight| [reward per unit of feature] and feature scale a model file may hold.

Learned weights are w / scale with the scale floored at 1e-12, so well below; the bound keeps
every product of a weight with a feature (and the dense scorer's float32 sums) finite."""
MAX_MAP_RESOLUTION = 1.0  # [m/cell] coarsest training-map resolution a model file may state
_META_KEYS = ("feature_set", "learner", "config", "robot", "map_resolution", "groups")


def read_model(version: int, arrays: dict[str, np.ndarray], meta: Any) -> FootholdModel:
    """A model from the arrays and metadata of its file, every field checked.

    Raises
    ------
    FootfallError
        Naming the field (``groups.front.families[1].params.bandwidths[0]``) or
        array (``front.templates.coef``) that is missing, unexpected, of the wrong
        type or shape, not finite or out of range.
    """
    from footfall.learning.ranker import get_learner  # imports scikit-learn: only when loading

    require_keys(meta, "meta", _META_KEYS, optional=("info", "units"))
    for key, value in arrays.items():
        require_float_array(value, f"array {key}", finite=False)
    feature_set = require_type(meta["feature_set"], str, "feature_set")
    names = feature_set_families(feature_set)
    get_learner(require_type(meta["learner"], str, "learner"))
    config = FeatureConfig.from_dict(meta["config"])
    robot = RobotDescription.from_dict(meta["robot"])
    resolution = require_number(meta["map_resolution"], "map_resolution [m/cell]", 0.0,
                                MAX_MAP_RESOLUTION, low_open=True)
    groups = require_keys(meta["groups"], "groups", LEG_GROUPS)
    read = _read_group_v1 if version == 1 else _read_group
    functions = {g: read(g, groups[g], arrays, config, robot, names) for g in LEG_GROUPS}
    _refuse_extra_arrays(arrays, functions, version)
    info = require_type(meta.get("info", {}), dict, "info")
    return FootholdModel(feature_set, meta["learner"], functions, config, robot, resolution, info)


def _weights(arrays: dict[str, np.ndarray], key: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The weights ``<key>coef`` and scales ``<key>scale`` (n,) of a family, checked."""
    for name in ("coef", "scale"):
        if key + name not in arrays:
            raise FootfallError(f"lacks array {key}{name}")
    coef = require_float_array(arrays[key + "coef"], f"array {key}coef", (n,), bound=MAX_WEIGHT)
    scale = require_float_array(arrays[key + "scale"], f"array {key}scale", (n,),
                                bound=MAX_WEIGHT)
    if not (scale > 0).all():
        raise FootfallError(f"array {key}scale must be > 0 (a standard deviation)")
    return coef, scale


def _read_group(group: str, meta: Any, arrays: dict, config: FeatureConfig,
                robot: RobotDescription, names: tuple[str, ...]) -> RankingFunction:
    """One leg group's ranking function from a version 2 file."""
    where = f"groups.{group}"
    require_keys(meta, where, ("families", "info"))
    entries = require_type(meta["families"], list, f"{where}.families")
    found = [require_keys(e, f"{where}.families[{k}]", ("name", "columns", "params")).get("name")
             for k, e in enumerate(entries)]
    if not found or found != [n for n in names if n in found]:
        raise FootfallError(f"{where}.families must be of the feature set's families "
                            f"{list(names)}, each at most once and in that order, "
                            f"got {shown(found)}")
    families, coef, scale = [], [], []
    for k, entry in enumerate(entries):
        field_path, prefix = f"{where}.families[{k}]", f"{group}.{entry['name']}."
        columns = require_str_list(entry["columns"], f"{field_path}.columns")
        params = {key[len(prefix):]: v for key, v in arrays.items()
                  if key.startswith(prefix) and key[len(prefix):] not in ("coef", "scale")}
        try:
            family = family_class(entry["name"]).from_params(config, robot, params,
                                                             entry["params"])
        except FootfallError as exc:
            raise FootfallError(f"{field_path} ({entry['name']}): {exc}") from None
        if list(family.columns()) != columns:
            raise FootfallError(f"{field_path}.columns do not match the {entry['name']} "
                                f"family's {len(family.columns())} columns")
        c, s = _weights(arrays, prefix, len(columns))
        families.append(family)
        coef.append(c)
        scale.append(s)
    return RankingFunction(tuple(families), tuple(coef), tuple(scale),
                           _group_info(meta["info"], f"{where}.info", len(config.scales)))


def _refuse_extra_arrays(arrays: dict[str, np.ndarray], functions: dict, version: int) -> None:
    """Refuse arrays the model's families did not write: a file holds exactly its own."""
    expected = set()
    for g, f in functions.items():
        if version == 1:
            expected |= {f"{g}_coef", f"{g}_scale"}
            if f.library is not None:
                expected |= set(f.library.arrays(prefix=f"{g}_lib_"))
            continue
        for family in f.families:
            prefix = f"{g}.{family.name}."
            expected |= {prefix + "coef", prefix + "scale"}
            expected |= {prefix + k for k in family.params()[0]}
    extra = sorted(set(arrays) - expected)
    if extra:
        raise FootfallError(f"unexpected array(s) {', '.join(extra[:4])}"
                            f"{'...' if len(extra) > 4 else ''}")


def _info_counts(value: Any, what: str, n_scales: int) -> None:
    require_type(value, list, what)
    if len(value) != n_scales:
        raise FootfallError(f"{what} must hold one count per scale ({n_scales})")
    for k, v in enumerate(value):
        require_int(v, f"{what}[{k}]", 0)


def _group_info(info: Any, what: str, n_scales: int) -> dict:
    """A ranking function's record, the entries footfall reads checked: numbers are finite."""
    require_type(info, dict, what)
    for key in ("lambda", "C", "cv_error"):
        if key in info:
            require_number(info[key], f"{what}.{key}")
    for key in ("n_nonzero", "n_demonstrations"):
        if key in info:
            require_int(info[key], f"{what}.{key}", 0)
    for key in ("library_counts", "kept_counts"):
        if key in info:
            _info_counts(info[key], f"{what}.{key}", n_scales)
    rms = info.get("bandwidth_rms_m")
    if rms is not None:
        require_type(rms, list, f"{what}.bandwidth_rms_m")
        for k, r in enumerate(rms):
            require_number(r, f"{what}.bandwidth_rms_m[{k}]", 0.0, low_open=True)
    return info


_V1_GROUP_KEYS = ("names", "bandwidths", "info", "library")


def _read_group_v1(group: str, meta: Any, arrays: dict, config: FeatureConfig,
                   robot: RobotDescription, families_of_set: tuple[str, ...]) -> RankingFunction:
    """One leg group's ranking function from a version 1 file: one flat list of names.

    Version 1 named terrain features ``scale.quantity``, templates
    ``scale.template_k`` and pose features ``pose.name``; its feature set was
    one of the paper's three.
    """
    where = f"groups.{group}"
    require_keys(meta, where, _V1_GROUP_KEYS)
    names = require_str_list(meta["names"], f"{where}.names")
    if len(set(names)) != len(names):
        raise FootfallError(f"{where}.names must be distinct")
    coef, scale = _weights(arrays, f"{group}_", len(names))
    families, coefs, scales, used = [], [], [], []
    for name in families_of_set:
        family, full = _family_v1(name, meta, where, arrays, config, robot, group)
        missing = [n for n in full if n not in names]
        if missing:
            raise FootfallError(f"{where}.names lack the {name} column {missing[0]!r}")
        pick = [names.index(n) for n in full]
        used += pick
        families.append(family)
        coefs.append(coef[pick])
        scales.append(scale[pick])
    if len(used) != len(names):
        extra = [n for k, n in enumerate(names) if k not in set(used)]
        raise FootfallError(f"{where}.names hold {extra[0]!r}, no column of the feature set")
    return RankingFunction(tuple(families), tuple(coefs), tuple(scales),
                           _group_info(meta["info"], f"{where}.info", len(config.scales)))


def _family_v1(name: str, meta: dict, where: str, arrays: dict, config: FeatureConfig,
               robot: RobotDescription, group: str) -> tuple[FeatureFamily, list[str]]:
    """A family of a version 1 group and its columns' names as version 1 wrote them."""
    if name != "templates":
        family = family_class(name).create(config, robot)
        return family, [f"pose.{c}" if name == "pose" else c for c in family.columns()]
    if meta["library"] is None:
        raise FootfallError(f"{where}.library must be a template library, got None")
    library = TemplateLibrary.from_arrays(arrays, meta["library"], prefix=f"{group}_lib_",
                                          what=f"{where}.library")
    if library.config != config:
        raise FootfallError(f"{where}.library.config: the template library was built with "
                            f"other feature settings than the model")
    bandwidths = check_bandwidths(meta["bandwidths"], len(config.scales), f"{where}.bandwidths")
    family = TemplateFeatures(config, library, bandwidths)
    return family, list(library.names())
