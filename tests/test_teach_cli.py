"""``footfall teach``: bad input is one line and exit 2; the server prints its address, answers
behind the token, and stops cleanly on Ctrl-C."""

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time

import httpx
import pytest

from cli_helpers import assert_user_error, run
from teach_helpers import store_of_runs


def test_a_missing_or_foreign_store_is_one_line(tmp_path, capsys):
    code, _, err = run(capsys, "teach", tmp_path / "none.sqlite")
    assert_user_error(code, err, "no such file")
    (tmp_path / "x.sqlite").write_text("not a store")
    code, _, err = run(capsys, "teach", tmp_path / "x.sqlite")
    assert_user_error(code, err, "not a footfall demonstration store")


def test_a_bad_labeler_or_a_port_in_use_is_one_line(tmp_path, capsys):
    path = store_of_runs(tmp_path / "s.sqlite", runs=1, steps=2)
    code, _, err = run(capsys, "teach", path, "--labeler", "a\tb")
    assert_user_error(code, err, "labeler name")
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        code, _, err = run(capsys, "teach", path, "--port", taken.getsockname()[1])
        assert_user_error(code, err, "cannot listen on 127.0.0.1")


@pytest.mark.parametrize("as_json", [False, True])
def test_the_server_prints_its_address_serves_and_stops_on_ctrl_c(tmp_path, as_json):
    path = store_of_runs(tmp_path / "s.sqlite", runs=1, steps=2)
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "footfall.cli", "teach", str(path),
                             "--labeler", "ada"] + (["--json"] if as_json else []),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        url, deadline = None, time.monotonic() + 60
        while url is None and time.monotonic() < deadline:
            line = proc.stdout.readline()
            if as_json and line.strip():
                started = json.loads(line)
                assert started["host"] == "127.0.0.1" and started["labeler"] == "ada"
                line = started["url"]
            found = re.search(r"http://127\.0\.0\.1:\d+/\?token=[\w-]+", line)
            url = found.group(0) if found else None
        assert url, "no address printed"
        base = url.split("/?")[0]
        assert httpx.get(base + "/api/session").status_code == 401
        session = httpx.get(url.replace("/?", "/api/session?"))
        assert session.json() == {"labeler": "ada", "store": "s.sqlite"}
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
        assert proc.returncode == 0 and "stopped" in out and "Traceback" not in err
        if as_json:  # one JSON line, as the help promises
            assert out.strip().count("\n") == 0 and json.loads(out) == {"stopped": str(path)}
    finally:
        if proc.poll() is None:
            proc.kill()


def test_demos_info_counts_demonstrations_by_source_and_labeler(tmp_path, capsys):
    from footfall.data.store import DemoStore

    path = store_of_runs(tmp_path / "s.sqlite", runs=1, steps=4)
    with DemoStore(path) as store:
        store.add_label(1, 0, "ada", "foothold", 2)
        store.add_label(1, 0, "grace", "foothold", 3)  # they disagree on step 0
        store.add_label(1, 1, "grace", "fine")
    code, out, _ = run(capsys, "demos", "info", path)
    assert code == 0
    assert "sources: human 2" in out
    assert "labeler ada: 1 footholds labelled, 0 choices marked fine" in out
    assert "labeler grace: 1 footholds labelled, 1 choices marked fine" in out
    assert "labelers disagree on 1 step" in out
    code, out, _ = run(capsys, "demos", "info", path, "--json")
    info = json.loads(out)
    assert info["by_source"] == {"human": 2} and info["labels"]["disagreements"] == 1
