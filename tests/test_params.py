"""Declared configuration: validation, plain data and the docs tables come from one declaration."""

import dataclasses
import importlib
import json
import math
import pkgutil
from dataclasses import dataclass

import pytest

import footfall
from footfall.control.body_path import BodyPathConfig
from footfall.control.cog import CogConfig
from footfall.control.footstep import FootstepConfig
from footfall.control.lowlevel import LowLevelConfig
from footfall.control.pose_finder import PoseConfig
from footfall.control.reflexes import ReflexConfig
from footfall.control.swing import SwingConfig
from footfall.core.errors import FootfallError
from footfall.core.files import plain_json
from footfall.core.limits import Limits
from footfall.core.params import (
    Interval,
    Params,
    above,
    at_least,
    from_dict,
    main,
    markdown_table,
    param,
    refresh_tables,
    specs,
    to_dict,
    within,
)
from footfall.experiments.ablation import AblationConfig
from footfall.experiments.curve_walk import CurveWalkConfig
from footfall.experiments.learning_curve import CurveConfig
from footfall.experiments.offline import OfflineConfig
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.student_curve import StudentCurveConfig
from footfall.experiments.terrain_suite import SuiteConfig
from footfall.expert.synthetic import ExpertConfig
from footfall.features.config import FeatureConfig
from footfall.sim.episode import WalkConfig
from footfall.sim.rollout import RolloutConfig
from footfall.sim.simulation import PerturbationConfig

CONFIGS = (Limits, FeatureConfig, PerturbationConfig, WalkConfig, LowLevelConfig, BodyPathConfig,
           FootstepConfig, CogConfig, SwingConfig, PoseConfig, ExpertConfig, ReproduceConfig,
           OfflineConfig, ReflexConfig, AblationConfig, CurveConfig, CurveWalkConfig,
           SuiteConfig, StudentCurveConfig, RolloutConfig)
"""Every declared config of footfall (test_every_declared_config_is_listed keeps it whole)."""


def _odd_pair(value) -> bool:
    return isinstance(value, tuple) and len(value) == 2 and all(
        isinstance(n, int) and n % 2 == 1 for n in value)


@dataclass(frozen=True)
class ToyConfig(Params):
    """A config with one field of every kind the helper knows."""

    length: float = param(0.1, unit="m", range=above(0), doc="a length")
    share: float = param(0.5, unit="-", range=within(0, 1, low_open=True), doc="a share")
    limit: float = param(math.inf, unit="s", range=within(0, math.inf, low_open=True),
                         doc="a time limit; inf: none")
    offset: float = param(-0.2, unit="m", doc="any finite number")
    count: int | None = param(3, unit="-", range=at_least(1), doc="a count; None: all")
    mode: str = param("a", choices=("a", "b"), doc="a mode")
    pair: tuple[int, int] = param((1, 3), unit="-", check=_odd_pair, must="two odd integers",
                                  doc="a pair")


@dataclass(frozen=True)
class OuterConfig(Params):
    """A config holding another."""

    toy: ToyConfig = param(factory=lambda: ToyConfig(length=0.2), doc="the nested config")
    flag: bool = param(False, doc="a switch")


# ------------------------------------------------------------------ validation
@pytest.mark.parametrize("field, value, message", [
    ("length", 0.0, r"toy config: length must be > 0, got 0\.0"),
    ("length", math.inf, r"length must be > 0, got inf"),
    ("length", math.nan, r"length must be > 0, got nan"),
    ("length", True, r"length must be > 0, got True"),
    ("length", "0.1", r"length must be > 0, got '0\.1'"),
    ("share", 0.0, r"share must be in \(0, 1\], got 0\.0"),
    ("limit", 0, r"limit must be in \(0, inf\], got 0"),
    ("offset", math.nan, r"offset must be a finite number, got nan"),
    ("count", 1.0, r"count must be an integer >= 1 or None, got 1\.0"),
    ("count", 0, r"count must be an integer >= 1 or None, got 0"),
    ("mode", "c", r"mode must be one of 'a', 'b', got 'c'"),
    ("pair", (1, 2), r"pair must be two odd integers, got \(1, 2\)"),
])
def test_a_declared_range_refuses_a_bad_value_with_one_clear_line(field, value, message):
    with pytest.raises(FootfallError, match=message) as info:
        ToyConfig(**{field: value})
    assert "\n" not in str(info.value)


def test_values_inside_their_declarations_are_accepted():
    ToyConfig(length=1, share=1.0, limit=math.inf, offset=-5, count=None, mode="b", pair=(5, 7))
    with pytest.raises(FootfallError, match="outer config: toy must be a ToyConfig"):
        OuterConfig(toy={"length": 0.1})
    with pytest.raises(FootfallError, match="flag must be True or False, got 1"):
        OuterConfig(flag=1)


@pytest.mark.parametrize("interval, text, inside, outside", [
    (above(0), "> 0", [1e-9, 5], [0, -1, math.inf, math.nan]),
    (at_least(1), ">= 1", [1, 2.5], [0.999, math.inf]),
    (within(0, 1), "in [0, 1]", [0, 1], [-1e-9, 1.5]),
    (within(0, 1, high_open=True), "in [0, 1)", [0, 0.999], [1]),
    (within(0, math.inf), "in [0, inf]", [0, math.inf], [-1, math.nan]),
    (Interval(high=2.0, high_open=False), "<= 2", [-1e9, 2], [2.1, -math.inf]),
])
def test_intervals_say_what_they_hold(interval, text, inside, outside):
    assert str(interval) == text
    assert all(v in interval for v in inside) and not any(v in interval for v in outside)


def test_a_field_not_declared_with_param_is_refused():
    @dataclass(frozen=True)
    class Loose(Params):
        size: float = 1.0

    with pytest.raises(TypeError, match="Loose.size is not declared with param"):
        Loose()


# ------------------------------------------------------------------ plain data
def test_to_dict_and_from_dict_round_trip_through_json():
    config = OuterConfig(toy=ToyConfig(limit=30.0, count=None, pair=(3, 5)), flag=True)
    data = to_dict(config)
    assert data == {"toy": {"length": 0.1, "share": 0.5, "limit": 30.0, "offset": -0.2,
                            "count": None, "mode": "a", "pair": (3, 5)}, "flag": True}
    assert from_dict(OuterConfig, data) == config
    assert OuterConfig.from_dict(json.loads(json.dumps(config.to_dict()))) == config


def test_from_dict_turns_json_lists_back_into_tuples_nested_too():
    @dataclass(frozen=True)
    class Boards(Params):
        boards: tuple[tuple[tuple[str, float], ...], ...] = param(
            ((("rocky", 0.4),), (("steps", 0.5), ("logs", 0.5))), doc="modules of each board")

    config = Boards()
    assert Boards.from_dict(json.loads(json.dumps(config.to_dict()))) == config


def test_from_dict_makes_floats_of_numbers_and_refuses_other_types():
    data = to_dict(ToyConfig())
    back = from_dict(ToyConfig, {**data, "length": 1})
    assert back.length == 1.0 and isinstance(back.length, float)
    with pytest.raises(FootfallError, match="toy config: length must be > 0, got '1'"):
        from_dict(ToyConfig, {**data, "length": "1"})


@pytest.mark.parametrize("data, message", [
    ({"colour": "red"}, "toy config: unknown setting 'colour'"),
    ({"length": None}, "toy config: length must be > 0, got None"),
])
def test_from_dict_refuses_unknown_keys_and_bad_values(data, message):
    with pytest.raises(FootfallError, match=message):
        from_dict(ToyConfig, {**to_dict(ToyConfig()), **data})


def test_from_dict_refuses_missing_keys_and_non_mappings():
    data = to_dict(OuterConfig())
    del data["toy"]["mode"]
    with pytest.raises(FootfallError, match="toy config: missing setting 'mode'"):
        from_dict(OuterConfig, data)
    with pytest.raises(FootfallError, match="outer config: expected a mapping of settings, got"):
        from_dict(OuterConfig, [1, 2])


# -------------------------------------------------------------------- docs
def test_markdown_table_has_a_row_per_field_with_default_unit_range_and_meaning():
    table = markdown_table(OuterConfig)
    rows = table.splitlines()
    assert rows[0] == "| field | default | unit | accepted | meaning |"
    assert rows[2] == ("| `toy` | `ToyConfig(length=0.2)` |  | a ToyConfig | the nested config |")
    assert rows[3] == "| `flag` | `False` |  | True or False | a switch |"
    toy = markdown_table(ToyConfig)
    assert "| `limit` | `inf` | s | in (0, inf] | a time limit; inf: none |" in toy
    assert "| `count` | `3` | - | an integer >= 1 or None | a count; None: all |" in toy


def test_refresh_tables_rewrites_only_what_lies_between_the_markers(tmp_path):
    marker = f"<!-- params {__name__}.OuterConfig -->\n"
    stale = f"# Settings\n\nWhy: because.\n\n{marker}| old |\n<!-- /params -->\n\nMore prose.\n"
    fresh = refresh_tables(stale)
    assert fresh == stale.replace("| old |\n", markdown_table(OuterConfig))
    assert refresh_tables(fresh) == fresh
    path = tmp_path / "settings.md"
    path.write_text(stale)
    assert main([str(path), "--check"]) == 1 and path.read_text() == stale
    assert main([str(path)]) == 0 and path.read_text() == fresh
    assert main([str(path), "--check"]) == 0
    with pytest.raises(FootfallError, match="no config class 'footfall.nowhere.Config'"):
        refresh_tables("<!-- params footfall.nowhere.Config -->\n<!-- /params -->")


# ------------------------------------------------------- every footfall config
def test_every_declared_config_is_listed():
    for info in pkgutil.walk_packages(footfall.__path__, "footfall."):
        if not info.name.endswith("__main__"):
            importlib.import_module(info.name)
    found, todo = set(), list(Params.__subclasses__())
    while todo:
        cls = todo.pop()
        todo += cls.__subclasses__()
        if cls.__module__.startswith("footfall."):
            found.add(cls)
    assert found == set(CONFIGS)


@pytest.mark.parametrize("cls", CONFIGS, ids=lambda c: c.__name__)
def test_every_config_round_trips_through_plain_data(cls):
    config = cls()
    assert cls.from_dict(config.to_dict()) == config
    on_disk = json.loads(json.dumps(plain_json(config.to_dict())))
    assert cls.from_dict(on_disk) == config
    with pytest.raises(FootfallError, match="unknown setting 'no_such_knob'"):
        cls.from_dict({**config.to_dict(), "no_such_knob": 1})


def test_changed_settings_round_trip_too():
    walk = WalkConfig(footstep=FootstepConfig(search_radius=0.03, pose_candidates=None),
                      pose=PoseConfig(grid=(5, 3, 3, 1)), max_steps=7, time_limit=math.inf,
                      swing=SwingConfig(timing="cubic", band=0.0))
    assert WalkConfig.from_dict(json.loads(json.dumps(walk.to_dict()))) == walk
    feature = FeatureConfig(template_resolution=0.002, min_coverage=1.0)
    assert FeatureConfig.from_dict(json.loads(json.dumps(feature.to_dict()))) == feature


@pytest.mark.parametrize("cls", [c for c in CONFIGS if c is not FeatureConfig],
                         ids=lambda c: c.__name__)
def test_to_dict_is_what_run_logs_and_stored_runs_always_recorded(cls):
    # run logs, config.json and stored runs hold dataclasses.asdict of these configs
    assert repr(cls().to_dict()) == repr(dataclasses.asdict(cls()))


def test_feature_config_keeps_its_model_file_form():
    assert FeatureConfig().to_dict() == {
        "template_resolution": 0.003, "min_coverage": 0.5,
        "scales": [["small", 0.024, 0.024], ["medium", 0.054, 0.054], ["large", 0.144, 0.054]]}


@pytest.mark.parametrize("cls", CONFIGS, ids=lambda c: c.__name__)
def test_every_field_of_every_config_has_a_row_and_a_meaning(cls):
    rows = markdown_table(cls).splitlines()[2:]
    assert [r.split(" | ")[0].strip("| `") for r in rows] == [s.name for s in specs(cls)]
    assert all(s.param.doc and "\n" not in s.param.doc for s in specs(cls))
    assert all(r.split(" | ")[4].strip(" |") for r in rows)
