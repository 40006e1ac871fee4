"""A folder an experiment owns, held while it runs.

A command that owns an output folder (a reproduction, a study, a learning curve, a terrain
suite...) resumes what the folder holds; two of them at once would both walk and store the
same runs, and the folder would hold everything twice. So the folder is held for the
command's run: :func:`hold_folder` takes an exclusive advisory lock (``flock``) on a file in
it, and a second command -- another process -- is refused in one line. The operating system
lets the lock go when its process ends however it ends, so a folder left by a killed run is
resumable at once, never locked for ever. Within one process a folder is held once (a
command that opens its folder again holds it already); :func:`holding_folders` lets go of
the folders a call took when it returns.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path
from typing import Callable, TypeVar

from footfall.core.errors import FootfallError

try:
    import fcntl
except ImportError:  # no flock (Windows): folders are not held
    fcntl = None

LOCK_NAME = ".footfall-lock"  # the file in a held folder: the holder's process id
_HELD: dict[str, int] = {}  # the real path of each folder this process holds -> its lock's fd

F = TypeVar("F", bound=Callable)


def hold_folder(out: str | os.PathLike, what: str) -> None:
    """Hold the existing folder ``out`` for this process (``what`` it holds, e.g. "a
    reproduction", names it in the message), or refuse.

    Raises
    ------
    FootfallError
        If another process holds it.
    """
    key = os.path.realpath(out)
    if fcntl is None or key in _HELD:
        return
    path = Path(out) / LOCK_NAME
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
        os.close(fd)
        raise FootfallError(f"{out} is in use: another footfall command (process {holder}) is "
                            f"running {what} in it; wait for it to end, or use another "
                            f"folder") from None
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    _HELD[key] = fd


def release_folder(out: str | os.PathLike) -> None:
    """Let go of the folder ``out`` if this process holds it."""
    fd = _HELD.pop(os.path.realpath(out), None)
    if fd is not None:
        os.close(fd)  # the lock goes with its file


def holding_folders(func: F) -> F:
    """Decorate a command's run: the folders it takes are let go when it returns or raises."""
    @functools.wraps(func)
    def run(*args, **kwargs):
        before = set(_HELD)
        try:
            return func(*args, **kwargs)
        finally:
            for key in set(_HELD) - before:
                release_folder(key)
    return run  # type: ignore[return-value]
