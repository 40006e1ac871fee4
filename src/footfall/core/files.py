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
import tempfile
import zipfile
from pathlib import Path
from typing import Any, Iterator, Literal

import numpy as np

from footfall.core.errors import FootfallError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success."""
    target = Path(path)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise FootfallError(f"output directory does not exist: {directory}")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp" + target.suffix,
                               dir=directory)
    os.close(fd)
    tmp_path = Path(tmp)
    os.chmod(tmp_path, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual permissions
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()


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


def load_npz(path: str | os.PathLike, fmt: str, max_version: int
             ) -> tuple[int, dict[str, np.ndarray], dict[str, Any]]:
    """Load a file written by :func:`save_npz`, checking its format and version.

    Returns ``(version, arrays, meta)``. Raises :class:`FootfallError` for a
    missing, corrupt or truncated file, another format, or a newer version.
    """
    p = Path(path)
    if not p.is_file():
        raise FootfallError(f"no such file: {p}")
    if not zipfile.is_zipfile(p):
        raise FootfallError(f"{p}: not a readable footfall .npz file (not a zip archive)")
    try:
        with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, KeyError) as exc:
        raise FootfallError(f"{p}: not a readable footfall .npz file ({exc})") from None
    try:
        found = str(arrays.pop("format"))
        version = int(arrays.pop("version"))
        meta = json.loads(str(arrays.pop("meta")))
    except (KeyError, ValueError, TypeError):
        raise FootfallError(f"{p}: not a footfall file (no format/version/meta header)") from None
    if found != fmt:
        raise FootfallError(f"{p}: holds a {found!r}, expected a {fmt!r}")
    if version < 1 or version > max_version:
        raise FootfallError(f"{p}: {fmt} version {version} is not supported "
                            f"(this footfall reads versions 1..{max_version})")
    return version, arrays, meta


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


def writable_path(path: str | os.PathLike) -> Path:
    """``path`` as a file to write, refused before any work whose result could not be kept.

    Raises
    ------
    FootfallError
        If ``path`` is a directory or its directory does not exist.
    """
    p = Path(path)
    if p.exists() and p.is_dir():
        raise FootfallError(f"output path is a directory: {p}")
    if not p.parent.exists():
        raise FootfallError(f"output directory does not exist: {p.parent}")
    return p
