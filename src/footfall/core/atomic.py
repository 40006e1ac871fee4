"""Atomic writes: a file appears whole or not at all.

Every file footfall writes goes to a temporary file in the target directory
and is renamed into place, so an interrupted command never leaves a
half-written file; the leftovers of a killed writer are removed by the next
write to the same path. The lowest of the file modules: it reads no limits and
no configuration, so that everything above (down to :mod:`footfall.core.params`)
may write with it.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Iterator

from footfall.core.errors import FootfallError

STALE_TEMP_AGE = 3600.0  # [s] a temporary file without a writer's pid older than this is stale


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    The temporary file is ``.NAME.PID.XXXXXXXX.tmpSUFFIX``: it names the writing
    process, so that the next write to ``path`` can remove the leftovers of a
    writer that was killed (:func:`remove_stale_temporaries`) without touching
    the live temporary file of a concurrent writer.
    """
    target = Path(path)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise FootfallError(f"output directory does not exist: {directory}")
    remove_stale_temporaries(target)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.{os.getpid()}.",
                               suffix=".tmp" + target.suffix, dir=directory)
    os.close(fd)
    tmp_path = Path(tmp)
    os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual permissions
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


def _process_alive(pid: int) -> bool:
    """Whether a process ``pid`` runs on this host (one of another user counts as running)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def remove_stale_temporaries(path: str | os.PathLike) -> list[Path]:
    """Remove the temporary files :func:`atomic_path` left beside ``path`` when killed.

    A temporary file of ``path`` is removed when the process named in its name
    no longer runs on this host; one of an older footfall, without a pid, when
    it is older than :data:`STALE_TEMP_AGE`. A live writer's file is never
    touched. Returns the files removed; files that cannot be removed are left.
    """
    target = Path(path)
    directory = target.parent if str(target.parent) else Path(".")
    pattern = re.compile(rf"\.{re.escape(target.name)}\.(?:(\d+)\.)?[A-Za-z0-9_]+"
                         rf"\.tmp{re.escape(target.suffix)}")
    removed = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    now = time.time()
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or not entry.is_file(follow_symlinks=False):
            continue
        try:
            if match.group(1) is not None:
                stale = not _process_alive(int(match.group(1)))
            else:
                stale = now - entry.stat(follow_symlinks=False).st_mtime > STALE_TEMP_AGE
            if stale:
                os.unlink(entry.path)
                removed.append(Path(entry.path))
        except OSError:
            continue
    return removed


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")

