"""One fuzz input run under guard: a time limit, a memory limit, its output and warnings captured.

The result is an :class:`Outcome`: ``ok`` (accepted, and the target's checks of the result
passed), ``refused`` (a :class:`~footfall.core.errors.FootfallError` of one line, or exit
status 2 with one line on standard error), or a failure -- ``traceback``, ``hang``,
``memory``, ``garbage`` (accepted, but the result breaks the target's checks, or an input
that must be refused was not), ``multiline`` (a refusal or warning of more than one line).
"""

from __future__ import annotations

import contextlib
import io
import resource
import signal
import traceback
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from footfall.cli.entry import main
from footfall.core.errors import FootfallError

FAILURES = ("traceback", "hang", "memory", "garbage", "multiline")
MEMORY_BUDGET = 3 << 30  # [bytes] address space an input may add before it counts as a blow-up


@dataclass(frozen=True)
class Outcome:
    """How one input ended."""

    target: str  # the loader or command
    kind: str  # "ok", "refused", or one of FAILURES
    detail: str  # the one-line message, or what went wrong
    case: str  # the input, in words (for reproducing a failure)

    @property
    def failed(self) -> bool:
        """Whether the input found a fault."""
        return self.kind in FAILURES


class Garbage(Exception):
    """Raised by a target's check: the input was accepted but the result is not valid."""


class Multiline(Exception):
    """Raised when a refusal or warning takes more (or less) than one line."""


class _Hang(BaseException):
    """Raised by the alarm when an input runs past its time limit."""


@contextlib.contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Interrupt the block (main thread only) after ``seconds`` [s] with :class:`_Hang`."""
    def alarm(signum, frame):  # noqa: ARG001 - the signal handler's signature
        raise _Hang()

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _address_space() -> int:
    """This process's virtual memory size [bytes]."""
    with open("/proc/self/status", encoding="ascii") as f:
        for line in f:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    return 0


@contextlib.contextmanager
def memory_limit(budget: int = MEMORY_BUDGET) -> Iterator[None]:
    """Let the block grow the address space by at most ``budget`` [bytes] (MemoryError beyond)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = _address_space() + budget
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def _last_frame(exc: BaseException) -> str:
    frames = traceback.extract_tb(exc.__traceback__)
    if not frames:
        return ""
    f = frames[-1]
    return f" at {f.filename.rsplit('/', 2)[-1]}:{f.lineno}"


def guarded(target: str, case: str, work: Callable[[], None], seconds: float) -> Outcome:
    """Run ``work`` for one input and classify how it ended.

    ``work`` returns None when the input was accepted and its result checked; raises
    :class:`Garbage` when the result is invalid, :class:`FootfallError` when refused.
    Printed output is swallowed; any warning counts as an extra line.
    """
    def outcome(kind: str, detail: str) -> Outcome:
        return Outcome(target, kind, " ".join(detail.split())[:300], case)

    sink = io.StringIO()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink), \
                    memory_limit(), time_limit(seconds):
                work()
        except FootfallError as exc:
            message = str(exc)
            if "\n" in message.strip() or not message.strip():
                return outcome("multiline", f"message of {len(message.splitlines())} lines: "
                                            f"{message!r}")
            result = outcome("refused", message)
        except Garbage as exc:
            return outcome("garbage", str(exc))
        except Multiline as exc:
            return outcome("multiline", str(exc))
        except _Hang:
            return outcome("hang", f"still running after {seconds:g} s")
        except MemoryError as exc:
            return outcome("memory", f"MemoryError{_last_frame(exc)}")
        except (Exception, SystemExit) as exc:  # noqa: BLE001 - classifying is the point here
            return outcome("traceback", f"{type(exc).__name__}: {exc}{_last_frame(exc)}")
        else:
            result = outcome("ok", "")
    if caught:
        w = caught[0]
        return outcome("multiline", f"warning {w.category.__name__}: {w.message} "
                                    f"({w.filename.rsplit('/', 1)[-1]}:{w.lineno})")
    return result


def cli_work(argv: list[str], must_refuse: bool, cwd: Path | None = None
             ) -> Callable[[], None]:
    """The work of running ``footfall ARGV`` in-process, judged as a user sees it.

    ``cwd``: the working directory to run in (the case's scratch folder), so that a fuzzed
    relative output name lands there and not in the caller's directory.

    Exit 0 is accepted (unless ``must_refuse``: the arguments hold a value the command must
    refuse); exit 2 must come with exactly one line on standard error, and is reported as a
    refusal; any other status or an escaping exception is a failure.
    """
    def work() -> None:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()), \
                contextlib.chdir(cwd if cwd is not None else Path.cwd()):
            code = main(list(argv))
        lines = [line for line in err.getvalue().splitlines() if line.strip()]
        if code == 2:
            if len(lines) != 1 or not lines[0].startswith("footfall: error: "):
                raise Multiline(f"exit 2 with {len(lines)} lines: {' | '.join(lines)[:200]}")
            raise FootfallError(lines[0])
        if code != 0:
            raise Garbage(f"exit status {code}: {' | '.join(lines)[:200]}")
        if must_refuse:
            raise Garbage("accepted an argument it must refuse")

    return work
