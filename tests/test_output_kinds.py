"""An output that is an existing file of another kind is refused in one line before any work,
and the file is left as it was; a writer may write over a file of its own kind. Each writer
has its own suffix, and a footfall file says its kind (footfall.core.files.footfall_format)."""

import hashlib
import json
import shutil

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.files import footfall_format
from footfall.data.store import DemoStore
from footfall.terrain import make_board, parse_board_spec


@pytest.fixture(scope="module")
def kinds(tmp_path_factory):
    """One file of every footfall kind, and a JSON file of another program."""
    from test_bad_models import make_model

    folder = tmp_path_factory.mktemp("kinds")
    make_board([parse_board_spec("rocky:0.5")], seed=1).save(folder / "board.npz")
    make_model().save(folder / "model.npz")
    with DemoStore(folder / "store.sqlite", create=True):
        pass
    (folder / "curve.json").write_text(json.dumps({"format": "footfall.learning-curve"}))
    (folder / "other.json").write_text(json.dumps({"format": "something else"}))
    return folder


def test_every_kind_says_what_it_is(kinds):
    assert footfall_format(kinds / "board.npz") == "footfall.heightmap"
    assert footfall_format(kinds / "model.npz") == "footfall.model"
    assert footfall_format(kinds / "store.sqlite") == "footfall.demostore"
    assert footfall_format(kinds / "curve.json") == "footfall.learning-curve"
    assert footfall_format(kinds / "other.json") is None  # not footfall's: nothing to protect
    assert footfall_format(kinds / "missing.npz") is None


CASES = [  # (command with {out} the output, the existing file it is given, what the message says)
    (["learn", "{f}/store.sqlite", "--features", "terrain", "-o", "{out}"], "board.npz",
     "is a footfall.heightmap file, not a footfall.model"),
    (["terrain", "make", "rocky", "--seed", "1", "-o", "{out}"], "model.npz",
     "is a footfall.model file, not a footfall.heightmap"),
    (["terrain", "board", "rocky:0.5", "--seed", "1", "-o", "{out}"], "model.npz",
     "is a footfall.model file, not a footfall.heightmap"),
    (["terrain", "import", "{f}/board.npz", "-o", "{out}"], "model.npz",
     "is a footfall.model file, not a footfall.heightmap"),
    (["outcomes", "{f}/store.sqlite", "--fit", "slid", "-o", "{out}"], "store.sqlite",
     "unknown expert settings format '.sqlite'"),
    (["outcomes", "{f}/store.sqlite", "--fit", "slid", "-o", "{out}"], "model.npz",
     "unknown expert settings format '.npz'"),
    (["outcomes", "{f}/store.sqlite", "--fit", "slid", "-o", "{out}"], "curve.json",
     "is a footfall.learning-curve file, not a footfall.expert"),
]


@pytest.mark.parametrize("args, existing, match", CASES,
                         ids=[f"{' '.join(c[0][:2])} over {c[1]}" for c in CASES])
def test_an_output_of_another_kind_is_refused_and_left_as_it_was(kinds, tmp_path, capsys,
                                                                 args, existing, match):
    target = tmp_path / existing
    shutil.copy(kinds / existing, target)
    digest = hashlib.sha256(target.read_bytes()).hexdigest()
    code, _, err = run(capsys, *[a.format(f=kinds, out=target) for a in args])
    assert_user_error(code, err, match)
    assert hashlib.sha256(target.read_bytes()).hexdigest() == digest


def test_a_writer_writes_over_a_file_of_its_own_kind(kinds, tmp_path, capsys):
    target = tmp_path / "board.npz"
    shutil.copy(kinds / "board.npz", target)
    code, _, err = run(capsys, "terrain", "make", "rocky", "--seed", "2", "-o", target)
    assert code == 0, err
    assert footfall_format(target) == "footfall.heightmap"
