"""``footfall curve-walk``: a learning curve's points walked on boards never trained on, paired."""

import json
from dataclasses import replace

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.curve_walk import (
    FOLDER,
    STORE_NAME,
    CurveWalkConfig,
    run_curve_walk,
    walk_markdown,
)
from footfall.experiments.learning_curve import CurveConfig, run_learning_curve
from footfall.experiments.reproduce import reproduction_walk

CURVE = CurveConfig(sizes=(10, 16), draws=2, feature_sets=("terrain",), learners=("l1",),
                    train_kinds=("rocky",), train_difficulties=(0.5,), test_difficulties=(0.5,),
                    test_decisions=6, library_size=30)
TINY = CurveWalkConfig(sizes=(10, 16), feature_set="terrain", learner="l1",
                       board=(("rocky", 0.4),), boards=2, runs=1,
                       walk=replace(reproduction_walk(), max_steps=6))


@pytest.fixture(scope="module")
def curve(tmp_path_factory):
    out = tmp_path_factory.mktemp("curve")
    run_learning_curve(out, CURVE, log=lambda s: None)
    return out


@pytest.fixture(scope="module")
def walked(curve):
    return run_curve_walk(curve, TINY, processes=1, log=lambda s: None)


def _keys(curve):
    with DemoStore(curve / FOLDER / STORE_NAME) as store:
        return sorted(r["key"] for r in store.runs())


def test_every_draws_model_and_the_reference_walk_the_same_units(curve, walked):
    keys = _keys(curve)
    units = TINY.boards * TINY.runs
    methods = {k.split("/")[0] for k in keys}
    assert methods == {"hand-tuned"} | {f"terrain-l1-{n}-draw{d}" for n in (10, 16)
                                       for d in (0, 1)}
    assert len(keys) == len(methods) * units
    per_method = {m: sorted(k.split("/", 1)[1] for k in keys if k.startswith(m + "/"))
                  for m in methods}
    assert len({tuple(v) for v in per_method.values()}) == 1  # the same boards and run seeds
    for n, f in walked["sizes"].items():
        assert f["runs"] == 2 * units and 0 <= f["successes"] <= f["runs"]
        assert set(f["draws"]) == {"0", "1"}
        assert sum(g["successes"] for g in f["draws"].values()) == f["successes"]
        assert f["steps"] > 0 and 0 <= f["above_margin"] <= 1
        assert 0 <= f["offline_above_margin"] <= 1  # the curve's own measure of the point
        a = f["against_hand_tuned"]
        assert a["pairs"] == 2 * units and a["a_only"] + a["b_only"] <= a["pairs"]
    assert walked["references"]["hand-tuned"]["runs"] == units
    assert walked["largest_against_smallest"]["pairs"] == 2 * units
    md = (curve / FOLDER / "walk-terrain-l1.md").read_text()  # a report per feature set, learner
    assert md == walk_markdown(walked) and "16 demonstrations (2 draws)" in md


def test_the_walking_boards_are_none_of_the_curves(curve, walked):
    from footfall.core.heightmap import HeightMap

    walking = {HeightMap.load(p).content_hash() for p in (curve / FOLDER / "terrain").glob("*")}
    seen = set()
    for name in ("test.sqlite", "draw0.sqlite", "draw1.sqlite"):
        with DemoStore(curve / name) as store:
            seen |= {d.terrain_hash for d in store.demonstrations()}
    assert len(walking) == TINY.boards and seen and not walking & seen


def test_a_rerun_walks_nothing_and_other_walks_are_refused(curve, walked):
    before = _keys(curve)
    logged: list[str] = []
    again = run_curve_walk(curve, TINY, processes=1, log=logged.append)
    assert _keys(curve) == before
    assert json.dumps(again, sort_keys=True) == json.dumps(walked, sort_keys=True)
    assert any("already stored" in line for line in logged)
    with pytest.raises(FootfallError, match="other settings"):
        run_curve_walk(curve, replace(TINY, runs=2), processes=1, log=lambda s: None)
    with pytest.raises(FootfallError, match="no point terrain/l1 at 48"):
        run_curve_walk(curve, replace(TINY, sizes=(10, 48)), processes=1, log=lambda s: None)


def test_the_command_refuses_a_folder_without_a_curve_or_point_in_one_line(curve, tmp_path,
                                                                          capsys):
    def refused(match, *args):
        assert_user_error(*run(capsys, "curve-walk", *args)[::2], match)

    refused("not a learning curve", tmp_path)
    refused("--sizes", curve, "--sizes", "10,x")
    refused("no point terrain/l1 at 400", curve, "--sizes", "400", "--features", "terrain",
            "--learner", "l1")
