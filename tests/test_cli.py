"""The command line: every command, --json, and one-line errors with exit status 2."""

import json
import subprocess
import sys

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.cli import main
from footfall.core.heightmap import HeightMap


@pytest.fixture(scope="module")
def board(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "board.npz"
    assert main(["terrain", "board", "rocky:0.6", "--seed", "3", "-o", str(path)]) == 0
    return path


def test_terrain_make_and_board_json(tmp_path, capsys):
    out = tmp_path / "m.npz"
    code, stdout, _ = run(capsys, "terrain", "make", "logs", "--difficulty", "0.4", "--seed", "1",
                          "-o", str(out), "--json")
    data = json.loads(stdout)
    assert code == 0 and data["shape"] == [610, 610] and data["resolution"] == 0.001
    assert data["metadata"]["modules"][0]["kind"] == "logs"
    assert HeightMap.load(out).content_hash() == data["hash"]
    code, stdout, _ = run(capsys, "terrain", "board", "rocky:0.3", "steps", "--seed", "2",
                          "-o", str(tmp_path / "b.npz"), "--json")
    kinds = [m["kind"] for m in json.loads(stdout)["metadata"]["modules"]]
    assert kinds == ["flat", "rocky", "steps", "flat"]


def test_features_json(board, capsys):
    code, stdout, _ = run(capsys, "features", str(board), "--at", "0.9", "0.02", "--leg", "RF",
                          "--yaw", "0.1", "--json")
    assert code == 0
    data = json.loads(stdout)
    assert len(data["terrain_features"]) == 27 and data["mirrored"] is True
    large = data["patches"]["large"]
    assert large["shape"] == [49, 19] and large["resolution"] == 0.003
    assert np.array(large["heights"]).shape == (49, 19)
    assert large["heights"][24][9] == pytest.approx(0.0)  # relative to the foothold


def test_show_and_import(board, tmp_path, capsys):
    png = tmp_path / "relief.png"
    code, _, _ = run(capsys, "terrain", "show", str(board), "-o", str(png))
    assert code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    arr = tmp_path / "a.npy"
    np.save(arr, np.random.default_rng(0).normal(size=(40, 30)) * 0.01)
    code, stdout, _ = run(capsys, "terrain", "import", str(arr), "--resolution", "0.002",
                          "-o", str(tmp_path / "a.npz"), "--json")
    assert code == 0 and json.loads(stdout)["shape"] == [40, 30]


@pytest.mark.parametrize("args, match", [
    (["terrain", "make", "lava", "--seed", "1", "-o", "{tmp}/x.npz"], "unknown terrain module kind"),
    (["terrain", "make", "rocky", "--difficulty", "2", "--seed", "1", "-o", "{tmp}/x.npz"],
     "difficulty"),
    (["terrain", "make", "rocky", "--seed", "1", "-o", "{tmp}/missing/x.npz"],
     "output directory does not exist"),
    (["terrain", "make", "rocky"], "Missing option"),
    (["terrain", "show", "{tmp}/nothing.npz", "-o", "{tmp}/x.png"], "no such file"),
    (["terrain", "show", "{tmp}/corrupt.npz", "-o", "{tmp}/x.png"], "not a readable"),
    (["terrain", "import", "{tmp}/a.npy", "--resolution", "0", "-o", "{tmp}/x.npz"], "resolution"),
    (["terrain", "import", "{tmp}/a.npy", "--resolution", "-1", "-o", "{tmp}/x.npz"], "resolution"),
    (["terrain", "import", "{tmp}/nan.npy", "--resolution", "0.01", "-o", "{tmp}/x.npz"], "no data"),
    (["terrain", "import", "{tmp}/bad3d.npy", "--resolution", "0.01", "-o", "{tmp}/x.npz"], "2-D"),
    (["features", "{board}", "--at", "5.0", "0.0"], "off the map"),
    (["features", "{board}", "--at", "0.02", "0.0"], "runs off the map"),
    (["features", "{board}", "--at", "0.9", "0.0", "--leg", "XX"], "Invalid value"),
    (["bench", "nothing"], "No such command"),
])
def test_bad_input_is_one_line_and_exit_2(board, tmp_path, capsys, args, match):
    (tmp_path / "corrupt.npz").write_bytes(b"PK\x03\x04 truncated")
    np.save(tmp_path / "a.npy", np.zeros((5, 5)))
    np.save(tmp_path / "nan.npy", np.full((5, 5), np.nan))
    np.save(tmp_path / "bad3d.npy", np.zeros((2, 2, 2)))
    args = [a.format(tmp=tmp_path, board=board) for a in args]
    code, _, err = run(capsys, *args)
    assert_user_error(code, err, match)
    assert not list(tmp_path.glob("x.*"))  # nothing written


def test_help_everywhere(capsys):
    for args in (["--help"], ["terrain", "--help"], ["terrain", "make", "--help"],
                 ["terrain", "board", "--help"], ["terrain", "import", "--help"],
                 ["terrain", "show", "--help"], ["features", "--help"],
                 ["bench", "scoring", "--help"], ["demo", "--help"]):
        code, out, _ = run(capsys, *args)
        assert code == 0 and "Usage:" in out


def test_console_script_errors_without_traceback_and_with_debug(tmp_path):
    cmd = [sys.executable, "-m", "footfall.cli", "terrain", "show", str(tmp_path / "no.npz"),
           "-o", str(tmp_path / "x.png")]
    plain = subprocess.run(cmd, capture_output=True, text=True)
    assert plain.returncode == 2 and plain.stderr.count("\n") == 1
    debug = subprocess.run(cmd[:3] + ["--debug"] + cmd[3:], capture_output=True, text=True)
    assert "Traceback" in debug.stderr


def test_demo_writes_its_pictures_and_report(tmp_path, capsys):
    code, stdout, _ = run(capsys, "demo", "--out", str(tmp_path / "demo"), "--json")
    assert code == 0
    summary = json.loads(stdout)
    for f in summary["files"]:
        assert (tmp_path / "demo" / f.split("/")[-1]).stat().st_size > 0
    for png in ("terrain.png", "reward.png", "features.png", "templates.png"):
        assert (tmp_path / "demo" / png).read_bytes()[:4] == b"\x89PNG"
    assert summary["valid_footholds"] > 0.9 * summary["lattice_points"]
    # The best foothold of the hand-tuned reward is on the rocky part, and better than the worst.
    assert 0.61 <= summary["best_foothold"][0] <= 1.83


def _choices(command, name):
    return next(p.type.choices for p in command.params if p.name == name)


def test_choices_come_from_the_registries(tmp_path, capsys, monkeypatch):
    from footfall.cli import cli
    from footfall.core.robot import LEG_NAMES
    from footfall.data.store import DemoStore
    from footfall.features.family import FEATURE_SETS, register_feature_set
    from footfall.learning import ranker
    from footfall.learning.learner import LEARNERS
    from footfall.terrain import KINDS

    assert _choices(cli.get_command(None, "features"), "leg") == tuple(LEG_NAMES)
    assert _choices(cli.get_command(None, "learn"), "learner") == LEARNERS.names()
    assert _choices(cli.get_command(None, "learn"), "selection") == tuple(ranker.SELECTIONS)
    assert _choices(cli.get_command(None, "terrain").commands["make"], "kind") == tuple(KINDS)
    # Read when used: a learner registered after import is a choice at once.
    huber = ranker.LinearLearner("huber", "for this test", ranker.get_learner("l2").make,
                                 ranker.get_learner("l2").path)
    ranker.register_learner(huber)
    try:
        assert _choices(cli.get_command(None, "learn"), "learner")[-1] == "huber"
    finally:
        LEARNERS.unregister("huber")
    # A feature set registered after import is accepted by --features and listed in --help;
    # family names joined by '+' are accepted too.
    empty = tmp_path / "empty.sqlite"
    DemoStore(empty, create=True).close()
    learn = ["learn", empty, "-o", tmp_path / "m.npz", "--features"]
    code, _, err = run(capsys, *learn, "edges")
    assert_user_error(code, err, "Invalid value for '--features'")
    register_feature_set("edges", ("terrain", "pose"))
    try:
        for features in ("edges", "pose+terrain"):
            code, _, err = run(capsys, *learn, features)
            assert_user_error(code, err, "the store holds no demonstrations")  # past the option
        code, out, _ = run(capsys, "learn", "--help")
        assert code == 0 and "terrain|templates|both|edges" in out
    finally:
        FEATURE_SETS.unregister("edges")


def test_the_command_table_matches_every_commands_own_help():
    """``footfall --help`` prints the table without importing the commands: it must say what
    each command says of itself, and name every command there is."""
    import importlib

    from footfall.cli.root import COMMANDS

    for name, (module, attribute, short) in COMMANDS.items():
        command = getattr(importlib.import_module(module), attribute)
        assert command.name == name
        assert command.get_short_help_str(limit=1000) == short, name


def test_the_help_is_printed_without_importing_the_library(tmp_path):
    """The command list comes from the table: no MuJoCo, scikit-learn or SciPy for --help."""
    import subprocess
    import sys

    code = ("import sys\nfrom footfall.cli import main\nassert main(['--help']) == 0\n"
            "heavy = [m for m in ('mujoco', 'sklearn', 'scipy', 'matplotlib') if m in sys.modules]"
            "\nassert not heavy, heavy\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "walk-many" in done.stdout and "reproduce" in done.stdout
