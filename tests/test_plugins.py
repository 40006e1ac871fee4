"""Plugins: a package's parts, named by an entry point, reach every registry and the CLI."""

import importlib.metadata
import sys

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core import plugins
from footfall.core.errors import FootfallError
from footfall.core.registry import Registry
from footfall.experiments.executors import EXECUTORS, LocalPool, make_executor
from footfall.experiments.variants import VARIANTS
from footfall.features.family import FAMILIES, FEATURE_SETS, feature_set_families
from footfall.learning.learner import LEARNERS, get_learner
from footfall.terrain import KINDS, make_module, unregister_kind

PLUGIN = '''
import numpy as np
from sklearn.linear_model import RidgeClassifier

from footfall.experiments.variants import register_variant
from footfall.experiments.executors import LocalPool, register_executor
from footfall.features.family import register_feature_set
from footfall.learning.learner import register_learner
from footfall.learning.ranker import LinearLearner
from footfall.terrain import register_kind


def table(difficulty, rng):
    """A 2 cm table in the middle of the module, its edges at 0."""
    z = np.zeros((610, 610))
    z[200:410, 200:410] = 0.02
    return z


register_kind("table", table)
register_learner(LinearLearner("plugin-ridge", "ridge (a plugin's)",
                               lambda C, tol, max_iter: RidgeClassifier(alpha=1 / C,
                                                                        fit_intercept=False),
                               lambda pairs, labels, n: np.logspace(-2, 1, n),
                               logistic=False))
register_feature_set("plugin-set", ("terrain", "pose"))
register_executor("plugin-pool", lambda processes=None, address=None: LocalPool(1))
register_variant("plugin-variant", "the defaults, from a plugin", lambda walk: walk)
'''


@pytest.fixture
def plugin(tmp_path, monkeypatch):
    """A plugin module on sys.path, named by a fake entry point; forgotten afterwards."""
    (tmp_path / "footfall_test_parts.py").write_text(PLUGIN)
    monkeypatch.syspath_prepend(str(tmp_path))
    entry = importlib.metadata.EntryPoint("table-parts", "footfall_test_parts", plugins.GROUP)
    monkeypatch.setattr(plugins, "_entry_points", lambda: [entry])
    monkeypatch.setattr(plugins, "_done", False)
    monkeypatch.setattr(plugins, "_loaded", [])
    yield
    unregister_kind("table")
    LEARNERS.unregister("plugin-ridge")
    FEATURE_SETS.unregister("plugin-set")
    EXECUTORS.unregister("plugin-pool")
    VARIANTS.unregister("plugin-variant")
    sys.modules.pop("footfall_test_parts", None)


def test_a_plugin_registers_its_parts_before_any_registry_answers(plugin):
    assert "footfall_test_parts" not in sys.modules  # nothing imported it yet
    module = make_module("table", 0.5, 0)  # the terrain registry loads the plugins first
    assert np.max(module.heights) == pytest.approx(0.02) and "table" in KINDS
    assert get_learner("plugin-ridge").name == "plugin-ridge"
    assert plugins.load_plugins() == ["table-parts"]  # imported once


@pytest.mark.parametrize("registry", [FAMILIES, FEATURE_SETS, KINDS, EXECUTORS, VARIANTS],
                         ids=lambda r: r.kind)
def test_every_registry_is_one_type_and_loads_the_plugins_before_it_answers(plugin, registry):
    assert isinstance(registry, Registry)
    assert "footfall_test_parts" not in sys.modules
    assert len(registry) > 0  # asking loads the plugins (families: none of the plugin's)
    assert plugins.load_plugins() == ["table-parts"]


def test_a_plugins_feature_set_executor_and_variant_are_found(plugin):
    assert feature_set_families("plugin-set") == ("terrain", "pose")  # loads the plugins
    assert isinstance(make_executor("plugin-pool"), LocalPool)
    assert VARIANTS.get("plugin-variant").description == "the defaults, from a plugin"
    with pytest.raises(FootfallError, match="unknown executor 'none'; use one of local, ray"):
        make_executor("none")


def test_the_command_line_offers_a_plugins_parts(plugin, tmp_path, capsys):
    code, out, _ = run(capsys, "terrain", "make", "table", "--seed", "1", "-o",
                       tmp_path / "t.npz", "--json")
    assert code == 0 and '"table"' in out


def test_a_broken_plugin_is_one_line_naming_it(tmp_path, monkeypatch, capsys):
    (tmp_path / "footfall_broken_parts.py").write_text("raise RuntimeError('no GPU here')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    entry = importlib.metadata.EntryPoint("broken", "footfall_broken_parts", plugins.GROUP)
    monkeypatch.setattr(plugins, "_entry_points", lambda: [entry])
    monkeypatch.setattr(plugins, "_done", False)
    monkeypatch.setattr(plugins, "_loaded", [])
    with pytest.raises(FootfallError, match="plugin 'broken' .* failed to load"):
        plugins.load_plugins()
    monkeypatch.setattr(plugins, "_done", False)
    code, _, err = run(capsys, "terrain", "make", "flat", "--seed", "1", "-o", tmp_path / "f.npz")
    assert_user_error(code, err, "plugin 'broken'")
