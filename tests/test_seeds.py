"""Named seed streams: the same name gives the same seed, and no two purposes or seeds collide."""

from itertools import combinations

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.seeds import PURPOSES, SeedStreams
from footfall.experiments.offline import OfflineConfig
from footfall.experiments.reproduce import ReproduceConfig
from footfall.experiments.workspace import (
    confirmation_board_count,
    most_calibration_boards,
    planned_seeds,
)


def test_a_stream_gives_the_same_seed_for_the_same_name_and_index():
    a, b = SeedStreams("reproduce", 3), SeedStreams("reproduce", 3)
    assert a.seed_for("evaluation runs", 4) == b.seed_for("evaluation runs", 4)
    assert a.seeds("sweep runs", 5) == [a.seed_for("sweep runs", k) for k in range(5)]
    x = a.generator("learning").random(3)
    np.testing.assert_array_equal(x, b.generator("learning").random(3))
    assert all(0 <= s < 2 ** 63 for s in a.seeds("boards", 50))


def test_experiments_seeds_purposes_and_indices_are_independent_streams():
    seeds = {
        (experiment, seed, purpose, index): SeedStreams(experiment, seed).seed_for(purpose, *index)
        for experiment in ("reproduce", "offline") for seed in (0, 1, 1000)
        for purpose in PURPOSES for index in ((), (0,), (1,), (0, 1), (1, 0))}
    assert len(set(seeds.values())) == len(seeds)  # arithmetic offsets would collide here


def test_bad_names_and_seeds_are_refused():
    with pytest.raises(FootfallError, match="unknown seed purpose 'runs'"):
        SeedStreams("reproduce", 0).seed_for("runs")
    with pytest.raises(FootfallError, match="unknown experiment"):
        SeedStreams("walk", 0)
    for bad in (-1, 1.5, True, "0"):
        with pytest.raises(FootfallError, match="integer >= 0"):
            SeedStreams("reproduce", bad)
    with pytest.raises(FootfallError, match="indices"):
        SeedStreams("reproduce", 0).seed_for("boards", -1)


@pytest.mark.parametrize("make", [ReproduceConfig, ReproduceConfig.quick])
def test_two_reproduction_seeds_share_no_board_seed_and_no_run_seed(make):
    planned = {seed: planned_seeds(make(seed=seed)) for seed in (0, 1, 2, 5)}
    for seed, by_purpose in planned.items():
        every = [s for seeds in by_purpose.values() for s in seeds]
        assert len(every) == len(set(every)), f"seed {seed}: two purposes share a seed"
        c = make(seed=seed)  # training, flat, test, and per grid level sweep and calibration
        cal = most_calibration_boards(c)  # every board a level may get, the rule's extra ones too
        assert cal == max(c.calibration_boards, -(-c.calibration_level_runs // c.calibration_runs))
        confirm = confirmation_board_count(c)  # fresh boards that may confirm each level
        assert confirm * c.calibration_runs >= c.confirmation_runs
        assert len(by_purpose["boards"]) == len(c.train_boards) + 1 + c.test_boards + \
            len(c.difficulties) * (1 + cal + confirm)
        # every calibration and confirmation board has run seeds of its own (not the same few
        # on every board)
        assert len(set(by_purpose["calibration runs"])) == \
            len(c.difficulties) * cal * c.calibration_runs
        assert len(set(by_purpose["confirmation runs"])) == \
            len(c.difficulties) * confirm * c.calibration_runs
    for (a, pa), (b, pb) in combinations(planned.items(), 2):
        for purpose in pa:
            assert not set(pa[purpose]) & set(pb[purpose]), \
                f"reproduction seeds {a} and {b} share {purpose} seeds"
        run_purposes = ("correction runs", "calibration runs", "confirmation runs",
                        "evaluation runs", "sweep runs")
        runs_a = {s for p in run_purposes for s in pa[p]}
        runs_b = {s for p in run_purposes for s in pb[p]}
        assert not runs_a & runs_b  # not even across purposes (seed 5's corrections, 0's eval)


def test_two_offline_seeds_share_no_board():
    a, b = OfflineConfig(seed=0).boards(), OfflineConfig(seed=1).boards()
    seeds_a = [s for split in a.values() for _, _, s in split]
    seeds_b = [s for split in b.values() for _, _, s in split]
    assert len(set(seeds_a)) == len(seeds_a) and not set(seeds_a) & set(seeds_b)
