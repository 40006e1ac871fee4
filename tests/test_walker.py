"""The kinematic walker, demonstration collection, and the `footfall demos` commands."""

import json
import shutil
import sqlite3
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import DEFAULT_STRIDE, LEG_NAMES, LITTLEDOG
from footfall.data.store import DemoStore
from footfall.expert import collect
from footfall.expert.collect import (
    PATH_OFFSETS,
    collect_demonstrations,
    estimated_steps,
    lateral_paths,
    rough_x_range,
)
from footfall.expert.protocol import expert_settings
from footfall.expert.walker import EDGE_MARGIN, WalkOptions, WalkPath, walk_demonstrations
from footfall.features.candidates import reachable_footholds
from footfall.features.config import FeatureConfig

SPACING = 0.01  # [m] a coarse candidate lattice keeps the walks fast
FAST = WalkOptions(spacing=SPACING)


class ProgressExpert:
    """Stand-in expert: forward progress, staying near the nominal lateral foot position."""

    def __init__(self, noise=0.005):
        self.noise = noise  # [m] spread of the value noise

    def values(self, hmap, state, candidates):
        leg = LITTLEDOG.leg(state.swing_leg)
        target_y = state.body_position[1] + leg.side * LITTLEDOG.nominal_foot_y
        return candidates[:, 0] - 2.0 * np.abs(candidates[:, 1] - target_y)

    def choose(self, hmap, state, candidates, rng):
        v = self.values(hmap, state, candidates)
        return int(np.argmax(v + self.noise * rng.standard_normal(v.shape)))


def bumpy(length=0.7, width=0.5, seed=1, modules=None):
    """Smooth random bumps (a few mm) on a board x in [0, length), centred on y = 0 [m]."""
    res = 0.002
    rng = np.random.default_rng(seed)
    h = gaussian_filter(rng.normal(size=(round(length / res), round(width / res))), 4) * 0.05
    meta = {} if modules is None else {"modules": modules}
    return HeightMap(h - h.min(), res, (res / 2, -width / 2 + res / 2), metadata=meta)


@pytest.fixture(scope="module")
def board():
    return bumpy()


@pytest.fixture(scope="module")
def walk(board):
    return walk_demonstrations(board, ProgressExpert(), np.random.default_rng(3), 8, options=FAST)


# ---------------------------------------------------------------------- walker
def test_walk_follows_the_crawl_gait_and_the_expert(board, walk):
    assert len(walk) == 8
    assert [d.swing_leg for d in walk] == list(LITTLEDOG.gait_order) * 2  # LH, LF, RH, RF
    step = DEFAULT_STRIDE / 4
    start_x = board.bounds[0] + LITTLEDOG.hip_x + EDGE_MARGIN
    for k, d in enumerate(walk):
        assert d.terrain_hash == board.content_hash() and d.source == "walker"
        assert d.expert == {"class": "test_walker.ProgressExpert"}
        body = d.state.body_position
        assert body[0] == pytest.approx(start_x + (k + 1) * step)  # advances 0.02 m a step
        assert body[1] == 0.0 and np.all(d.state.body_rpy == 0.0)
        assert body[2] == pytest.approx(d.state.feet[:, 2].mean() + LITTLEDOG.nominal_height)
        assert 0 <= d.chosen < d.n_candidates
        np.testing.assert_array_equal(d.foothold, d.candidates[d.chosen])
        v = ProgressExpert().values(board, d.state, d.candidates)
        assert v[d.chosen] > np.quantile(v, 0.99)  # the stand-in's choice, up to its noise
    for prev, d in zip(walk, walk[1:]):  # the swing foot lands on the chosen foothold ...
        moved = LEG_NAMES.index(prev.swing_leg)
        np.testing.assert_array_equal(d.state.feet[moved], prev.foothold)
        others = [i for i in range(4) if i != moved]  # ... and the others stay put
        np.testing.assert_array_equal(d.state.feet[others], prev.state.feet[others])
    # The swing feet land ahead: the robot walks forward.
    lf = [d.foothold[0] for d in walk if d.swing_leg == "LF"]
    assert lf[1] > lf[0] > walk[0].state.feet[0, 0]


def test_candidates_are_the_reachable_footholds_with_valid_features(board, walk):
    for d in (walk[0], walk[5]):
        expected = reachable_footholds(board, d.state, LITTLEDOG, SPACING, FeatureConfig())
        assert d.candidates.tobytes() == expected.tobytes()


def test_a_search_radius_keeps_the_footholds_near_the_gait_nominal_one_as_the_planner_does(
        board, walk):
    from dataclasses import replace

    from footfall.core.state import stance_target

    near = walk_demonstrations(board, ProgressExpert(), np.random.default_rng(3), 8,
                               options=replace(FAST, search_radius=0.03, lead=0.01))
    assert [d.swing_leg for d in near] == [d.swing_leg for d in walk]
    for d in near:
        full = reachable_footholds(board, d.state, LITTLEDOG, SPACING, FeatureConfig())
        target = stance_target(d.state, LITTLEDOG, 0.01)
        inside = np.hypot(*(full[:, :2] - target).T) <= 0.03
        assert 2 <= d.n_candidates == inside.sum() < full.shape[0]  # F: exactly those near
        assert d.candidates.tobytes() == full[inside].tobytes()
    leg = LITTLEDOG.leg(near[0].swing_leg)  # the target: the default stance, lead ahead
    expected = near[0].state.body_position[:2] + np.array(
        [leg.hip[0] + 0.01, leg.side * LITTLEDOG.nominal_foot_y])
    np.testing.assert_allclose(stance_target(near[0].state, LITTLEDOG, 0.01), expected,
                               atol=1e-12)
    with pytest.raises(FootfallError, match="search_radius"):
        collect_demonstrations([board], ProgressExpert(), 4, seed=0, search_radius=-0.01)


def test_walk_is_deterministic_for_a_seed(board):
    def signature(seed):
        demos = walk_demonstrations(board, ProgressExpert(noise=0.05), np.random.default_rng(seed),
                                    5, options=FAST)
        return [(d.state.to_vector().tobytes(), d.candidates.tobytes(), d.chosen) for d in demos]

    first = signature(3)
    assert signature(3) == first
    assert [c for _, _, c in signature(4)] != [c for _, _, c in first]


def test_walk_stops_before_the_far_end(board):
    demos = walk_demonstrations(board, ProgressExpert(), np.random.default_rng(0), 1000,
                                WalkPath(y=0.05),
                                WalkOptions(spacing=SPACING, source="walker:test"))
    stop_x = board.bounds[1] - LITTLEDOG.hip_x - EDGE_MARGIN
    last = demos[-1].state.body_position[0]
    assert last <= stop_x < last + DEFAULT_STRIDE / 4
    assert len(demos) == 9 == estimated_steps(board, None)
    assert {d.source for d in demos} == {"walker:test"}
    assert all(d.state.body_position[1] == 0.05 for d in demos)


def test_x_range_keeps_only_footholds_in_it(board, walk):
    lo, hi = 0.40, 0.50
    kept = walk_demonstrations(board, ProgressExpert(), np.random.default_rng(3), 100,
                               WalkPath(x_range=(lo, hi)), FAST)
    assert kept and all(lo <= d.foothold[0] <= hi for d in kept)
    # The same walk, thinned: the kept steps are the walk's steps in the range.
    in_range = [d for d in walk if lo <= d.foothold[0] <= hi]
    assert [d.state.to_vector().tobytes() for d in kept[:len(in_range)]] == \
        [d.state.to_vector().tobytes() for d in in_range]


def test_record_every_thins_the_same_walk(board, walk):
    thinned = walk_demonstrations(board, ProgressExpert(), np.random.default_rng(3), 2,
                                  WalkPath(record_every=3, record_phase=1), FAST)
    assert [d.state.to_vector().tobytes() for d in thinned] == \
        [walk[k].state.to_vector().tobytes() for k in (1, 4)]
    assert [d.chosen for d in thinned] == [walk[1].chosen, walk[4].chosen]


def test_walk_checks_its_arguments(board):
    expert, rng = ProgressExpert(), np.random.default_rng(0)
    assert walk_demonstrations(board, expert, rng, 0) == []
    with pytest.raises(FootfallError, match="Generator"):
        walk_demonstrations(board, expert, 0, 2)
    with pytest.raises(FootfallError, match="n_max"):
        walk_demonstrations(board, expert, rng, -1)
    with pytest.raises(FootfallError, match="stride"):
        walk_demonstrations(board, expert, rng, 2, options=WalkOptions(stride=0.0))
    with pytest.raises(FootfallError, match="off the terrain"):
        walk_demonstrations(board, expert, rng, 2, WalkPath(y=0.3))
    with pytest.raises(FootfallError, match="x_range"):
        walk_demonstrations(board, expert, rng, 2, WalkPath(x_range=(0.5, 0.4)))
    with pytest.raises(FootfallError, match="record_phase"):
        walk_demonstrations(board, expert, rng, 2, WalkPath(record_every=2, record_phase=2))

    class Wild(ProgressExpert):
        def choose(self, hmap, state, candidates, rng):
            return len(candidates)

    with pytest.raises(FootfallError, match="not an index"):
        walk_demonstrations(board, Wild(), rng, 2, options=FAST)


def test_expert_settings_record_the_config():
    @dataclass(frozen=True)
    class Config:
        noise: float = 0.1
        weights: tuple = (1.0, np.float64(2.0))

    class WithConfig:
        config = Config()

    settings = expert_settings(WithConfig())
    assert settings["config"] == {"noise": 0.1, "weights": [1.0, 2.0]}
    assert settings["class"].endswith("WithConfig")


# ----------------------------------------------------------------- collection
def test_rough_x_range_and_lateral_paths():
    modules = [{"kind": "flat", "x_start": 0.0, "x_end": 0.61},
               {"kind": "rocky", "x_start": 0.61, "x_end": 1.22},
               {"kind": "steps", "x_start": 1.22, "x_end": 1.83},
               {"kind": "flat", "x_start": 1.83, "x_end": 2.44}]
    assert rough_x_range(bumpy(modules=modules)) == (0.61, 1.83)
    assert rough_x_range(bumpy(modules=modules[:1])) is None
    assert rough_x_range(bumpy()) is None
    wide = bumpy(width=0.61)
    assert lateral_paths(wide, 0) == pytest.approx(list(PATH_OFFSETS))
    assert lateral_paths(wide, 1) == pytest.approx([-0.1, 0.0, 0.1])
    assert lateral_paths(wide, 2) == pytest.approx(np.arange(-0.125, 0.13, 0.05))
    narrow = bumpy(width=0.3)  # room for the centre line only
    assert lateral_paths(narrow, 0) == [0.0] and lateral_paths(narrow, 1) == []
    assert lateral_paths(bumpy(width=0.5), 0) == pytest.approx([-0.05, 0.05])


def test_collect_spreads_over_terrains_and_paths():
    boards = [bumpy(length=0.6, width=0.61, seed=1), bumpy(length=0.6, width=0.61, seed=2)]
    demos = collect_demonstrations(boards + boards[:1], ProgressExpert(), 10, seed=5,
                                   spacing=SPACING)
    assert len(demos) == 10
    hashes = [b.content_hash() for b in boards]
    for h in hashes:  # half each, over every lateral path of round 0
        on = [d for d in demos if d.terrain_hash == h]
        assert len(on) == 5
        assert sorted({d.state.body_position[1] for d in on}) == pytest.approx(PATH_OFFSETS)
    again = collect_demonstrations(boards, ProgressExpert(), 10, seed=5, spacing=SPACING)
    assert [(d.terrain_hash, d.state.to_vector().tobytes(), d.chosen) for d in again] == \
        [(d.terrain_hash, d.state.to_vector().tobytes(), d.chosen) for d in demos]


def test_a_few_demonstrations_spread_along_the_path_and_over_the_legs():
    board = bumpy(width=0.61, seed=3)  # nine steps per path: each of 4 walks records one
    demos = collect_demonstrations([board], ProgressExpert(), 4, seed=0, spacing=SPACING)
    assert sorted(d.swing_leg for d in demos) == sorted(LEG_NAMES)
    assert len({d.state.body_position[0] for d in demos}) == 4
    assert min(d.state.body_position[0] for d in demos) > 0.251 + 4 * DEFAULT_STRIDE / 4


def test_collect_returns_what_fits_and_checks_arguments():
    short = bumpy(length=0.55, width=0.61)  # two steps per path
    demos = collect_demonstrations([short], ProgressExpert(), 50, seed=0, spacing=SPACING,
                                   max_rounds=2)
    assert len(demos) == 2 * (len(PATH_OFFSETS) + 3)
    with pytest.raises(FootfallError, match=">= 1"):
        collect_demonstrations([short], ProgressExpert(), 0, seed=0)
    with pytest.raises(FootfallError, match="seed"):
        collect_demonstrations([short], ProgressExpert(), 3, seed=-1)
    with pytest.raises(FootfallError, match="at least one terrain"):
        collect_demonstrations([], ProgressExpert(), 3, seed=0)


def test_with_the_synthetic_expert(board):
    expert_module = pytest.importorskip("footfall.expert.synthetic")
    expert = expert_module.SyntheticExpert()
    demos = walk_demonstrations(board, expert, np.random.default_rng(0), 2, options=FAST)
    assert len(demos) == 2 and demos[0].expert["class"].endswith("SyntheticExpert")
    for d in demos:  # noiseless by default: the best foothold by its own values
        v = expert.values(board, d.state, d.candidates)
        assert v.shape == (d.n_candidates,) and v[d.chosen] == v.max()


# ------------------------------------------------------------------------- CLI
@dataclass(frozen=True)
class FakeExpertConfig:
    noise: float = 0.0
    second_best_prob: float = 0.0


class FakeSyntheticExpert(ProgressExpert):
    """Stands in for footfall.expert.synthetic.SyntheticExpert (same constructor and methods)."""

    calls = 0
    fail_at = None  # raise on this call of choose, to test a command failing mid-walk

    def __init__(self, config=FakeExpertConfig(), robot=LITTLEDOG):
        super().__init__(noise=config.noise)
        self.config = config

    def choose(self, hmap, state, candidates, rng):
        FakeSyntheticExpert.calls += 1
        if FakeSyntheticExpert.calls == self.fail_at:
            raise FootfallError("the expert gave up")
        return super().choose(hmap, state, candidates, rng)


@pytest.fixture
def fake_expert(monkeypatch):
    """The fast stand-in where collect_into_store (``footfall demos collect``) finds the expert."""
    monkeypatch.setattr(collect, "ExpertConfig", FakeExpertConfig)
    monkeypatch.setattr(collect, "SyntheticExpert", FakeSyntheticExpert)
    monkeypatch.setattr(FakeSyntheticExpert, "calls", 0)
    return FakeSyntheticExpert


@pytest.fixture(scope="module")
def terrain_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("demos") / "bumpy.npz"
    bumpy(length=0.6, modules=[{"kind": "flat", "x_start": 0.0, "x_end": 0.3},
                               {"kind": "rocky", "difficulty": 0.6, "x_start": 0.3,
                                "x_end": 0.6}]).save(path)
    return path


def test_collect_appends_and_info_counts(tmp_path, terrain_file, fake_expert, capsys):
    store = tmp_path / "demos.sqlite"
    code, out, _ = run(capsys, "demos", "collect", "--terrain", terrain_file, "--n", 4,
                       "--seed", 0, "-o", store, "--noise", 0.002, "--json")
    assert code == 0
    first = json.loads(out)
    digest = HeightMap.load(terrain_file).content_hash()
    assert (first["added"], first["first_id"], first["last_id"], first["total"]) == (4, 1, 4, 4)
    assert first["added_by_terrain"] == {digest: 4}
    assert first["expert"]["config"] == {"noise": 0.002, "second_best_prob": 0.0}
    # Appends; the terrain is stored once; only footholds on the rocky module by default.
    code, out, _ = run(capsys, "demos", "collect", "--terrain", terrain_file,
                       "-n", 2, "--seed", 1, "-o", store, "--second-best", 0.5)
    assert code == 0 and out.startswith(f"added 2 demonstrations (ids 5..6) to {store}: now 6")
    with DemoStore(store) as s:
        demos = s.demonstrations()
        assert s.terrain_hashes() == [digest]
    assert all(d.foothold[0] >= 0.3 for d in demos)
    assert [d.expert["config"]["second_best_prob"] for d in demos] == [0.0] * 4 + [0.5] * 2
    code, out, _ = run(capsys, "demos", "info", store, "--json")
    info = json.loads(out)
    assert code == 0 and info["demonstrations"] == 6 and info["by_terrain"] == {digest: 6}
    assert info["by_source"] == {"walker": 6}
    assert sum(info["by_leg"].values()) == 6 and set(info["by_leg"]) == set(LEG_NAMES)
    assert info["terrain_info"][digest]["label"] == "flat, rocky:0.6"
    code, out, _ = run(capsys, "demos", "info", store)
    assert code == 0 and out.startswith(f"{store}: 6 demonstrations on 1 terrain")
    assert f"terrain {digest[:12]}       6  flat, rocky:0.6" in out


def test_collect_steps_all_records_the_flat_start(tmp_path, terrain_file, fake_expert, capsys):
    store = tmp_path / "all.sqlite"
    code, out, _ = run(capsys, "demos", "collect", "--terrain", terrain_file, "--n", 4, "--seed",
                       0, "-o", store, "--steps", "all", "--json")
    assert code == 0 and json.loads(out)["added"] == 4
    with DemoStore(store) as s:
        footholds_x = [d.foothold[0] for d in s.demonstrations()]
    assert min(footholds_x) < 0.3 <= max(footholds_x)  # on the flat start and the rocky part


def store_snapshot(path):
    with sqlite3.connect(path) as con:
        rows = con.execute("SELECT * FROM demonstrations ORDER BY id").fetchall()
        terrains = con.execute("SELECT hash FROM terrains").fetchall()
    con.close()
    return path.read_bytes(), rows, terrains


@pytest.fixture(scope="module")
def base_store(tmp_path_factory, terrain_file):
    """A store with two demonstrations on the CLI test terrain."""
    path = tmp_path_factory.mktemp("base") / "demos.sqlite"
    hmap = HeightMap.load(terrain_file)
    demos = walk_demonstrations(hmap, ProgressExpert(), np.random.default_rng(0), 2, options=FAST)
    with DemoStore(path, create=True) as store:
        store.add_demonstrations(demos, terrains=[hmap])
    return path


@pytest.mark.parametrize("args, match", [
    (["demos", "info", "{tmp}/missing.sqlite"], "no such file"),
    (["demos", "info", "{tmp}/text.sqlite"], "not an SQLite database"),
    (["demos", "info", "{tmp}/empty.sqlite"], "empty file"),
    (["demos", "info", "{tmp}/corrupt.sqlite"], "corrupt demonstration store"),
    (["demos", "collect", "--terrain", "{tmp}/missing.npz", "--n", "2", "--seed", "0",
      "-o", "{store}"], "no such file"),
    (["demos", "collect", "--terrain", "{terrain}", "{tmp}/text.sqlite", "--n", "2", "--seed",
      "0", "-o", "{store}"], "not a readable footfall .npz"),
    (["demos", "collect", "--terrain", "{terrain}", "--n", "2", "--seed", "0",
      "-o", "{tmp}/text.sqlite"], "not an SQLite database"),
    (["demos", "collect", "--terrain", "{terrain}", "--n", "2", "--seed", "0",
      "-o", "{tmp}/corrupt.sqlite"], "corrupt demonstration store"),
    (["demos", "collect", "--terrain", "{terrain}", "--n", "0", "--seed", "0", "-o", "{store}"],
     "Invalid value for '-n'"),
    (["demos", "collect", "--terrain", "{terrain}", "--n", "2", "--seed", "0", "-o", "{store}",
      "--second-best", "1.5"], "Invalid value for '--second-best'"),
    (["demos", "collect", "--terrain", "{terrain}", "--n", "2", "--seed", "0",
      "-o", "{tmp}/nowhere/d.sqlite"], "output directory does not exist"),
    (["demos", "collect", "--n", "2", "--seed", "0", "-o", "{store}"], "Missing option"),
])
def test_bad_input_is_one_line_and_leaves_the_store_alone(tmp_path, terrain_file, base_store,
                                                          fake_expert, capsys, args, match):
    store = tmp_path / "demos.sqlite"
    shutil.copyfile(base_store, store)
    (tmp_path / "text.sqlite").write_text("not a store")
    (tmp_path / "empty.sqlite").write_bytes(b"")
    data = store.read_bytes()
    (tmp_path / "corrupt.sqlite").write_bytes(data[:len(data) // 2])
    capsys.readouterr()
    before = store_snapshot(store)
    code, _, err = run(capsys, *[a.format(tmp=tmp_path, store=store, terrain=terrain_file)
                                 for a in args])
    assert_user_error(code, err, match)
    assert fake_expert.calls == 0  # refused before walking
    assert store_snapshot(store) == before
    assert (tmp_path / "text.sqlite").read_text() == "not a store"
    assert not (tmp_path / "missing.sqlite").exists()


def test_collect_failing_mid_walk_changes_nothing(tmp_path, terrain_file, base_store,
                                                  fake_expert, capsys):
    store = tmp_path / "demos.sqlite"
    shutil.copyfile(base_store, store)
    before = store_snapshot(store)

    def collect_failing_at(call, n, out):
        fake_expert.calls, fake_expert.fail_at = 0, call
        try:
            return run(capsys, "demos", "collect", "--terrain", terrain_file, "--n", n,
                       "--seed", 1, "-o", out)
        finally:
            fake_expert.fail_at = None

    code, _, err = collect_failing_at(3, 2, store)  # after a demonstration was collected
    assert_user_error(code, err, "the expert gave up")
    assert store_snapshot(store) == before
    new = tmp_path / "new.sqlite"  # nor is a new store left behind
    code, _, err = collect_failing_at(1, 1, new)
    assert_user_error(code, err, "the expert gave up")
    assert not new.exists()


def test_demos_help(capsys):
    for args in (["demos", "--help"], ["demos", "collect", "--help"], ["demos", "info", "--help"]):
        code, out, _ = run(capsys, *args)
        assert code == 0 and out.startswith("Usage: footfall demos")
        assert ("--json" in out) == (args != ["demos", "--help"])
