"""Bad model files are refused at load with one line naming the file and the field (issue 17).

A small model is built directly (no learning: fast), saved, and then its arrays and metadata
are mutated and written back with the same format/version/meta header; each mutation must
be refused by :meth:`FootholdModel.load` and by ``footfall walk`` / ``footfall rank-eval``.
"""

import json

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.robot import LITTLEDOG
from footfall.data.store import DemoStore
from footfall.features.config import FeatureConfig
from footfall.features.pose_features import PoseFeatures
from footfall.features.reward import analytic_templates
from footfall.features.scoring import score_footholds
from footfall.features.template_library import TemplateLibrary
from footfall.features.templates import BANDWIDTH_RANGE, TemplateFeatures
from footfall.features.terrain_features import TerrainFeatures
from footfall.learning.function import MAX_WEIGHT, LinearFunction
from footfall.learning.model import LEG_GROUPS, FootholdModel

CONFIG = FeatureConfig()
INFO = {"lambda": 0.1, "C": 10.0, "cv_error": 0.2, "n_nonzero": 5, "library_counts": [3, 3, 3],
        "kept_counts": [3, 3, 3], "bandwidth_rms_m": [0.004, 0.004, 0.004]}


def make_model(coef_scale=1.0, bandwidths=None, library=None) -> FootholdModel:
    """A "both" model with the Fig. 2 templates and random weights (seeded)."""
    library = library or analytic_templates(CONFIG)[0]
    templates = TemplateFeatures(CONFIG, library).with_rms((0.004,) * 3)
    if bandwidths is not None:
        templates = TemplateFeatures(CONFIG, library, bandwidths)
    families = (TerrainFeatures(CONFIG), templates, PoseFeatures())
    rng = np.random.default_rng(0)
    functions = {g: LinearFunction(
        families, tuple(np.clip(coef_scale * rng.normal(size=len(f.columns())), -MAX_WEIGHT,
                                MAX_WEIGHT) for f in families),
        tuple(np.ones(len(f.columns())) for f in families), dict(INFO)) for g in LEG_GROUPS}
    return FootholdModel("both", "l1", functions, CONFIG, LITTLEDOG, 0.001, {"seed": 0})


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    path = tmp_path_factory.mktemp("models") / "good.npz"
    make_model().save(path)
    return path


def read_raw(path):
    with np.load(path, allow_pickle=False) as data:
        raw = {k: data[k] for k in data.files}
    return raw, json.loads(str(raw.pop("meta")))


def write_raw(path, raw, meta):
    """Write arrays and metadata with a header like :func:`footfall.core.files.save_npz`'s."""
    np.savez(path, meta=np.array(json.dumps(meta)), **raw)


def mutated(good, tmp_path, change, name="bad.npz"):
    raw, meta = read_raw(good)
    change(raw, meta)
    path = tmp_path / name
    write_raw(path, raw, meta)
    return path


def _front_family(meta, k):
    return meta["groups"]["front"]["families"][k]


def _set(getter, key, value):
    def change(raw, meta):
        getter(meta)[key] = value
    return change


def _bandwidth(value):
    return _set(lambda m: _front_family(m, 1)["params"]["bandwidths"], 0, value)


def _array(key, make):
    def change(raw, meta):
        raw[key] = make(raw[key])
    return change


def _with(value, at=0):
    def make(a):
        b = a.astype(np.float64).copy()
        b.flat[at] = value
        return b
    return make


def _delete(getter, key):
    def change(raw, meta):
        del getter(meta)[key]
    return change


COEF = "front.terrain.coef"
TEMPLATES = "front.templates.small_templates"
BAD_FILES = {
    # bandwidths [1/m^2] in the metadata
    "nan bandwidth": (_bandwidth(float("nan")), "groups.front.families[1] (templates): "
                      "params.bandwidths[0] [1/m^2] must be a finite number in [1e-06, 1e+12]"),
    "inf bandwidth": (_bandwidth(float("inf")), "params.bandwidths[0] [1/m^2] must be a finite"),
    "huge bandwidth": (_bandwidth(1e300), "got 1e+300"),
    "zero bandwidth": (_bandwidth(0.0), "params.bandwidths[0] [1/m^2] must be a finite"),
    "tiny bandwidth": (_bandwidth(1e-300), "params.bandwidths[0] [1/m^2] must be a finite"),
    "string bandwidth": (_bandwidth("abc"), "params.bandwidths[0] [1/m^2] must be a number, "
                                            "got str 'abc'"),
    "bool bandwidth": (_bandwidth(True), "must be a number, got bool True"),
    "two bandwidths": (_set(lambda m: _front_family(m, 1)["params"], "bandwidths", [1.0, 2.0]),
                       "params.bandwidths must hold one bandwidth per scale (3), got 2"),
    "bandwidths a dict": (_set(lambda m: _front_family(m, 1)["params"], "bandwidths", {"a": 1}),
                          "params.bandwidths must be a list"),
    # weights and scales
    "nan coef": (_array(COEF, _with(np.nan)), f"array {COEF} must be finite"),
    "inf coef": (_array(COEF, _with(-np.inf)), f"array {COEF} must be finite"),
    "huge coef": (_array(COEF, _with(1e300)), f"array {COEF} must lie within +-1e+20"),
    "complex coef": (_array(COEF, lambda a: a.astype(np.complex128)),
                     f"array {COEF} must hold real floating-point numbers, got dtype complex128"),
    "string coef": (_array(COEF, lambda a: a.astype(str)), "must hold real floating-point"),
    "bool coef": (_array(COEF, lambda a: a > 0), "got dtype bool"),
    "int coef": (_array(COEF, lambda a: a.astype(np.int64)), "got dtype int64"),
    "short coef": (_array(COEF, lambda a: a[:-1]), f"array {COEF} must have shape (27,), got (26,)"),
    "2-d coef": (_array(COEF, lambda a: a[None]), "must have shape (27,), got (1, 27)"),
    "zero scale": (_array("hind.pose.scale", _with(0.0)), "array hind.pose.scale must be > 0"),
    "nan scale": (_array("hind.pose.scale", _with(np.nan)), "array hind.pose.scale must be finite"),
    "missing coef": (lambda raw, meta: raw.pop("hind.pose.coef"), "lacks array hind.pose.coef"),
    "extra array": (lambda raw, meta: raw.update(junk=np.zeros(3)), "unexpected array(s) junk"),
    "extra terrain parameter": (lambda raw, meta: raw.update({"front.terrain.h": np.zeros(3)}),
                                "(terrain): has unexpected array(s) h"),
    # templates
    "nan template": (_array(TEMPLATES, _with(np.nan)), "array small_templates must be finite"),
    "huge template": (_array(TEMPLATES, _with(1e300)), "array small_templates must lie within"),
    "complex template": (_array(TEMPLATES, lambda a: a + 1j), "small_templates must hold real"),
    "template patch shape": (_array(TEMPLATES, lambda a: a[:, :-1]),
                             "array small_templates must have shape (n, 81), got (3, 80)"),
    "sources shape": (_array("front.templates.small_sources", lambda a: a[:, :3]),
                      "array small_sources must have shape (3, 4)"),
    "missing templates": (lambda raw, meta: raw.pop(TEMPLATES),
                          "the template library lacks array small_templates"),
    "library config": (_set(lambda m: _front_family(m, 1)["params"]["library"]["config"],
                            "min_coverage", 0.75), "other feature settings"),
    "library a list": (_set(lambda m: _front_family(m, 1)["params"], "library", [1]),
                       "params.library must be an object"),
    "terrain hashes": (_set(lambda m: _front_family(m, 1)["params"]["library"],
                            "terrain_hashes", [1]), "params.library.terrain_hashes[0] must be"),
    "terrain params": (_set(lambda m: _front_family(m, 0), "params", {"h": 1}),
                       "(terrain): params must be empty"),
    # structure
    "groups a list": (_set(lambda m: m, "groups", [1, 2]), "groups must be an object (dict), "
                                                           "got list [1, 2]"),
    "groups lack hind": (_delete(lambda m: m["groups"], "hind"), "groups lacks 'hind'"),
    "groups extra": (_set(lambda m: m["groups"], "middle", {}), "groups has unknown key(s) 'middle'"),
    "families a dict": (_set(lambda m: m["groups"]["front"], "families", {}),
                        "groups.front.families must be a list"),
    "family a string": (_set(lambda m: m["groups"]["front"]["families"], 0, "terrain"),
                        "groups.front.families[0] must be an object"),
    "family name an int": (_set(lambda m: _front_family(m, 0), "name", 3),
                           "groups.front.families must be of the feature set's families"),
    "family names swapped": (lambda raw, meta: meta["groups"]["front"]["families"].reverse(),
                             "must be of the feature set's families ['terrain', 'templates', "
                             "'pose'], each at most once and in that order"),
    "family repeated": (lambda raw, meta: meta["groups"]["front"]["families"].append(
        _front_family(meta, 0)), "each at most once"),
    "no families": (_set(lambda m: m["groups"]["front"], "families", []),
                    "groups.front.families must be of the feature set's families"),
    "columns of ints": (_set(lambda m: _front_family(m, 2), "columns", [1, 2]),
                        "groups.front.families[2].columns[0] must be a string"),
    "columns mismatched": (lambda raw, meta: _front_family(meta, 2)["columns"].pop(),
                           "groups.front.families[2].columns do not match the pose family's"),
    "group info a list": (_set(lambda m: m["groups"]["hind"], "info", []),
                          "groups.hind.info must be an object"),
    "lambda a string": (_set(lambda m: m["groups"]["hind"]["info"], "lambda", "x"),
                        "groups.hind.info.lambda must be a number"),
    "counts a string": (_set(lambda m: m["groups"]["hind"]["info"], "library_counts", "abc"),
                        "groups.hind.info.library_counts must be a list"),
    "meta a list": (None, "meta must be a JSON object, got list"),  # refused by load_npz
    "feature set unknown": (_set(lambda m: m, "feature_set", "colour"), "unknown feature set"),
    "feature set an int": (_set(lambda m: m, "feature_set", 3), "feature_set must be a string"),
    "learner unknown": (_set(lambda m: m, "learner", "magic"), "unknown learner 'magic'"),
    "learner a list": (_set(lambda m: m, "learner", ["l1"]), "learner must be a string"),
    "no feature set": (_delete(lambda m: m, "feature_set"), "meta lacks 'feature_set'"),
    "unknown meta key": (_set(lambda m: m, "colour", 1), "meta has unknown key(s) 'colour'"),
    "map resolution nan": (_set(lambda m: m, "map_resolution", float("nan")),
                           "map_resolution [m/cell] must be a finite number in (0, 1]"),
    "map resolution string": (_set(lambda m: m, "map_resolution", "abc"),
                              "map_resolution [m/cell] must be a number, got str 'abc'"),
    "map resolution negative": (_set(lambda m: m, "map_resolution", -1), "map_resolution"),
    "info a list": (_set(lambda m: m, "info", [1]), "info must be an object"),
    "scales empty": (_set(lambda m: m["config"], "scales", []), "feature config: scales must be"),
    "scale nan": (_set(lambda m: m["config"], "scales", [["small", float("nan"), 0.02]]),
                  "feature config: scales must be"),
    "resolution tiny": (_set(lambda m: m["config"], "template_resolution", 1e-12),
                        "feature config: template_resolution must be in [0.0001, 0.01]"),
    "resolution absurd": (_set(lambda m: m["config"], "template_resolution", 1e-200),
                          "feature config: template_resolution must be in [0.0001, 0.01]"),
    "resolution huge": (_set(lambda m: m["config"], "template_resolution", 1e300),
                        "feature config: template_resolution must be in [0.0001, 0.01]"),
    "resolution a string": (_set(lambda m: m["config"], "template_resolution", "abc"),
                            "feature config: template_resolution must be in [0.0001, 0.01], "
                            "got 'abc'"),
    "robot a list": (_set(lambda m: m, "robot", []), "robot must be an object"),
    "robot huge leg": (_set(lambda m: m["robot"], "upper_leg", 1e300), "robot.upper_leg must be"),
    "robot leg string": (_set(lambda m: m["robot"], "upper_leg", "x"), "robot.upper_leg must be"),
    "robot unknown": (_set(lambda m: m["robot"], "wings", 2), "robot has unknown field(s)"),
    "robot tuple": (_set(lambda m: m["robot"], "trunk_size", [1]), "robot.trunk_size must hold 3"),
}


def _meta_a_list(good, tmp_path):
    raw, _ = read_raw(good)
    path = tmp_path / "bad.npz"
    write_raw(path, raw, [1, 2])
    return path


def bad_file(good, tmp_path, case):
    change, match = BAD_FILES[case]
    if change is None:
        return _meta_a_list(good, tmp_path), match
    return mutated(good, tmp_path, change), match


def test_the_good_model_loads_and_round_trips(good):
    model = FootholdModel.load(good)
    assert model.feature_set == "both" and model.functions["front"].info == INFO
    assert model.functions["hind"].family("templates").bandwidths == \
        make_model().functions["hind"].family("templates").bandwidths


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_a_bad_model_file_is_refused_naming_the_file_and_field(good, tmp_path, case):
    path, match = bad_file(good, tmp_path, case)
    with pytest.raises(FootfallError) as info:
        FootholdModel.load(path)
    message = str(info.value)
    prefix = f"{path}: " if case == "meta a list" else f"{path}: malformed model: "
    assert message.startswith(prefix) and "\n" not in message, message
    assert match in message, message


@pytest.fixture(scope="module")
def board(tmp_path_factory):
    from footfall.cli import main

    path = tmp_path_factory.mktemp("board") / "board.npz"
    assert main(["terrain", "make", "flat", "--seed", "1", "-o", str(path)]) == 0
    return path


@pytest.mark.parametrize("case", ["nan bandwidth", "string bandwidth", "huge bandwidth",
                                  "complex coef", "huge template", "groups a list",
                                  "columns mismatched", "meta a list"])
def test_walk_and_rank_eval_refuse_a_bad_model_in_one_line(good, board, tmp_path, capsys, case):
    path, match = bad_file(good, tmp_path, case)
    store = tmp_path / "demos.sqlite"
    DemoStore(store, create=True).close()
    for args in (["walk", "--terrain", board, "--model", path, "--seed", "0"],
                 ["rank-eval", path, store], ["rank-eval", path, store, "--json"]):
        code, out, err = run(capsys, *args)
        assert_user_error(code, err, f"{path}: " if case == "meta a list"
                          else f"{path}: malformed model: ")
        assert match in err and out == ""


def _as_version_1(good, tmp_path):
    """The good model rewritten in the version 1 layout: one flat list of names per group."""
    raw, meta = read_raw(good)
    out = {"format": raw["format"], "version": np.array(1, dtype=np.int64)}
    for g in LEG_GROUPS:
        names, coef, scale = [], [], []
        for family in meta["groups"][g]["families"]:
            f = family["name"]
            names += [f"pose.{c}" if f == "pose" else c for c in family["columns"]]
            coef.append(raw[f"{g}.{f}.coef"])
            scale.append(raw[f"{g}.{f}.scale"])
            if f == "templates":
                library, bandwidths = family["params"]["library"], family["params"]["bandwidths"]
                for s in CONFIG.scale_names:
                    for kind in ("templates", "sources"):
                        out[f"{g}_lib_{s}_{kind}"] = raw[f"{g}.templates.{s}_{kind}"]
        out[f"{g}_coef"], out[f"{g}_scale"] = np.concatenate(coef), np.concatenate(scale)
        meta["groups"][g] = {"names": names, "bandwidths": bandwidths, "library": library,
                             "info": meta["groups"][g]["info"]}
    path = tmp_path / "v1.npz"
    write_raw(path, out, meta)
    return path


V1_CASES = {
    "nan bandwidth": (lambda raw, meta: meta["groups"]["front"]["bandwidths"].__setitem__(
        0, float("nan")), "groups.front.bandwidths[0] [1/m^2] must be a finite number"),
    "library none": (_set(lambda m: m["groups"]["hind"], "library", None),
                     "groups.hind.library must be a template library, got None"),
    "name missing": (lambda raw, meta: meta["groups"]["front"]["names"].__setitem__(
        meta["groups"]["front"]["names"].index("small.std"), "small.stdev"),
                     "groups.front.names lack the terrain column 'small.std'"),
    "name unknown": (lambda raw, meta: meta["groups"]["front"]["names"].__setitem__(0, "x.y"),
                     "groups.front.names lack the terrain column 'small.slope_x_pos'"),
    "names repeated": (lambda raw, meta: meta["groups"]["front"]["names"].__setitem__(
        1, "small.slope_x_pos"), "groups.front.names must be distinct"),
    "nan coef": (_array("front_coef", _with(np.nan, at=5)), "array front_coef must be finite"),
    "complex scale": (_array("hind_scale", lambda a: a + 0j), "array hind_scale must hold real"),
    "short coef": (_array("front_coef", lambda a: a[:-1]), "array front_coef must have shape"),
    "nan template": (_array("hind_lib_large_templates", _with(np.nan)),
                     "array hind_lib_large_templates must be finite"),
    "extra array": (lambda raw, meta: raw.update(front_junk=np.zeros(2)),
                    "unexpected array(s) front_junk"),
    "group keys": (_delete(lambda m: m["groups"]["front"], "names"),
                   "groups.front lacks 'names'"),
}


def test_a_version_1_model_loads_and_ranks_like_version_2(good, tmp_path):
    v1, v2 = FootholdModel.load(_as_version_1(good, tmp_path)), FootholdModel.load(good)
    for g in LEG_GROUPS:
        assert v1.functions[g].names == v2.functions[g].names
        for a, b in zip(v1.functions[g].coef, v2.functions[g].coef):
            np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("case", sorted(V1_CASES))
def test_a_bad_version_1_model_is_refused(good, tmp_path, case):
    v1 = _as_version_1(good, tmp_path)
    change, match = V1_CASES[case]
    path = mutated(v1, tmp_path, change, name="bad-v1.npz")
    raw, meta = read_raw(path)
    with pytest.raises(FootfallError, match="malformed model") as info:
        FootholdModel.load(path)
    assert match in str(info.value), str(info.value)


def test_the_extremes_a_model_file_admits_still_score_finite(board, tmp_path):
    """At the edges of every accepted range (weights, bandwidths, template heights) a loaded
    model's reward of finite terrain is finite (or -inf: not a valid foothold), never NaN."""
    from footfall.core.heightmap import HeightMap
    from footfall.core.state import nominal_state
    from footfall.features.dense import score_grid

    hmap = HeightMap.load(board)
    base = analytic_templates(CONFIG)[0]
    for h, height in ((BANDWIDTH_RANGE[1], 1000.0), (BANDWIDTH_RANGE[0], -1000.0)):
        library = TemplateLibrary(CONFIG, tuple(np.clip(t * 1e6, -height, height) if height > 0
                                                else np.full_like(t, height) for t in base.templates),
                                  base.sources)
        model = make_model(coef_scale=MAX_WEIGHT, bandwidths=(h,) * 3, library=library)
        path = tmp_path / "extreme.npz"
        model.save(path)
        back = FootholdModel.load(path)
        reward = back.reward_for("LF")
        grid = score_grid(hmap, reward, spacing=0.01)
        assert not np.isnan(grid.reward).any() and np.isfinite(grid.reward[grid.valid]).all()
        x0, x1, y0, y1 = hmap.bounds
        centre = ((x0 + x1) / 2, (y0 + y1) / 2)
        state = nominal_state(hmap, centre, 0.0, "LF")
        near = state.feet[0] + np.array([[dx, dy, 0.0] for dx in (-0.02, 0.0, 0.02)
                                         for dy in (-0.02, 0.0, 0.02)])
        near[:, 2] = hmap.height_at(near[:, :2])
        r = score_footholds(hmap, state, near, reward)
        assert np.isfinite(r).all(), r


# ------------------------------------------------------------------ footfall learn arguments
@pytest.mark.parametrize("args, match", [
    (["--bandwidth-rms", "1e-300", "1e-300", "1e-300"],
     "Invalid value for '--bandwidth-rms': 1e-300 is not in the range 1e-05<=x<=1.0"),
    (["--bandwidth-rms", "nan", "0.004", "0.004"], "'nan' is not a finite number"),
    (["--bandwidth-rms", "0.004", "inf", "0.004"], "Invalid value for '--bandwidth-rms'"),
    (["--bandwidth-rms", "0.004", "abc", "0.004"], "Invalid value for '--bandwidth-rms'"),
    (["--seed", "-1"], "Invalid value for '--seed': -1 is not in the range 0<=x<="),
    (["--seed", str(10 ** 30)], "Invalid value for '--seed'"),
    (["--library-size", "1000000"], "--library-size = 1000000 is above the limit of 100000"),
    (["--library-size", "2"], "Invalid value for '--library-size'"),
    (["--training-candidates", "1000000"], "--training-candidates = 1000000 is above the limit"),
    (["--training-candidates", "0"], "Invalid value for '--training-candidates'"),
    (["--cv", "1"], "Invalid value for '--cv'"),
    (["-o", "{tmp}/model.txt"], "output model {tmp}/model.txt must end in .npz"),
    (["-o", "{tmp}/missing/model.npz"], "output directory does not exist: {tmp}/missing"),
    (["-o", "{tmp}/dir.npz"], "output path is a directory: {tmp}/dir.npz"),
])
def test_learn_arguments_are_checked_before_anything_is_read(tmp_path, capsys, args, match):
    (tmp_path / "dir.npz").mkdir()
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    if "-o" not in args:
        args += ["-o", str(tmp_path / "m.npz")]
    # The store does not exist: each bad argument is found first, before the store is opened.
    code, out, err = run(capsys, "learn", tmp_path / "none.sqlite", "--features", "terrain", *args)
    assert_user_error(code, err, match.replace("{tmp}", str(tmp_path)))
    assert out == "" and not (tmp_path / "m.npz").exists()


def test_learn_counts_follow_the_max_count_limit(tmp_path, capsys):
    code, _, err = run(capsys, "--limit", "max_count=2000000", "learn", tmp_path / "none.sqlite",
                       "--features", "terrain", "--library-size", "1000000", "-o",
                       tmp_path / "m.npz")
    assert_user_error(code, err, "none.sqlite")  # the count passed: the missing store is next


@pytest.mark.skipif(not hasattr(__import__("os"), "geteuid") or __import__("os").geteuid() == 0,
                    reason="root may write anywhere")
def test_learn_refuses_an_output_directory_it_cannot_write(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        code, _, err = run(capsys, "learn", tmp_path / "none.sqlite", "--features", "terrain",
                           "-o", locked / "m.npz")
    finally:
        locked.chmod(0o700)
    assert_user_error(code, err, f"output directory is not writable: {locked}")


def test_learning_settings_are_checked_by_the_library_too():
    from footfall.features.templates import bandwidth_for_rms
    from footfall.learning.train import learn_model

    for kwargs, match in (({"seed": -1}, "seed must be >= 0, got -1"),
                          ({"seed": 1.5}, "seed must be an integer, got float 1.5"),
                          ({"library_size": 10 ** 9}, "library_size = 1000000000 is above"),
                          ({"training_candidates": True}, "training_candidates must be a whole"),
                          ({"cv": 1}, "cv must be >= 2")):
        with pytest.raises(FootfallError, match=match):
            learn_model([], "terrain", **kwargs)
    for rms in (1e-300, 0.0, float("nan"), float("inf"), 2.0, "abc"):
        with pytest.raises(FootfallError, match="RMS height difference"):
            bandwidth_for_rms(rms, CONFIG.grids[0])
    with pytest.raises(FootfallError, match="bandwidths must hold one bandwidth per scale"):
        TemplateFeatures(CONFIG).with_rms((0.004, 0.004))


def test_the_cli_rms_range_is_the_template_family_s():
    from footfall.cli.learning import RMS_RANGE
    from footfall.features import templates

    assert RMS_RANGE == templates.RMS_RANGE


# ------------------------------------------------------------- rank-eval without the expert
@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    from footfall.expert.collect import collect_demonstrations
    from footfall.expert.synthetic import SyntheticExpert
    from footfall.terrain import make_board

    board = make_board([("flat", 0.3)], seed=11)
    demos = collect_demonstrations([board], SyntheticExpert(), 2, seed=3)
    path = tmp_path_factory.mktemp("store") / "demos.sqlite"
    with DemoStore(path, create=True) as store:
        store.add_demonstrations(demos, terrains=[board])
    return path


def test_rank_eval_without_the_expert_prints_null_and_n_a(good, small_store, capsys):
    code, out, err = run(capsys, "rank-eval", good, small_store, "--no-expert", "--json")
    assert code == 0, err
    data = json.loads(out)  # strict JSON: no NaN token
    assert "NaN" not in out and data["n"] >= 1
    assert data["reward_loss"] is None and data["reward_loss_std"] is None
    assert data["reward_loss_ci"] == [None, None] and data["losses"] == []
    assert 0 <= data["percentile"] <= 1
    code, out, err = run(capsys, "rank-eval", good, small_store, "--no-expert")
    assert code == 0 and "reward loss n/a (95 % CI n/a to n/a)" in out and "nan" not in out


def test_emit_prints_a_non_finite_number_as_null(capsys):
    from footfall.cli.output import emit

    emit(True, {"a": float("nan"), "b": [float("inf"), 1.5], "c": np.float64("-inf")}, "")
    assert json.loads(capsys.readouterr().out) == {"a": None, "b": [None, 1.5], "c": None}


def test_an_object_array_is_refused_without_unpickling(good, tmp_path):
    raw, meta = read_raw(good)
    raw[COEF] = np.array([{"a": 1}] * 27, dtype=object)
    path = tmp_path / "object.npz"
    np.savez(path, meta=np.array(json.dumps(meta)), allow_pickle=True, **raw)
    with pytest.raises(FootfallError) as info:
        FootholdModel.load(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)
