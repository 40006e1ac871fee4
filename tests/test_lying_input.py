"""Input that looks valid but is not: an output that is an input, seeds past their range, and
commands that fail leaving files behind or losing what they did."""

import os

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.files import same_file, writable_path
from footfall.core.heightmap import HeightMap
from footfall.data.store import DemoStore
from footfall.experiments import batch
from footfall.experiments.ablation import AblationConfig
from footfall.expert.collect import collect_into_store
from footfall.terrain.saving import save_board

TOP = 2 ** 63 - 1  # the largest seed a store keeps


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lying")
    save_board(["flat", "flat"], 0, folder / "flat.npz")  # 1.22 m: a short run
    save_board(["flat"], 0, folder / "short.npz", flat_ends=False)  # too short to walk
    save_board(["rocky:0.5"], 1, folder / "rocky.npz")
    collect_into_store([folder / "rocky.npz"], folder / "store.sqlite", n=12, seed=0)
    return folder


def test_an_output_that_is_an_input_by_name_or_link_is_refused_and_the_input_kept(files,
                                                                                  tmp_path,
                                                                                  capsys):
    store = tmp_path / "st.npz"  # a store under a model's name: the finding
    store.write_bytes((files / "store.sqlite").read_bytes())
    (tmp_path / "soft.npz").symlink_to(store)
    os.link(store, tmp_path / "hard.npz")
    before = store.read_bytes()
    for output in ("st.npz", "soft.npz", "hard.npz"):
        assert_user_error(*run(capsys, "learn", store, "--features", "terrain", "-o",
                               tmp_path / output)[::2], "is also an input")
    assert store.read_bytes() == before
    board = files / "flat.npz"
    for args in (["terrain", "show", board, "-o", board],
                 ["terrain", "import", board, "-o", board],
                 ["terrain", "board", "flat", board, "--seed", 0, "-o", board],
                 ["walk", "--terrain", board, "--seed", 0, "--log", board],
                 ["walk", "--terrain", board, "--seed", 0, "--snapshots", tmp_path / "a.png",
                  "--explain-plot", tmp_path / "a.png"],
                 ["walk-many", "--terrain", board, "--runs", 1, "--seed", 0, "--log", board],
                 ["demos", "collect", "--terrain", board, "-n", 1, "--seed", 0, "-o", board]):
        assert_user_error(*run(capsys, *args)[::2], "is also an input")
    assert same_file(board, files / "flat.npz") and batch.load_board(board).shape[0] > 0


def test_same_file_sees_through_links_and_missing_files(tmp_path):
    a = tmp_path / "a"
    a.write_text("x")
    (tmp_path / "b").symlink_to(a)
    assert same_file(a, tmp_path / "b") and same_file(tmp_path / "c", tmp_path / "." / "c")
    assert not same_file(a, tmp_path / "c")
    with pytest.raises(FootfallError, match="is also an input"):
        writable_path(tmp_path / "b", inputs=(None, a))


def test_a_batch_whose_last_seed_is_past_the_range_is_refused_before_any_run(files, tmp_path,
                                                                            capsys):
    log = tmp_path / "s.sqlite"
    assert_user_error(*run(capsys, "walk-many", "--terrain", files / "flat.npz", "--runs", 2,
                           "--seed", TOP, "--log", log)[::2], f"reaches seed {TOP + 1}")
    assert not log.exists()
    with pytest.raises(FootfallError, match="the test board's first run seed"):
        AblationConfig(test_seed=TOP - 2)
    code, out, _ = run(capsys, "walk-many", "--terrain", files / "flat.npz", "--runs", 1,
                       "--seed", TOP, "--log", log, "--json")
    assert code == 0  # the last seed itself is fine, and kept exactly
    with DemoStore(log) as store:
        assert [store.run(r["id"]).seed for r in store.runs()] == [TOP]


def test_a_refused_walk_leaves_no_store_and_a_walked_run_outlives_its_picture(files, tmp_path,
                                                                             monkeypatch):
    log = tmp_path / "new.sqlite"
    for walk in (lambda: batch.walk_once(files / "short.npz", 0, log_path=log),
                 lambda: batch.walk_batch(files / "short.npz", 2, 0, log_path=log)):
        with pytest.raises(FootfallError, match="too short"):
            walk()
        assert not log.exists()

    def full_disk(*args, **kwargs):
        raise FootfallError("no space left on the device")

    monkeypatch.setattr(batch, "save_strip", full_disk)
    with pytest.raises(FootfallError, match="no space"):
        batch.walk_once(files / "flat.npz", 1, search_radius=0.03, log_path=log,
                        snapshots=tmp_path / "snap.png", frames=2)
    with DemoStore(log) as store:
        assert [store.run(r["id"]).seed for r in store.runs()] == [1]  # the run was kept


def test_a_listed_command_without_its_optional_library_says_what_to_install(capsys,
                                                                            monkeypatch):
    import sys

    for name in [m for m in sys.modules if m.startswith("footfall.cli.fuzz")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "hypothesis", None)  # as on an install without [test]
    assert_user_error(*run(capsys, "bench", "fuzz", "--minutes", 0.05)[::2],
                      "pip install 'footfall[test]'")


def test_absurd_but_finite_template_resolutions_are_refused_in_one_line(files, capsys):
    for value in ("1e-300", "1e300", "0.02"):
        assert_user_error(*run(capsys, "features", files / "rocky.npz", "--at", 0.3, 0.1,
                               "--template-resolution", value)[::2],
                          "template_resolution must be in [0.0001, 0.01]")
    from footfall.features.config import SCALES, FeatureConfig, Scale

    with pytest.raises(FootfallError, match="no sample beside its centre"):
        FeatureConfig(template_resolution=0.008, scales=(Scale("tiny", 0.004, 0.004), *SCALES))


def test_a_model_that_cannot_tell_candidates_apart_is_not_scored_as_perfect(files, tmp_path,
                                                                           capsys):
    from test_bad_models import make_model

    make_model(coef_scale=0.0).save(tmp_path / "zero.npz")  # every candidate valued 0
    code, out, err = run(capsys, "rank-eval", tmp_path / "zero.npz", files / "store.sqlite",
                         "--no-expert", "--json")
    assert code == 0, err
    import json

    s = json.loads(out)
    assert s["constant"] == 1.0 and s["tied"] == 1.0
    assert s["top1"] < 0.05 and s["percentile"] == 0.5  # a coin, not a perfect ranker
    code, out, _ = run(capsys, "rank-eval", tmp_path / "zero.npz", files / "store.sqlite",
                       "--no-expert")
    assert "cannot tell them apart" in out


def test_ties_are_expectations_over_the_tied_best():
    from types import SimpleNamespace

    from footfall.learning.evaluation import _decision

    d = SimpleNamespace(chosen=0, candidates=np.array([[0, 0, 0], [0.005, 0, 0], [0.1, 0, 0],
                                                       [0.2, 0, 0]], dtype=float))
    values = np.array([3.0, 2.0, 1.0, 0.0])  # the expert's: its choice is worth 3
    top1, near, pct, loss, tied, constant = _decision(np.array([5.0, 5.0, 5.0, 1.0]), d, values)
    assert top1 == pytest.approx(1 / 3) and near == pytest.approx(2 / 3)
    assert pct == pytest.approx((1 + 0.5 * 2) / 3) and loss == pytest.approx(3 - 2)
    assert tied == 1.0 and constant == 0.0
    assert _decision(np.array([9.0, 5.0, 5.0, 1.0]), d, values)[:4] == (1.0, 1.0, 1.0, 0.0)


def _lying_board(source, path, **change):
    """The board at ``source`` saved to ``path`` with some of its fields changed."""
    hm = HeightMap.load(source)
    fields = {"heights": hm.heights, "resolution": hm.resolution, "origin": hm.origin,
              "metadata": hm.metadata, **change}
    HeightMap(**fields).save(path)
    return path


def test_a_board_whose_records_disagree_with_its_map_is_refused_in_one_line(files, tmp_path,
                                                                           capsys):
    flat = HeightMap.load(files / "flat.npz")
    moved = [dict(m, x_start=m["x_start"] + 50.0, x_end=m["x_end"] + 50.0)
             for m in flat.metadata["modules"]]
    for change, message in (
            ({"resolution": 0.002}, "its modules end at 1.22 m but the map is 2.44 m long "
                                    "(1220 cells of 0.002 m)"),
            ({"metadata": {**flat.metadata, "modules": moved}},
             "module 0 starts at 50 m, not where the map starts (0 m)"),
            ({"origin": (999_000.0, flat.origin[1])},
             "m from its frame's origin; a board that is walked must lie within 1000 m")):
        board = _lying_board(files / "flat.npz", tmp_path / "lie.npz", **change)
        code, _, err = run(capsys, "walk", "--terrain", board, "--seed", "0")
        assert_user_error(code, err, message)
    assert batch.load_board(files / "flat.npz").shape == flat.shape  # the true board walks


def test_a_model_is_held_to_the_terrains_its_templates_claim(files, tmp_path, capsys):
    import json

    from footfall.core.files import load_npz, save_npz
    from footfall.learning import model as model_file
    from footfall.learning.train import learn_from_store

    model = tmp_path / "m.npz"
    learn_from_store(files / "store.sqlite", model, "templates", library_size=30, cv=3, Cs=4)
    code, out, err = run(capsys, "rank-eval", model, files / "store.sqlite", "--no-expert",
                         "--json")
    assert code == 0, err
    assert json.loads(out)["trained_here"] == 1  # measured on its own terrain: said so
    _, out, _ = run(capsys, "rank-eval", model, files / "store.sqlite", "--no-expert")
    assert "not a held-out measure" in out
    other = tmp_path / "other.sqlite"  # another board's decisions: held out, no warning
    save_board(["rocky:0.5"], 2, tmp_path / "other.npz")
    collect_into_store([tmp_path / "other.npz"], other, n=4, seed=0)
    code, out, err = run(capsys, "rank-eval", model, other, "--no-expert", "--json")
    assert code == 0 and json.loads(out)["trained_here"] == 0, err

    _, arrays, meta = load_npz(model, model_file.FORMAT, model_file.VERSION, allow_nonfinite=True)
    name = next(k for k in sorted(arrays) if k.endswith("_templates") and arrays[k].size)
    edited = dict(arrays, **{name: arrays[name] + 0.001})  # every template 1 mm higher
    save_npz(tmp_path / "edited.npz", model_file.FORMAT, model_file.VERSION, edited, meta)
    assert_user_error(*run(capsys, "rank-eval", tmp_path / "edited.npz", files / "store.sqlite",
                           "--no-expert")[::2], "not the patches their sources name")
    code, out, err = run(capsys, "rank-eval", tmp_path / "edited.npz", other, "--no-expert")
    assert code == 0, err  # its terrains are not here: nothing to hold it to

    text = json.dumps(meta)
    hashes = {h for g in meta["groups"].values() for fam in g["families"]
              for h in fam["params"].get("library", {}).get("terrain_hashes", [])}
    assert hashes, "the model names the terrains of its templates"
    for h in hashes:
        text = text.replace(h, "no-such-terrain")
    save_npz(tmp_path / "nowhere.npz", model_file.FORMAT, model_file.VERSION, arrays,
             json.loads(text))
    assert_user_error(*run(capsys, "rank-eval", tmp_path / "nowhere.npz", other,
                           "--no-expert")[::2], "64 hexadecimal digits")


def test_walk_many_refuses_a_stored_run_the_store_check_calls_corrupt(files, tmp_path, capsys):
    import sqlite3

    log = tmp_path / "s.sqlite"
    args = ("walk-many", "--terrain", files / "flat.npz", "--runs", 1, "--seed", 7, "--log", log,
            "--processes", 1)
    code, _, err = run(capsys, *args)
    assert code == 0, err
    con = sqlite3.connect(log)
    with con:
        con.execute("UPDATE runs SET n_steps = n_steps + 1")  # the steps no longer add up
    con.close()
    assert_user_error(*run(capsys, "store", "check", log)[::2], "n_steps")
    assert_user_error(*run(capsys, *args)[::2], "n_steps")  # not reused as if it were whole
