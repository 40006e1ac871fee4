"""Helpers for tests that drive the command line in-process."""

from footfall.cli import main


def run(capsys, *args):
    """Run ``footfall ARGS`` in-process; return (exit code, stdout, stderr)."""
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def assert_user_error(code, err, match):
    """A user error: exit 2 and exactly one line on stderr, no traceback."""
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("footfall: error:") and match in lines[0], lines[0]
    assert "Traceback" not in err
