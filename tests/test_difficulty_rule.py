"""The test difficulty rule on scripted outcomes of the expert (issue 20)."""

import pytest

from footfall.core.errors import FootfallError
from footfall.experiments.difficulty import (
    calibration_held,
    choose_difficulty,
    confirm_choice,
    confirms,
    deciding_levels,
    next_to_confirm,
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


def test_fresh_runs_confirm_a_level_unless_their_interval_stays_below_the_threshold():
    # 95 % Wilson upper ends: 24 / 30 reaches 90 % (90.5 %), 23 / 30 does not (88.3 %)
    assert confirms(24, 30, 0.9) and not confirms(23, 30, 0.9)
    assert confirms(30, 30, 0.9) and not confirms(0, 30, 0.9)


def test_the_choice_is_confirmed_on_fresh_boards_stepping_down_until_one_stands():
    grid = (0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
    # the reproduction's case: 27 / 30 at 1 chose 1 (fitted exactly 90 %)
    choice = choose_difficulty({0.5: (10, 10), 0.6: (9, 10), 0.7: (10, 10), 0.8: (10, 10),
                                0.9: (9, 10), 1.0: (27, 30)})
    assert choice.difficulty == 1.0
    walked = {}
    assert next_to_confirm(choice, grid, walked) == 1.0  # the chosen level first
    walked[1.0] = (20, 30)  # 67 %: not confirmed -> the next easier level, fresh boards
    assert next_to_confirm(choice, grid, walked) == 0.9
    walked[0.9] = (26, 30)  # confirmed: over
    assert next_to_confirm(choice, grid, walked) is None
    done = confirm_choice(choice, walked)
    assert done.difficulty == 0.9 and done.met and done.selected == 1.0
    assert list(done.confirmations) == ["1", "0.9"]  # hardest first
    assert [v["confirmed"] for v in done.confirmations.values()] == [False, True]
    assert "confirmed on fresh boards" in done.rule
    # the test boards are held against the confirmation's runs, not the chosen level's 27 / 30
    held = calibration_held(done.as_dict(), 45, 63)
    assert held["against"] == "confirmation" and held["calibration"] == [26, 30]
    assert calibration_held(choice.as_dict(), 45, 63)["against"] == "calibration"


def test_a_confirmation_that_never_stands_ends_at_the_easiest_level_not_met():
    grid = (0.5, 0.6)
    choice = choose_difficulty({0.5: (10, 10), 0.6: (28, 30)})
    walked = {0.6: (15, 30)}
    assert next_to_confirm(choice, grid, walked) == 0.5
    walked[0.5] = (18, 30)
    assert next_to_confirm(choice, grid, walked) is None  # nothing easier to walk
    done = confirm_choice(choice, walked)
    assert done.difficulty == 0.5 and not done.met
    assert confirm_choice(choice, {}) is choice  # nothing walked: the choice unchanged
