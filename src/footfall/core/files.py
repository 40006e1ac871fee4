"""Atomic, versioned, pickle-free files.

Every file footfall writes goes to a temporary file in the target directory
and is renamed into place, so an interrupted command never leaves a
half-written file. Array files are ``.npz`` archives read with
``allow_pickle=False`` and carry a ``format`` name and a ``version`` number.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import re
import stat
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Iterator, Literal

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.limits import current_limits

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


def save_npz(path: str | os.PathLike, fmt: str, version: int, arrays: dict[str, np.ndarray],
             meta: dict[str, Any]) -> None:
    """Save ``arrays`` and JSON ``meta`` as a self-describing compressed ``.npz``.

    The archive holds ``format`` (a name such as ``footfall.core.heightmap``),
    ``version`` (an integer) and ``meta`` (a JSON string) beside the arrays.
    """
    payload = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
    for reserved in ("format", "version", "meta"):
        if reserved in payload:
            raise ValueError(f"array name {reserved!r} is reserved")
    payload["format"] = np.array(fmt)
    payload["version"] = np.array(version, dtype=np.int64)
    payload["meta"] = np.array(json.dumps(meta, sort_keys=True))
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **payload)


def load_npz(path: str | os.PathLike, fmt: str, max_version: int, *,
             check_member: Callable[[str, tuple[int, ...], np.dtype], None] | None = None,
             allow_nonfinite: bool = False) -> tuple[int, dict[str, np.ndarray], dict[str, Any]]:
    """Load a file written by :func:`save_npz`, checking its format and version.

    Returns ``(version, arrays, meta)``. The archive is inspected before
    anything is inflated (:mod:`footfall.core.npz`): a corrupt, encrypted,
    oversized or foreign file fails before it can allocate more than the
    limits allow. ``check_member(name, shape, dtype)``, if given, may refuse
    an array by raising :class:`FootfallError` before the array is read.
    ``meta`` is strict JSON: NaN and infinity are refused unless
    ``allow_nonfinite`` (for a format that records undefined figures as NaN).

    Raises
    ------
    FootfallError
        Naming the file (and the member or field) for a missing, unreadable,
        corrupt, truncated or oversized file, another format, a newer
        version, or a malformed ``format``/``version``/``meta`` header.
    """
    from footfall.core.npz import read_npz_members

    p = Path(path)
    arrays = read_npz_members(p, check_member)
    header = {}
    for key in ("format", "version", "meta"):
        if key not in arrays:
            raise FootfallError(f"{p}: not a footfall file (no format/version/meta header)")
        header[key] = arrays.pop(key)
    found = _header_string(p, "format", header["format"])
    if found != fmt:
        raise FootfallError(f"{p}: holds a {found!r}, expected a {fmt!r}")
    version = _header_version(p, header["version"])
    if version < 1 or version > max_version:
        raise FootfallError(f"{p}: {fmt} version {version} is not supported "
                            f"(this footfall reads versions 1..{max_version})")
    meta = parse_json_text(_header_string(p, "meta", header["meta"]), f"{p}: meta",
                           allow_nonfinite=allow_nonfinite)
    if not isinstance(meta, dict):
        raise FootfallError(f"{p}: meta must be a JSON object, got {type(meta).__name__}")
    return version, arrays, meta


def _header_string(p: Path, key: str, value: np.ndarray) -> str:
    if value.dtype.kind != "U" or value.ndim != 0:
        raise FootfallError(f"{p}: {key} must be a string, got an array of dtype {value.dtype} "
                            f"and shape {value.shape}")
    return str(value[()])


def _header_version(p: Path, value: np.ndarray) -> int:
    if value.dtype.kind not in "iu" or value.ndim != 0:
        raise FootfallError(f"{p}: version must be an integer, got an array of dtype "
                            f"{value.dtype} and shape {value.shape}")
    return int(value[()])


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number JSON allows")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"number {text} is out of range")
    return value


def json_depth(text: str) -> int:
    """The deepest nesting of lists and objects in JSON ``text``, found without recursion."""
    brackets = re.sub(r'"(?:[^"\\]|\\.)*"', '""', text, flags=re.DOTALL)
    depth = deepest = 0
    for char in re.findall(r"[\[\]{}]", brackets):
        depth += 1 if char in "[{" else -1
        deepest = max(deepest, depth)
    return deepest


def parse_json_text(text: str, what: str, allow_nonfinite: bool = False) -> Any:
    """Strict JSON: bounded length and nesting (the limits), no NaN, infinity or overflow.

    ``allow_nonfinite`` lets NaN and infinity through (for old files that
    record undefined figures so). Raises :class:`FootfallError` naming
    ``what`` for text that is too long, too deeply nested or not strict JSON.
    """
    limits = current_limits()
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > limits.max_metadata_bytes:
        raise FootfallError(f"{what} is {size} bytes long, above the limit of "
                            f"{limits.max_metadata_bytes} (raise it with "
                            f"--limit max_metadata_bytes=N)")
    depth = json_depth(text)
    if depth > limits.max_metadata_depth:
        raise FootfallError(f"{what} is nested {depth} levels deep, above the limit of "
                            f"{limits.max_metadata_depth} (raise it with "
                            f"--limit max_metadata_depth=N)")
    try:
        if allow_nonfinite:
            return json.loads(text)
        return json.loads(text, parse_constant=_refuse_constant, parse_float=_finite_float)
    except (ValueError, RecursionError) as exc:
        raise FootfallError(f"{what} is not valid JSON ({exc})") from None


def plain_json(value: Any, nonfinite: Literal["keep", "null", "error"] = "error",
               other: Literal["error", "repr"] = "error") -> Any:
    """A copy of ``value`` built of JSON types only: dict (str keys), list, str, int, float, bool, None.

    NumPy scalars and arrays become Python numbers and lists, tuples become
    lists, dataclass instances dicts. A non-finite float is kept as it is
    (``"keep"``), becomes None (``"null"``) or fails (``"error"``). Any other
    object fails, or becomes its ``repr`` (``other="repr"``). Failures raise
    :class:`FootfallError`.
    """
    if isinstance(value, dict):
        return {str(k): plain_json(v, nonfinite, other) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain_json(v, nonfinite, other) for v in value]
    if isinstance(value, np.ndarray):
        return plain_json(value.tolist(), nonfinite, other)
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (str, bool, int)):
        return value
    if isinstance(value, float):
        if math.isfinite(value) or nonfinite == "keep":
            return value
        if nonfinite == "null":
            return None
        raise FootfallError(f"not a finite number: {value!r}")
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return plain_json(dataclasses.asdict(value), nonfinite, other)
    if other == "repr":
        return repr(value)
    raise FootfallError(f"not JSON-serialisable: {type(value).__name__}")


def checked_json(value: Any, what: str, object_only: bool = False) -> Any:
    """A private copy of JSON data, checked: only JSON types, no NaN or infinity, keys sorted.

    Raises :class:`FootfallError` naming ``what`` if ``value`` is not such
    data (or, with ``object_only``, not a JSON object).
    """
    try:
        out = json.loads(json.dumps(value, sort_keys=True, allow_nan=False))
    except (TypeError, ValueError, RecursionError) as exc:
        raise FootfallError(f"{what} must be JSON-serialisable without NaN ({exc})") from None
    if object_only and not isinstance(out, dict):
        raise FootfallError(f"{what} must be a JSON object")
    return out


def writable_path(path: str | os.PathLike, suffixes: tuple[str, ...] = (), *, what: str = "",
                  kind: str = "file") -> Path:
    """``path`` as a file to write, refused before any work whose result could not be kept.

    ``suffixes`` (lower case, with the dot, e.g. ``(".mp4",)``), if given, are
    the only file types the writer knows; ``what`` (e.g. ``"--video"``) and
    ``kind`` (e.g. ``"video"``) name the output in messages.

    Raises
    ------
    FootfallError
        If ``path`` is a directory, its directory does not exist or cannot be
        written to, or its suffix is not one of ``suffixes``.
    """
    p = Path(path)
    lead = f"{what}: " if what else ""
    if p.exists() and p.is_dir():
        raise FootfallError(f"{lead}output path is a directory: {p}")
    parent = p.parent
    if not parent.exists():
        raise FootfallError(f"{lead}output directory does not exist: {parent}")
    if not parent.is_dir():
        raise FootfallError(f"{lead}{p}: {parent} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise FootfallError(f"{lead}{p}: cannot write to directory {parent} (permission denied)")
    if suffixes and p.suffix.lower() not in suffixes:
        known = " or ".join(suffixes)
        raise FootfallError(f"{lead}{p}: unknown {kind} format {p.suffix or '(no suffix)'!r} "
                            f"(use {known})")
    return p


def readable_file(path: str | os.PathLike) -> Path:
    """``path`` as an existing regular file this process may read, within ``max_file_bytes``.

    Raises
    ------
    FootfallError
        Naming the file: missing, not a regular file, permission denied, or
        larger than the ``max_file_bytes`` limit.
    """
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise FootfallError(f"no such file: {p}") from None
    except PermissionError:
        raise FootfallError(f"{p}: permission denied") from None
    except OSError as exc:
        raise FootfallError(f"{p}: cannot read ({exc.strerror or exc})") from None
    if not stat.S_ISREG(st.st_mode):
        raise FootfallError(f"{p}: not a regular file")
    if not os.access(p, os.R_OK):
        raise FootfallError(f"{p}: permission denied")
    limit = current_limits().max_file_bytes
    if st.st_size > limit:
        raise FootfallError(f"{p}: the file is {st.st_size} bytes, above the limit of {limit} "
                            f"(raise it with --limit max_file_bytes=N)")
    return p
