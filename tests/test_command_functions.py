"""The library functions behind the commands: each returns its result object, bad input raises
FootfallError, and the result's JSON is what the command prints."""

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from cli_helpers import run
from footfall.core.errors import FootfallError
from footfall.core.files import writable_path
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES
from footfall.data.inventory import StoreInventory, store_inventory, terrain_label
from footfall.data.store import DemoStore
from footfall.experiments.batch import (
    BatchOutcome,
    WalkOutcome,
    walk_batch,
    walk_config,
    walk_once,
)
from footfall.experiments.rank_eval import ModelAgreement, rank_eval
from footfall.expert import collect
from footfall.expert.collect import CollectedDemonstrations, collect_into_store
from footfall.learning.train import LearnedModel, learn_from_store, store_demonstrations
from footfall.plots.relief import save_relief_of_file
from footfall.terrain.saving import MapSummary, save_board, save_imported, save_module
from test_walker import FakeExpertConfig, FakeSyntheticExpert

SMALL_LEARNING = {"library_size": 60, "training_candidates": 30, "cv": 3, "Cs": 5,
                  "bandwidth_rms": (0.004, 0.004, 0.008)}  # fast, as test_model_training's


@pytest.fixture(scope="module")
def boards(tmp_path_factory):
    folder = tmp_path_factory.mktemp("boards")
    save_board(["rocky:0.6"], 11, folder / "rocky.npz")
    save_board(["steps:0.5"], 12, folder / "steps.npz")
    return folder / "rocky.npz", folder / "steps.npz"


def _fake_expert(monkeypatch):
    """test_walker's fast stand-in for the synthetic expert, where collect_into_store finds it."""
    monkeypatch.setattr(collect, "ExpertConfig", FakeExpertConfig)
    monkeypatch.setattr(collect, "SyntheticExpert", FakeSyntheticExpert)


@pytest.fixture(scope="module")
def store(boards, tmp_path_factory):
    path = tmp_path_factory.mktemp("store") / "demos.sqlite"
    with pytest.MonkeyPatch.context() as monkeypatch:
        _fake_expert(monkeypatch)
        collect_into_store(boards, path, 16, 3)
    return path


# ------------------------------------------------------------------- terrain
def test_saving_a_module_returns_the_summary_of_the_file_written(tmp_path):
    summary = save_module("logs", 0.4, 1, tmp_path / "m.npz")
    assert isinstance(summary, MapSummary)
    hmap = HeightMap.load(tmp_path / "m.npz")
    assert summary.hash == hmap.content_hash() and summary.shape == (610, 610)
    assert summary.length == pytest.approx(hmap.length)
    assert summary.height_min >= 0.0 and summary.no_data_fraction == 0.0
    data = summary.as_dict()
    assert list(data) == ["file", "shape", "resolution", "origin", "bounds", "height_min",
                          "height_max", "no_data_fraction", "hash", "metadata"]
    assert data["metadata"]["modules"][0]["kind"] == "logs"
    json.dumps(data, allow_nan=False)


def test_saving_a_board_and_an_import(tmp_path):
    board = save_board(["rocky:0.3", "steps"], 2, tmp_path / "b.npz")
    assert [m["kind"] for m in board.metadata["modules"]] == ["flat", "rocky", "steps", "flat"]
    assert save_board(["rocky:0.3"], 2, tmp_path / "c.npz", flat_ends=False).shape == (610, 610)
    np.save(tmp_path / "a.npy", np.full((40, 30), 0.01))
    imported = save_imported(tmp_path / "a.npy", tmp_path / "a.npz", resolution=0.002)
    assert imported.shape == (40, 30) and imported.resolution == 0.002
    assert imported.height_max == pytest.approx(0.01)


@pytest.mark.parametrize("make, match", [
    (lambda d: save_module("lava", 0.5, 1, d / "x.npz"), "unknown terrain module kind"),
    (lambda d: save_module("rocky", 2.0, 1, d / "x.npz"), "difficulty"),
    (lambda d: save_module("rocky", 0.5, 1, d / "missing" / "x.npz"),
     "output directory does not exist"),
    (lambda d: save_module("rocky", 0.5, 1, d), "output path is a directory"),
    (lambda d: save_board(["rocky:x"], 1, d / "x.npz"), "rocky:x"),
    (lambda d: save_imported(d / "none.npy", d / "x.npz", resolution=0.01), "no such file"),
    (lambda d: save_relief_of_file(d / "none.npz", d / "x.png"), "no such file"),
])
def test_terrain_functions_refuse_bad_input(tmp_path, make, match):
    with pytest.raises(FootfallError, match=match):
        make(tmp_path)
    assert not list(tmp_path.glob("x.*"))


def test_relief_of_a_file(boards, tmp_path):
    out = save_relief_of_file(boards[0], tmp_path / "r.png")
    assert out == tmp_path / "r.png" and out.read_bytes()[:4] == b"\x89PNG"


def test_writable_path_checks_before_any_work(tmp_path):
    assert writable_path(tmp_path / "new.npz") == tmp_path / "new.npz"
    with pytest.raises(FootfallError, match="output path is a directory"):
        writable_path(tmp_path)


# -------------------------------------------------- demonstrations and stores
def test_collecting_into_a_store_counts_what_it_added(boards, store, tmp_path, monkeypatch):
    _fake_expert(monkeypatch)
    path = tmp_path / "d.sqlite"
    added = collect_into_store(boards[:1], path, 5, 0, noise=0.002, steps="all")
    assert isinstance(added, CollectedDemonstrations)
    assert (added.requested, added.added, added.first_id, added.last_id) == (5, 5, 1, 5)
    assert (added.total, added.terrains, added.steps) == (5, 1, "all")
    assert added.added_by_terrain == {HeightMap.load(boards[0]).content_hash(): 5}
    assert sum(added.added_by_leg.values()) == 5 and set(added.added_by_leg) <= set(LEG_NAMES)
    assert added.expert["config"]["noise"] == 0.002
    assert list(added.as_dict())[:3] == ["store", "requested", "added"]
    with DemoStore(store) as s:
        assert s.count() == 16


@pytest.mark.parametrize("kwargs, match", [
    ({"steps": "some"}, "steps must be one of rough, all"),
    ({"n": 0}, "number of demonstrations must be >= 1"),
    ({"second_best": 1.5}, "second_best"),
])
def test_collecting_refuses_bad_arguments(boards, tmp_path, kwargs, match):
    args = {"n": 2, **kwargs}
    with pytest.raises(FootfallError, match=match):
        collect_into_store(boards[:1], tmp_path / "d.sqlite", args.pop("n"), 0, **args)
    assert not (tmp_path / "d.sqlite").exists()


def test_a_store_inventory_counts_and_labels(store, boards):
    inventory = store_inventory(store)
    assert isinstance(inventory, StoreInventory)
    assert inventory.summary["demonstrations"] == 16 and inventory.summary["terrains"] == 2
    labels = sorted(t["label"] for t in inventory.terrains.values())
    assert labels == ["flat, rocky:0.6, flat", "flat, steps:0.5, flat"]
    data = inventory.as_dict()
    assert list(data)[0] == "store" and list(data)[-1] == "terrain_info"
    assert all("metadata" not in t for t in data["terrain_info"].values())
    assert terrain_label({"shape": [40, 30], "resolution": 0.002, "metadata": {}}) == \
        "40 x 30 cells at 2 mm"
    with pytest.raises(FootfallError, match="no such file"):
        store_inventory(store.parent / "none.sqlite")


def test_store_demonstrations_by_source(store):
    demos, maps = store_demonstrations(store, source="walker")
    assert len(demos) == 16 and set(maps) == {d.terrain_hash for d in demos}
    with pytest.raises(FootfallError, match="no demonstrations from source 'teacher'"):
        store_demonstrations(store, source="teacher")


# ------------------------------------------------------- learning, rank-eval
def test_learning_from_a_store_and_ranking_its_demonstrations(store, tmp_path):
    learned = learn_from_store(store, tmp_path / "m.npz", "terrain+pose", **SMALL_LEARNING)
    assert isinstance(learned, LearnedModel) and learned.demonstrations == 16
    assert learned.model == str(tmp_path / "m.npz") and (tmp_path / "m.npz").exists()
    assert set(learned.groups) == {"front", "hind"}
    assert learned.groups["front"]["templates_kept"] == [0, 0, 0]
    agreement = rank_eval(tmp_path / "m.npz", store)
    assert isinstance(agreement, ModelAgreement) and agreement.feature_set == "terrain+pose"
    assert agreement.scores.n == 16 and agreement.scores.reward_loss >= 0
    assert list(agreement.as_dict())[:4] == ["model", "feature_set", "learner", "n"]
    assert math.isnan(rank_eval(tmp_path / "m.npz", store, with_expert=False).scores.reward_loss)


@pytest.mark.parametrize("call, match", [
    (lambda s, d: learn_from_store(s, d / "m.npz", "colour"), "unknown feature set"),
    (lambda s, d: learn_from_store(s, d / "m.npz", "terrain", "lasso"), "unknown learner"),
    (lambda s, d: learn_from_store(s, d / "missing" / "m.npz", "terrain"),
     "output directory does not exist"),
    (lambda s, d: rank_eval(d / "none.npz", s), "no such file"),
])
def test_learning_and_ranking_refuse_bad_input(store, tmp_path, call, match):
    with pytest.raises(FootfallError, match=match):
        call(store, tmp_path)
    assert not (tmp_path / "m.npz").exists()


# ------------------------------------------------------------------ walking
@pytest.fixture(scope="module")
def flat_board(tmp_path_factory):
    path = tmp_path_factory.mktemp("walk") / "flat.npz"
    save_board(["flat", "flat"], 0, path)  # 1.22 m: a short run
    return path


def test_one_walk_logged_and_a_batch_of_one(flat_board, tmp_path):
    outcome = walk_once(flat_board, 1, search_radius=0.03, log_path=tmp_path / "log.sqlite")
    assert isinstance(outcome, WalkOutcome) and outcome.record.result["success"]
    assert outcome.run_id == 1 and outcome.as_dict()["run_id"] == 1
    assert list(outcome.as_dict())[:5] == ["terrain", "model", "expert", "teacher", "seed"]
    batch = walk_batch(flat_board, 1, 1, search_radius=0.03, log_path=tmp_path / "log.sqlite")
    assert isinstance(batch, BatchOutcome) and batch.summary.runs == 1
    for key in ("success", "distance", "steps", "slip_mean_mm"):  # the same seed, the same run
        assert batch.records[0].result[key] == outcome.record.result[key]
    assert batch.as_dict()["runs_detail"][0]["seed"] == 1
    with DemoStore(tmp_path / "log.sqlite") as s:
        assert s.summary()["runs"] == 2


@pytest.mark.parametrize("kwargs, match", [
    ({"expert": True, "model_path": "m.npz"}, "--expert chooses the footholds itself"),
    ({"search_radius": 0.0}, "search_radius must be > 0"),
    ({"path_bias": -1.0}, "bias_weight must be >= 0"),
    ({"snapshots": "{tmp}/missing/s.png"}, "output directory does not exist"),
    ({"log_path": "{tmp}/missing/log.sqlite"}, "output directory does not exist"),
])
def test_walks_refuse_bad_settings_before_running(flat_board, tmp_path, kwargs, match):
    kwargs = {k: v.format(tmp=tmp_path) if isinstance(v, str) else v for k, v in kwargs.items()}
    with pytest.raises(FootfallError, match=match):
        walk_once(flat_board, 0, **kwargs)
    if "snapshots" not in kwargs:
        with pytest.raises(FootfallError, match=match):
            walk_batch(flat_board, 2, 0, **kwargs)
    with pytest.raises(FootfallError, match="no such terrain file"):
        walk_once(tmp_path / "none.npz", 0)


def test_walk_config_limits_the_candidate_set_and_sets_the_path_bias():
    assert walk_config(search_radius=0.03).footstep.search_radius == 0.03
    assert walk_config() == walk_config(None, False, None)
    assert walk_config().footstep.bias_weight == 60.0  # the walk's own
    assert walk_config(path_bias=0.0).footstep.bias_weight == 0.0
    assert walk_config(path_bias=0.0).footstep == replace(walk_config().footstep, bias_weight=0)


def test_walk_config_walks_a_controller_variant_on_top_of_its_own_settings():
    from footfall.experiments.variants import VARIANTS

    assert walk_config(variant="defaults") == walk_config()
    base = walk_config(search_radius=0.03)
    unheld = walk_config(search_radius=0.03, variant="no-load-hold")
    assert unheld == VARIANTS.get("no-load-hold").change(base)
    assert unheld.lowlevel.load_hold == 0 and base.lowlevel.load_hold == 0.2
    assert unheld.footstep.search_radius == 0.03  # the variant changes only its own part
    with pytest.raises(FootfallError, match="nobody"):
        walk_config(variant="nobody")


# -------------------------------------------------- the commands print them
def test_a_command_prints_its_result_objects_json(boards, tmp_path, capsys):
    code, out, _ = run(capsys, "terrain", "make", "rocky", "--seed", 4, "-o", tmp_path / "c.npz",
                       "--json")
    assert code == 0
    assert json.loads(out) == save_module("rocky", 0.5, 4, tmp_path / "c.npz").as_dict()
