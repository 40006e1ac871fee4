"""Learning a model from demonstrations: the model file, compatibility, isolation from the expert."""

import json
import subprocess
import sys

import numpy as np
import pytest

from footfall.cli import main
from footfall.core.errors import FootfallError
from footfall.core.robot import RobotDescription
from footfall.data.store import DemoStore
from footfall.expert.collect import collect_demonstrations
from footfall.expert.synthetic import SyntheticExpert
from footfall.features.config import FeatureConfig
from footfall.learning.model import FootholdModel
from footfall.learning.train import TrainingDemo, learn_model
from footfall.terrain import make_board


@pytest.fixture(scope="module")
def demos_and_maps():
    boards = [make_board([("rocky", 0.6)], seed=11), make_board([("steps", 0.5)], seed=12)]
    demos = collect_demonstrations(boards, SyntheticExpert(), 16, seed=3)
    maps = {b.content_hash(): b for b in boards}
    return demos, maps


def training(demos, maps):
    return [TrainingDemo(maps[d.terrain_hash], d.state, d.candidates, d.chosen) for d in demos]


def small(feature_set, demos, maps, **kw):
    return learn_model(training(demos, maps), feature_set, kw.pop("learner", "l1"),
                       library_size=60, training_candidates=30, cv=3, Cs=5,
                       bandwidth_rms=(0.004, 0.004, 0.008), **kw)


def test_learned_model_round_trips_through_its_file(demos_and_maps, tmp_path):
    demos, maps = demos_and_maps
    model = small("both", demos, maps)
    path = tmp_path / "model.npz"
    model.save(path)
    back = FootholdModel.load(path)
    assert (back.feature_set, back.learner, back.config, back.robot) == \
        (model.feature_set, model.learner, model.config, model.robot)
    d = demos[0]
    hmap = maps[d.terrain_hash]
    from footfall.features.scoring import score_footholds
    for leg in ("LF", "RH"):
        a = score_footholds(hmap, d.state, d.candidates, model.reward_for(leg))
        b = score_footholds(hmap, d.state, d.candidates, back.reward_for(leg))
        np.testing.assert_array_equal(a, b)
    # Only templates with a non-zero weight are kept, and the kept counts are Table I.
    for f in back.functions.values():
        template_weights = list(f.weights("templates"))
        assert all(w != 0 for w in template_weights)
        assert len(template_weights) == sum(f.library.counts) <= 60
    table = back.templates_kept()
    assert set(table) == {"front", "hind"} and all(sum(v["library"]) >= 57 for v in table.values())
    meta = json.loads(str(np.load(path, allow_pickle=False)["meta"]))
    assert meta["robot"]["upper_leg"] == 0.075 and meta["config"]["template_resolution"] == 0.003


def test_model_refuses_another_robot_or_feature_setting(demos_and_maps, tmp_path):
    demos, maps = demos_and_maps
    model = small("terrain", demos, maps)
    with pytest.raises(FootfallError, match="trained for robot"):
        model.check_compatible(robot=RobotDescription(upper_leg=0.09))
    with pytest.raises(FootfallError, match="other feature settings"):
        model.check_compatible(config=FeatureConfig(template_resolution=0.002))
    with pytest.raises(FootfallError, match="coarser"):
        model.check_compatible(map_resolution=0.005)
    model.check_compatible(robot=model.robot, config=model.config, map_resolution=0.001)
    path = tmp_path / "m.npz"
    model.save(path)
    raw = dict(np.load(path, allow_pickle=False))
    meta = json.loads(str(raw.pop("meta")))
    columns = meta["groups"]["front"]["families"][0]["columns"]
    meta["groups"]["front"]["families"][0]["columns"] = columns[:-1]
    np.savez(tmp_path / "bad.npz", meta=json.dumps(meta), **raw)
    with pytest.raises(FootfallError, match="malformed model"):
        FootholdModel.load(tmp_path / "bad.npz")


def test_learning_never_consults_the_expert(demos_and_maps, monkeypatch):
    demos, maps = demos_and_maps

    def forbidden(*args, **kwargs):
        raise AssertionError("the learner asked the expert")

    for name in ("values", "terms", "choose"):
        monkeypatch.setattr(SyntheticExpert, name, forbidden)
    model = small("both", demos, maps)
    assert model.functions["front"].info["n_demonstrations"] > 0
    # And the learning modules do not even import it.
    code = ("import sys, footfall.learning.train, footfall.learning.ranker, footfall.learning.dataset, footfall.learning.model; "
            "print('footfall.expert.synthetic' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_learning_is_deterministic(demos_and_maps):
    demos, maps = demos_and_maps
    a, b = small("templates", demos, maps), small("templates", demos, maps)
    for g in ("front", "hind"):
        for fa, fb, ca, cb in zip(a.functions[g].families, b.functions[g].families,
                                  a.functions[g].coef, b.functions[g].coef):
            assert fa.columns() == fb.columns()
            np.testing.assert_array_equal(ca, cb)


def test_learn_and_rank_eval_commands(demos_and_maps, tmp_path, capsys):
    demos, maps = demos_and_maps
    store = tmp_path / "demos.sqlite"
    with DemoStore(store, create=True) as s:
        s.add_demonstrations(demos, terrains=list(maps.values()))
    model = tmp_path / "model.npz"
    code = main(["learn", str(store), "--features", "terrain", "--cv", "3", "-o", str(model),
                 "--json"])
    out, _ = capsys.readouterr()
    assert code == 0
    summary = json.loads(out)
    assert summary["groups"]["front"]["templates_kept"] == [0, 0, 0]
    assert summary["groups"]["hind"]["lambda"] > 0
    code = main(["rank-eval", str(model), str(store), "--json"])
    out, _ = capsys.readouterr()
    scores = json.loads(out)
    assert code == 0 and scores["n"] == len(demos)
    assert 0.5 < scores["percentile"] <= 1.0 and scores["reward_loss"] >= 0


def test_learning_bad_input_is_one_line_and_exit_2(demos_and_maps, tmp_path, capsys):
    demos, maps = demos_and_maps
    empty = tmp_path / "empty.sqlite"
    DemoStore(empty, create=True).close()
    corrupt = tmp_path / "corrupt.sqlite"
    corrupt.write_bytes(b"SQLite format 3\x00" + b"\x00" * 50)
    cases = [
        (["learn", str(empty), "--features", "both", "-o", str(tmp_path / "m.npz")], "no demonstrations"),
        (["learn", str(corrupt), "--features", "both", "-o", str(tmp_path / "m.npz")], ""),
        (["learn", str(tmp_path / "none.sqlite"), "--features", "both", "-o", str(tmp_path / "m.npz")], ""),
        (["learn", str(empty), "--features", "colour", "-o", str(tmp_path / "m.npz")], "Invalid value"),
        (["rank-eval", str(tmp_path / "nomodel.npz"), str(empty)], "no such file"),
    ]
    for args, match in cases:
        code = main(args)
        _, err = capsys.readouterr()
        assert code == 2, args
        assert len(err.strip().splitlines()) == 1 and match in err, err
    assert not (tmp_path / "m.npz").exists()
    # A model for another robot cannot rank demonstrations of this one.
    store = tmp_path / "d.sqlite"
    with DemoStore(store, create=True) as s:
        s.add_demonstrations(demos[:4], terrains=list(maps.values()))
    model = small("terrain", demos, maps)
    other = FootholdModel(model.feature_set, model.learner, model.functions, model.config,
                          RobotDescription(name="bigdog", upper_leg=0.3, lower_leg=0.3))
    other.save(tmp_path / "other.npz")
    code = main(["rank-eval", str(tmp_path / "other.npz"), str(store)])
    _, err = capsys.readouterr()
    assert code == 2 and "trained for robot" in err


def test_nan_features_are_refused():
    from footfall.learning.ranker import FootholdRanker
    X = np.zeros((4, 2))
    X[1, 0] = np.nan
    with pytest.raises(FootfallError, match="NaN"):
        FootholdRanker(cv=2).fit(X, np.array([1, 0, 1, 0]), np.array([0, 0, 1, 1]))


def test_servo_gains_do_not_make_a_model_incompatible():
    import dataclasses

    from footfall.core.robot import LITTLEDOG, SERVO_FIELDS
    model = FootholdModel("terrain", "l1", {}, FeatureConfig(), LITTLEDOG)
    softer = dataclasses.replace(LITTLEDOG, joint_kp=LITTLEDOG.joint_kp / 2, joint_kd=0.3)
    model.check_compatible(robot=softer)  # the servo only tracks set-points: same footholds
    assert "joint_kp" in SERVO_FIELDS
    with pytest.raises(FootfallError, match="lower_leg"):
        model.check_compatible(robot=dataclasses.replace(LITTLEDOG, lower_leg=0.12))


def test_family_options_reach_only_their_family_and_unknown_ones_are_refused(demos_and_maps):
    demos, maps = demos_and_maps
    with pytest.raises(FootfallError, match=r"'templates' has no option 'library_sise'; "
                                            r"its options: library_size, bandwidth_rms"):
        small("both", demos, maps, family_options={"templates": {"library_sise": 30}})
    with pytest.raises(FootfallError, match=r"'terrain' has no option 'library_size'; "
                                            r"its options: none"):
        small("both", demos, maps, family_options={"terrain": {"library_size": 30}})
    with pytest.raises(FootfallError, match=r"family 'templates', which is not in the feature "
                                            r"set \(terrain, pose\)"):
        small("terrain", demos, maps, family_options={"templates": {"library_size": 30}})
    # A family's own option reaches it, over the argument of the same name.
    rms = (0.002, 0.003, 0.006)  # [m]
    given = small("templates", demos, maps, family_options={"templates": {"bandwidth_rms": rms}})
    direct = learn_model(training(demos, maps), "templates", "l1", library_size=60,
                         training_candidates=30, cv=3, Cs=5, bandwidth_rms=rms)
    default = small("templates", demos, maps)
    for group, f in given.functions.items():
        bandwidths = f.family("templates").bandwidths
        assert bandwidths == direct.functions[group].family("templates").bandwidths
        assert bandwidths != default.functions[group].family("templates").bandwidths


def test_a_capped_library_never_offers_more_templates_than_its_size(demos_and_maps, tmp_path):
    demos, maps = demos_and_maps  # 16 demonstrations: more than 30 / 3 a scale
    logs = {True: [], False: []}
    for capped, log in logs.items():
        model = learn_model(training(demos, maps), "templates", "l1", library_size=30,
                            library_capped=capped, training_candidates=30, cv=3, Cs=5,
                            bandwidth_rms=(0.004, 0.004, 0.008), log=log.append)
    offered = {capped: next(line for line in log if line.startswith("template library"))
               for capped, log in logs.items()}
    assert offered[True] == "template library: 30 templates (10, 10, 10)"
    assert offered[False] == "template library: 48 templates (16, 16, 16)"
    model.save(tmp_path / "uncapped.npz")
    back = FootholdModel.load(tmp_path / "uncapped.npz")
    assert back.info["library_capped"] is False and back.info["library_size"] == 30
