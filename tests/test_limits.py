"""Size limits (issue 17): defaults, raising one on the command line or in the environment."""

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.limits import Limits, check_cells, check_count, current_limits, use_limits


def test_a_count_above_the_limit_is_refused_and_the_limit_can_be_raised():
    with use_limits(Limits(max_count=10)):
        assert check_count(10, "runs") == 10
        with pytest.raises(FootfallError, match="runs = 11 is above the limit of 10"):
            check_count(11, "runs")
    with pytest.raises(FootfallError, match="whole number"):
        check_count(True, "runs")
    with pytest.raises(FootfallError, match=">= 1"):
        check_count(0, "runs", minimum=1)


def test_cells_are_counted_before_allocating():
    with use_limits(Limits(max_map_cells=100)):
        check_cells((10, 10), "a map")
        with pytest.raises(FootfallError, match="a map would have 110 cells"):
            check_cells((11, 10), "a map")


def test_the_environment_raises_a_limit(monkeypatch):
    monkeypatch.setenv("FOOTFALL_MAX_COUNT", "250000")
    assert current_limits().max_count == 250_000
    monkeypatch.setenv("FOOTFALL_MAX_COUNT", "lots")
    with pytest.raises(FootfallError, match="FOOTFALL_MAX_COUNT: limit max_count must be a number"):
        current_limits()


def test_limit_on_the_command_line_holds_for_that_command_only(capsys, tmp_path):
    out = tmp_path / "m.npz"
    code, _, err = run(capsys, "--limit", "max_map_cells=1000", "terrain", "make", "flat",
                       "--seed", "0", "-o", out)
    assert_user_error(code, err, "above the limit of 1000")
    assert current_limits().max_map_cells == Limits().max_map_cells
    code, _, err = run(capsys, "--limit", "max_cells=5", "terrain", "make", "flat", "--seed", "0",
                       "-o", out)
    assert_user_error(code, err, "unknown limit 'max_cells'")
    code, _, err = run(capsys, "--limit", "max_count", "terrain", "make", "flat", "--seed", "0",
                       "-o", out)
    assert_user_error(code, err, "--limit takes NAME=VALUE")
