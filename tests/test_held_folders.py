"""A folder a command owns is held while it runs: a second command into it -- another process
-- is refused in one line before any work, and a folder left by a killed command is free at
once (the lock goes with its process). Every folder-owning command takes its folder the same
way (``claim_folder``, or ``hold_folder`` for a learning curve)."""

import subprocess
import sys
import textwrap

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.folders import LOCK_NAME, hold_folder, holding_folders, release_folder
from footfall.experiments.runs import claim_folder

HOLDER = textwrap.dedent("""
    import sys, time
    from footfall.core.folders import hold_folder
    hold_folder(sys.argv[1], "a test")
    print("held", flush=True)
    time.sleep(120)
""")


@pytest.fixture
def held(tmp_path):
    """A folder another process holds (killed at the end)."""
    folder = tmp_path / "out"
    folder.mkdir()
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(folder)],
                              stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    yield folder, holder
    holder.kill()
    holder.wait()
    holder.stdout.close()


COMMANDS = [
    ["reproduce", "--quick", "--out", "{out}"],
    ["study", "--quick", "--seeds", "0", "--out", "{out}"],
    ["ablation", "--out", "{out}"],
    ["benchmark-terrain", "--out", "{out}"],
    ["learning-curve", "--out", "{out}"],
    ["student-curve", "{src}", "--out", "{out}"],
]


@pytest.mark.parametrize("args", COMMANDS, ids=[c[0] for c in COMMANDS])
def test_a_second_command_into_a_held_folder_is_refused_in_one_line(held, tmp_path, capsys,
                                                                    args):
    folder, holder = held
    before = sorted(p.name for p in folder.iterdir())
    code, _, err = run(capsys, *[a.format(out=folder, src=tmp_path) for a in args])
    assert_user_error(code, err, f"{folder} is in use")
    assert f"process {holder.pid}" in err
    assert sorted(p.name for p in folder.iterdir()) == before  # nothing written


def test_a_folder_left_by_a_killed_command_is_free_at_once(held):
    folder, holder = held
    with pytest.raises(FootfallError, match="is in use"):
        claim_folder(folder, {"a": 1}, "a test")
    holder.kill()
    holder.wait()
    claim_folder(folder, {"a": 1}, "a test")  # resumable: the lock went with its process
    claim_folder(folder, {"a": 1}, "a test")  # this process holds it already
    assert (folder / LOCK_NAME).read_text().strip().isdigit()
    release_folder(folder)


def test_a_command_lets_go_of_its_folders_when_it_returns(tmp_path):
    @holding_folders
    def command(out):
        hold_folder(out, "a test")
        raise KeyboardInterrupt  # however it ends

    with pytest.raises(KeyboardInterrupt):
        command(tmp_path)
    other = subprocess.run([sys.executable, "-c", HOLDER.replace("time.sleep(120)", ""),
                            str(tmp_path)], capture_output=True, text=True)
    assert other.returncode == 0 and other.stdout.strip() == "held"
