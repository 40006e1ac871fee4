"""The test difficulty rule on scripted outcomes of the expert (issue 20)."""

import pytest

from footfall.core.errors import FootfallError
from footfall.experiments.difficulty import (
    calibration_held,
    choose_difficulty,
    deciding_levels,
)


def test_the_hardest_level_at_which_the_expert_still_crosses_90_percent():
    outcomes = {0.5: (10, 10), 0.6: (10, 10), 0.7: (9, 10), 0.8: (8, 10), 0.9: (5, 10)}
    choice = choose_difficulty(outcomes, 0.9)
    assert choice.difficulty == 0.7 and choice.met
    assert [v["passes"] for v in choice.levels.values()] == [True, True, True, False, False]
    assert choice.levels["0.8"]["successes"] == 8 and choice.levels["0.8"]["runs"] == 10
    lo, hi = choice.levels["0.8"]["success_ci"]
    assert lo < 0.8 < hi
    assert "90%" in choice.rule


def test_one_unlucky_easy_level_does_not_stop_the_climb():
    """The first default reproduction's calibration: raw, 8 / 10 at 0.6 would stop at 0.5.
    Fitted non-increasing, 0.6-0.8 pool to 27 / 30 = 0.9."""
    outcomes = {0.5: (10, 10), 0.6: (8, 10), 0.7: (9, 10), 0.8: (10, 10), 0.9: (6, 10),
                1.0: (2, 10)}
    choice = choose_difficulty(outcomes, 0.9)
    assert choice.difficulty == 0.8 and choice.met
    fitted = [v["fitted"] for v in choice.levels.values()]
    assert fitted == pytest.approx([1.0, 0.9, 0.9, 0.9, 0.6, 0.2])
    assert [v["success_rate"] for v in choice.levels.values()] == [1.0, 0.8, 0.9, 1.0, 0.6, 0.2]


def test_one_lucky_hard_level_does_not_set_the_difficulty():
    """10 / 10 at 0.8 above two levels of 5 / 10: pooled to 20 / 30, below the threshold."""
    outcomes = {0.5: (10, 10), 0.6: (5, 10), 0.7: (5, 10), 0.8: (10, 10)}
    choice = choose_difficulty(outcomes, 0.9)
    assert choice.difficulty == 0.5
    assert choice.levels["0.8"]["fitted"] == pytest.approx(20 / 30)


def test_levels_are_weighted_by_their_runs():
    """A level of 40 runs outweighs a level of 2 when they are pooled."""
    outcomes = {0.5: (36, 40), 0.6: (2, 2)}  # pooled: 38 / 42 = 0.905
    assert choose_difficulty(outcomes, 0.9).difficulty == 0.6
    outcomes = {0.5: (35, 40), 0.6: (2, 2)}  # pooled: 37 / 42 = 0.881; 0.5 alone 0.875
    assert not choose_difficulty(outcomes, 0.9).met


def test_the_grid_order_is_the_difficulty_not_the_dict_order():
    outcomes = {0.9: (0, 10), 0.5: (10, 10), 0.7: (10, 10)}
    assert choose_difficulty(outcomes).difficulty == 0.7


def test_every_level_passing_gives_the_hardest():
    assert choose_difficulty({0.5: (5, 5), 1.0: (9, 10)}).difficulty == 1.0


def test_the_threshold_is_inclusive():
    assert choose_difficulty({0.5: (9, 10), 0.6: (18, 20)}, 0.9).difficulty == 0.6
    assert choose_difficulty({0.5: (9, 10), 0.6: (17, 20)}, 0.9).difficulty == 0.5


def test_an_expert_failing_already_at_the_easiest_level_is_reported_not_met():
    choice = choose_difficulty({0.5: (6, 10), 0.7: (2, 10)}, 0.9)
    assert choice.difficulty == 0.5 and not choice.met
    assert choice.as_dict()["met"] is False


def test_bad_outcomes_are_refused():
    with pytest.raises(FootfallError, match="at least one"):
        choose_difficulty({})
    with pytest.raises(FootfallError, match="threshold"):
        choose_difficulty({0.5: (1, 1)}, 0.0)
    with pytest.raises(FootfallError, match="successes <= trials"):
        choose_difficulty({0.5: (3, 2)})
    with pytest.raises(FootfallError, match=r"\[0, 1\]"):
        choose_difficulty({1.5: (1, 1)})


def test_whether_the_calibration_held_on_the_test_boards():
    choice = choose_difficulty({0.5: (10, 10), 0.6: (9, 10), 0.7: (6, 10)}).as_dict()
    assert choice["difficulty"] == 0.6
    # the fresh reproduction's case: 9 / 10 in calibration, then 45 / 63 on the test boards
    held = calibration_held(choice, 45, 63)
    lo, hi = choice["levels"]["0.6"]["success_ci"]
    assert held["calibration"] == [9, 10] and held["test"] == [45, 63]
    assert held["inside"] == (lo <= 45 / 63 <= hi)
    assert 0 < held["fisher_p"] <= 1
    same = calibration_held(choice, 56, 63)  # 89 %: the calibration's own rate
    assert same["inside"] and same["fisher_p"] == 1.0
    far = calibration_held(choice, 10, 63)
    assert not far["inside"] and far["fisher_p"] < 0.001
    # a difficulty that was given, not calibrated, or no test runs: nothing to say
    given = {**choice, "difficulty": 0.55}
    assert calibration_held(given, 45, 63) is None
    assert calibration_held(choice, 0, 0) is None


def test_the_levels_the_choice_rests_on_are_walked_until_they_hold_enough_runs():
    first = {0.5: (10, 10), 0.6: (10, 10), 0.7: (9, 10), 0.8: (6, 10), 0.9: (2, 10)}
    assert choose_difficulty(first).difficulty == 0.7
    assert deciding_levels(first, 0.9, 30) == [0.7, 0.8]  # the chosen level and the next harder
    # 0.7 measured better fails the threshold: the choice moves down, and so does the question
    second = {**first, 0.7: (24, 30), 0.8: (17, 30)}
    assert choose_difficulty(second).difficulty == 0.6
    assert deciding_levels(second, 0.9, 30) == [0.6]  # 0.7 holds its 30 already
    third = {**second, 0.6: (28, 30)}
    assert choose_difficulty(third).difficulty == 0.6
    assert deciding_levels(third, 0.9, 30) == []  # decided on 30 runs at both levels


def test_the_hardest_level_passing_needs_only_itself_and_no_level_passing_the_easiest_two():
    assert deciding_levels({0.5: (10, 10), 0.9: (10, 10)}, 0.9, 30) == [0.9]
    assert deciding_levels({0.5: (3, 10), 0.7: (2, 10), 0.9: (0, 10)}, 0.9, 30) == [0.5, 0.7]
