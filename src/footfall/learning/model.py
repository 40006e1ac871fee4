"""The learned foothold model file: ranking functions for front and hind legs.

A model holds, for the front legs and for the hind legs (paper §V: their
properties differ), a ranking function (:mod:`footfall.learning.function`)
over the feature families of one feature set: per family its learned
parameters (the kept templates and their RBF bandwidths), the learner's own
arrays (a linear learner's: the weights on each family's raw columns and the
standardisation it used), and the cross-validation record. Stored as a
versioned ``.npz`` with JSON metadata -- never pickled -- together with the
robot description and the feature settings it was trained with; loading it
for another robot or other feature settings fails with a clear error.
Version 1 (one flat list of feature names per leg group) and version 2
(linear functions only) files are still read.
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
from footfall.features.scorer import FootholdScorer
from footfall.features.template_library import TemplateLibrary
from footfall.features.templates import TemplateFeatures, check_bandwidths
from footfall.learning.function import (
    LinearFunction,
    RankingFunction,
    check_function,
    weight_arrays,
)
from footfall.learning.learner import Learner, get_learner

FORMAT = "footfall.model"
VERSION = 3  # 1: one list of names per group; 2: feature families, each with its parameters
# (linear functions); 3: the function's own arrays named in the file, any registered learner
LEG_GROUPS = ("front", "hind")


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

    def reward_for(self, leg: str) -> FootholdScorer:
        """The scorer a leg's footholds are ranked by."""
        group = "front" if self.robot.leg(leg).front else "hind"
        return self.functions[group].scorer(self.config,
                                            name=f"{self.feature_set}/{self.learner}/{group}")

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

        Arrays are named ``<group>.<family>.<parameter>`` (the families'
        learned parameters) and ``<group>.<name>`` for each of the ranking
        function's own arrays (a linear function's: ``<family>.coef`` and
        ``<family>.scale``), which the metadata lists per group.
        """
        arrays: dict[str, np.ndarray] = {}
        groups: dict[str, Any] = {}
        for g, f in self.functions.items():
            families = []
            for fam in f.families:
                params, meta = fam.params()
                arrays.update({f"{g}.{fam.name}.{k}": v for k, v in params.items()})
                families.append({"name": fam.name, "columns": list(fam.columns()),
                                 "params": meta})
            own = f.arrays()
            clash = sorted(set(f"{g}.{k}" for k in own) & set(arrays))
            if clash:
                raise FootfallError(f"the ranking function's array {clash[0]} has the name of a "
                                    f"family parameter")
            arrays.update({f"{g}.{k}": v for k, v in own.items()})
            groups[g] = {"families": families, "function": sorted(own), "info": f.info}
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
    require_keys(meta, "meta", _META_KEYS, optional=("info", "units"))
    for key, value in arrays.items():
        require_float_array(value, f"array {key}", finite=False)
    feature_set = require_type(meta["feature_set"], str, "feature_set")
    names = feature_set_families(feature_set)
    learner = get_learner(require_type(meta["learner"], str, "learner"))
    config = FeatureConfig.from_dict(meta["config"])
    robot = RobotDescription.from_dict(meta["robot"])
    resolution = require_number(meta["map_resolution"], "map_resolution [m/cell]", 0.0,
                                MAX_MAP_RESOLUTION, low_open=True)
    groups = require_keys(meta["groups"], "groups", LEG_GROUPS)
    if version < 3 and not issubclass(learner.function_type, LinearFunction):
        raise FootfallError(f"learner {learner.name!r} makes no linear function, which a "
                            f"version {version} file holds")
    if version == 1:
        functions = {g: _read_group_v1(g, groups[g], arrays, config, robot, names)
                     for g in LEG_GROUPS}
    else:
        functions = {g: _read_group(g, groups[g], arrays, config, robot, names, learner, version)
                     for g in LEG_GROUPS}
    _refuse_extra_arrays(arrays, functions, version)
    info = require_type(meta.get("info", {}), dict, "info")
    return FootholdModel(feature_set, meta["learner"], functions, config, robot, resolution, info)


def _read_group(group: str, meta: Any, arrays: dict, config: FeatureConfig,
                robot: RobotDescription, names: tuple[str, ...], learner: Learner,
                version: int) -> RankingFunction:
    """One leg group's ranking function from a version 2 or 3 file."""
    where = f"groups.{group}"
    require_keys(meta, where, ("families", "info") + (("function",) if version >= 3 else ()))
    entries = require_type(meta["families"], list, f"{where}.families")
    found = [require_keys(e, f"{where}.families[{k}]", ("name", "columns", "params")).get("name")
             for k, e in enumerate(entries)]
    if not found or found != [n for n in names if n in found]:
        raise FootfallError(f"{where}.families must be of the feature set's families "
                            f"{list(names)}, each at most once and in that order, "
                            f"got {shown(found)}")
    if version >= 3:
        own = require_str_list(meta["function"], f"{where}.function")
    else:  # version 2: a linear function's weights and scales per family
        own = [f"{n}.{k}" for n in found for k in ("coef", "scale")]
    for key in own:
        if f"{group}.{key}" not in arrays:
            raise FootfallError(f"lacks array {group}.{key}")
    mine = {f"{group}.{key}" for key in own}
    families = []
    for k, entry in enumerate(entries):
        field_path, prefix = f"{where}.families[{k}]", f"{group}.{entry['name']}."
        columns = require_str_list(entry["columns"], f"{field_path}.columns")
        params = {key[len(prefix):]: v for key, v in arrays.items()
                  if key.startswith(prefix) and key not in mine}
        try:
            family = family_class(entry["name"]).from_params(config, robot, params,
                                                             entry["params"])
        except FootfallError as exc:
            raise FootfallError(f"{field_path} ({entry['name']}): {exc}") from None
        if list(family.columns()) != columns:
            raise FootfallError(f"{field_path}.columns do not match the {entry['name']} "
                                f"family's {len(family.columns())} columns")
        families.append(family)
    info = _group_info(meta["info"], f"{where}.info", len(config.scales))
    function = learner.function_type.from_arrays(tuple(families), {k: arrays[k] for k in mine},
                                                 info, prefix=f"{group}.")
    return check_function(function)


def _refuse_extra_arrays(arrays: dict[str, np.ndarray], functions: dict, version: int) -> None:
    """Refuse arrays the model's families and functions did not write: a file holds exactly its
    own."""
    expected = set()
    for g, f in functions.items():
        if version == 1:
            expected |= {f"{g}_coef", f"{g}_scale"}
            if f.library is not None:
                expected |= set(f.library.arrays(prefix=f"{g}_lib_"))
            continue
        expected |= {f"{g}.{k}" for k in f.arrays()}
        for family in f.families:
            expected |= {f"{g}.{family.name}.{k}" for k in family.params()[0]}
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
    coef, scale = weight_arrays(arrays, f"{group}_", len(names))
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
    return LinearFunction(tuple(families), tuple(coefs), tuple(scales),
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
