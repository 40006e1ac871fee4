"""Progress of a batch of runs: a bar on a terminal, a line every few runs in a log.

A reproduction or an ablation walks for many minutes. On a terminal a bar
(tqdm) shows it; when standard error goes to a file or a pipe (``make run >
log``, CI) a bar is useless, so :class:`BatchProgress` prints a plain line
instead -- done, failed, elapsed, an estimate of the time left -- every
``every`` items (about twenty lines a batch) or every ``interval`` seconds,
whichever comes first, and one at the end.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

from tqdm import tqdm

LINES_PER_BATCH = 20  # [-] about this many lines for a batch, plus the last
INTERVAL = 60.0  # [s] a line at least this often while items finish


def duration_text(seconds: float) -> str:
    """``seconds`` [s] as ``"1 h 05 min"``, ``"12 min 03 s"`` or ``"42 s"``."""
    s = max(0, round(seconds))
    if s >= 3600:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    if s >= 60:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s} s"


def progress_line(desc: str, done: int, total: int, failed: int | None, elapsed: float,
                  unit: str = "run") -> str:
    """One line of a batch's progress; ``elapsed`` [s]; ``failed`` None where nothing fails."""
    parts = [f"{desc}: {done} / {total} {unit}s done"]
    if failed is not None:
        parts.append(f"{failed} failed")
    parts.append(f"{duration_text(elapsed)} elapsed")
    if 0 < done < total:
        parts.append(f"about {duration_text(elapsed / done * (total - done))} left")
    return ", ".join(parts)


class BatchProgress:
    """Counts a batch's items as they finish (:meth:`update`); :meth:`close` at the end.

    ``stream`` a terminal (and not ``quiet``): a tqdm bar. Otherwise, unless
    ``quiet`` or not ``lines``: a :func:`progress_line` after every ``every`` items (default
    about a twentieth of ``total``), whenever ``interval`` [s] has passed
    since the last line, and after the last item. ``clock`` [s] is for tests;
    ``started`` [s, on ``clock``]: when the batch began, if before this progress opened.
    """

    def __init__(self, total: int, desc: str, unit: str = "run", quiet: bool = False,
                 lines: bool = True, stream: TextIO | None = None, every: int | None = None,
                 interval: float = INTERVAL, clock: Callable[[], float] = time.monotonic,
                 started: float | None = None):
        self.total, self.desc, self.unit = int(total), desc, unit
        self.stream = sys.stderr if stream is None else stream
        self.every = max(1, every if every is not None else -(-self.total // LINES_PER_BATCH))
        self.interval, self.clock = float(interval), clock
        self.done, self.failed, self._counts_failures = 0, 0, False
        self._start = self._last = clock() if started is None else started
        self._printed_at = 0  # items done at the last line
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._lines = lines and not quiet and not tty
        self._bar = None
        if not quiet and tty:
            self._bar = tqdm(total=self.total, unit=unit, desc=desc, file=self.stream,
                             dynamic_ncols=True)

    def update(self, failed: bool | None = None) -> None:
        """One more item finished; ``failed`` True/False where items can fail (runs)."""
        self.done += 1
        if failed is not None:
            self._counts_failures = True
            self.failed += bool(failed)
        if self._bar is not None:
            self._bar.update(1)
            if self._counts_failures:
                self._bar.set_postfix(failed=self.failed, refresh=False)
            return
        now = self.clock()
        if self._lines and (self.done - self._printed_at >= self.every or self.done >= self.total
                            or now - self._last >= self.interval):
            self._print(now)

    def _print(self, now: float) -> None:
        failed = self.failed if self._counts_failures else None
        line = progress_line(self.desc, self.done, self.total, failed, now - self._start,
                             self.unit)
        self.stream.write(line + "\n")
        self.stream.flush()
        self._last, self._printed_at = now, self.done

    def close(self) -> None:
        """Close the bar (a line-printing progress has printed its last line already)."""
        if self._bar is not None:
            self._bar.close()
