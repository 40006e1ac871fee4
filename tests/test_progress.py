"""Progress of a batch: lines in a log (not a terminal), a bar on a terminal, nothing when quiet."""

import io

import pytest

from footfall.core.progress import BatchProgress, duration_text, progress_line


class Clock:
    """A clock the test moves [s]."""

    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


class Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("seconds, text", [(0, "0 s"), (42.4, "42 s"), (59.6, "1 min 00 s"),
                                           (723, "12 min 03 s"), (3900, "1 h 05 min"),
                                           (-3, "0 s")])
def test_durations_read_as_a_person_says_them(seconds, text):
    assert duration_text(seconds) == text


def test_a_line_says_done_failed_elapsed_and_time_left():
    assert (progress_line("evaluation", 30, 120, 4, 600.0) ==
            "evaluation: 30 / 120 runs done, 4 failed, 10 min 00 s elapsed, "
            "about 30 min 00 s left")
    # nothing left to estimate at the end; no failure count where items do not fail
    assert progress_line("collect", 5, 5, None, 12.0, unit="demo") == \
        "collect: 5 / 5 demos done, 12 s elapsed"


def test_in_a_log_a_line_every_twentieth_of_the_batch_and_at_the_end():
    log, clock = io.StringIO(), Clock()
    bar = BatchProgress(45, "runs", stream=log, clock=clock)
    for i in range(45):
        clock.t += 10.0
        bar.update(failed=i % 9 == 0)
    bar.close()
    lines = log.getvalue().splitlines()
    assert bar.every == 3 and len(lines) == 15  # after 3, 6, ..., 45
    assert lines[0] == "runs: 3 / 45 runs done, 1 failed, 30 s elapsed, about 7 min 00 s left"
    assert lines[-1] == "runs: 45 / 45 runs done, 5 failed, 7 min 30 s elapsed"


def test_in_a_log_a_slow_batch_still_prints_a_line_every_interval():
    log, clock = io.StringIO(), Clock()
    bar = BatchProgress(1000, "ablation runs", stream=log, clock=clock, interval=60.0)
    for _ in range(3):  # far fewer than every = 50 runs, but minutes apart
        clock.t += 61.0
        bar.update(failed=False)
    assert [line.split(",")[0] for line in log.getvalue().splitlines()] == [
        "ablation runs: 1 / 1000 runs done", "ablation runs: 2 / 1000 runs done",
        "ablation runs: 3 / 1000 runs done"]


def test_quiet_or_no_lines_prints_nothing_and_a_terminal_gets_a_bar_not_lines():
    quiet = io.StringIO()
    bar = BatchProgress(4, "runs", quiet=True, stream=quiet)
    for _ in range(4):
        bar.update(failed=False)
    bar.close()
    assert quiet.getvalue() == ""
    short = io.StringIO()  # a short batch that asks for no lines in a log (demos collect)
    bar = BatchProgress(4, "collect", unit="demo", lines=False, stream=short)
    for _ in range(4):
        bar.update()
    bar.close()
    assert short.getvalue() == ""
    terminal = Terminal()
    bar = BatchProgress(4, "runs", stream=terminal)
    for _ in range(4):
        bar.update(failed=True)
    bar.close()
    shown = terminal.getvalue()
    assert "4/4" in shown and "failed=4" in shown  # tqdm's bar, redrawn with \r
    assert "runs done" not in shown
