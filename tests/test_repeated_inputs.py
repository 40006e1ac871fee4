"""The same input given twice -- by its name, another path to it or a link -- is refused in one
line before any work, by every command that takes several stores or files: its contents would
otherwise count twice (twice the runs, twice the demonstrations, one model walked twice)."""

import os

import pytest

from cli_helpers import assert_user_error, run
from footfall.data.store import DemoStore
from footfall.terrain import make_board, parse_board_spec


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from test_bad_models import make_model

    folder = tmp_path_factory.mktemp("inputs")
    with DemoStore(folder / "runs.sqlite", create=True):
        pass
    make_board([parse_board_spec("rocky:0.5")], seed=1).save(folder / "board.npz")
    make_model().save(folder / "m.npz")
    os.symlink(folder / "runs.sqlite", folder / "link.sqlite")
    os.link(folder / "m.npz", folder / "hard.npz")
    return folder


CASES = [  # (arguments, what the message names); {f} is the folder of the files
    (["outcomes", "{f}/runs.sqlite", "{f}/runs.sqlite"], "run store"),
    (["outcomes", "{f}/runs.sqlite", "{f}/../{name}/runs.sqlite"], "run store"),
    (["outcomes", "{f}/runs.sqlite", "{f}/link.sqlite"], "run store"),
    (["learn", "--trials", "{f}/runs.sqlite", "--trials", "{f}/link.sqlite", "--features",
      "terrain", "-o", "{f}/o.npz"], "--trials store"),
    (["demos", "correct", "{f}/runs.sqlite", "{f}/runs.sqlite", "-o", "{f}/d.sqlite"],
     "run store"),
    (["demos", "correct", "{f}/runs.sqlite", "{f}/link.sqlite", "--teacher", "rollout", "-o",
      "{f}/d.sqlite"], "run store"),
    (["demos", "collect", "--terrain", "{f}/board.npz", "--terrain", "{f}/board.npz", "-n", "4",
      "--seed", "0", "-o", "{f}/d.sqlite"], "terrain"),
    (["rank-eval", "{f}/m.npz", "{f}/hard.npz", "{f}/runs.sqlite"], "model"),
    (["benchmark-terrain", "--model", "a={f}/m.npz", "--model", "b={f}/hard.npz", "--out",
      "{f}/suite"], "model"),
]


@pytest.mark.parametrize("args, what", CASES, ids=[" ".join(c[0][:2]) + f" {i}"
                                                    for i, c in enumerate(CASES)])
def test_an_input_given_twice_is_refused_in_one_line_before_any_work(files, capsys, args,
                                                                     what):
    before = set(os.listdir(files))
    code, _, err = run(capsys, *[a.format(f=files, name=files.name) for a in args])
    assert_user_error(code, err, f"{what} ")
    assert "is given twice" in err and "would count twice" in err
    assert set(os.listdir(files)) == before  # nothing written
