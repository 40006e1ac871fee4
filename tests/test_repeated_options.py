"""An option that takes one value, given twice, is refused in one line (click would take the
last without a word, and which one the user meant is unknown); a repeatable option stays
repeatable. Matplotlib's warnings about a character its font cannot draw do not reach the
command's standard error."""

import pytest

from cli_helpers import assert_user_error, run
from footfall.terrain import make_board, parse_board_spec

CASES = [
    ["terrain", "make", "rocky", "--seed", "1", "--seed", "2", "-o", "{f}/x.npz"],
    ["terrain", "make", "rocky", "--seed=1", "--seed", "2", "-o", "{f}/x.npz"],
    ["terrain", "make", "rocky", "--seed", "1", "-o", "{f}/x.npz", "--output", "{f}/y.npz"],
    ["rank-eval", "--reward", "hand-tuned", "--reward", "expert", "{f}/s.sqlite"],
    ["walk-many", "--terrain", "{f}/b.npz", "--terrain", "{f}/b.npz", "--runs", "1"],
    ["demos", "correct", "{f}/s.sqlite", "-o", "{f}/d.sqlite", "--every-step", "--every-step"],
    ["reproduce", "--quick", "--quick", "--out", "{f}/r"],
]


@pytest.mark.parametrize("args", CASES, ids=[" ".join(c[:2]) + f" {i}"
                                             for i, c in enumerate(CASES)])
def test_an_option_given_twice_is_refused_in_one_line(tmp_path, capsys, args):
    code, _, err = run(capsys, *[a.format(f=tmp_path) for a in args])
    assert_user_error(code, err, "is given twice: give it once")
    assert list(tmp_path.iterdir()) == []  # nothing made


def test_a_repeatable_option_stays_repeatable(tmp_path, capsys):
    code, _, err = run(capsys, "terrain", "board", "rocky:0.5", "flat", "--seed", "1", "-o",
                       tmp_path / "b.npz")
    assert code == 0, err
    code, _, err = run(capsys, "--limit", "max_count=100000", "--limit", "max_count=200000",
                       "terrain", "make", "flat", "--seed", "1", "-o", tmp_path / "f.npz")
    assert code == 0, err


def test_a_name_the_font_cannot_draw_warns_nothing_on_stderr(tmp_path, capsys):
    board = tmp_path / "\N{GRINNING FACE}\N{CJK UNIFIED IDEOGRAPH-5730}.npz"
    make_board([parse_board_spec("rocky:0.5")], seed=1).save(board)
    code, _, err = run(capsys, "terrain", "show", board, "-o", tmp_path / "r.png")
    assert code == 0 and err == "", err
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
