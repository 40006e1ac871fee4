"""Versioned, pickle-free files and strict JSON.

Array files are ``.npz`` archives read with ``allow_pickle=False`` (through
:mod:`footfall.core.npz`, inspected before anything is inflated) and carry a
``format`` name and a ``version`` number; they are written atomically
(:mod:`footfall.core.atomic`). JSON is read strictly (bounded, finite) and
written from plain data only.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import sqlite3
import zipfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np

from footfall.core.atomic import atomic_path
from footfall.core.errors import FootfallError
from footfall.core.limits import current_limits
from footfall.core.npz import read_npz_members


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


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name one file: the same inode (through symbolic and hard links) when
    both exist, else the same resolved path."""
    try:
        try:
            return os.path.samefile(a, b)
        except OSError:  # one is missing (or unreadable): compare where they would be
            return os.path.realpath(a) == os.path.realpath(b)
    except ValueError:  # a name the file system cannot hold (NUL, an unpaired surrogate):
        return os.fspath(a) == os.fspath(b)  # no such file exists; only the same text is one


FORMAT_PEEK_BYTES = 1 << 20  # [bytes] the most a file's kind is read from (a JSON file's head)


def footfall_format(path: str | os.PathLike) -> str | None:
    """The footfall kind of the existing file at ``path`` -- the ``format`` a footfall ``.npz``
    archive, store or JSON file names (e.g. ``footfall.model``) -- or None for anything else:
    no such file, another program's file, an unreadable one. Reads a few bytes; never
    changes the file (a store is opened read-only and immutable)."""
    p = Path(path)
    try:
        if not p.is_file():
            return None
        with open(p, "rb") as fh:
            head = fh.read(16)
        if head.startswith(b"PK"):  # a zip archive: an .npz's "format" member
            with zipfile.ZipFile(p) as archive:
                info = archive.getinfo("format.npy")
                if info.file_size > 4096:
                    return None
                with archive.open(info) as member:
                    value = np.lib.format.read_array(member, allow_pickle=False)
            return str(value) if value.dtype.kind == "U" and value.ndim == 0 else None
        if head == b"SQLite format 3\x00":
            con = sqlite3.connect(f"{p.resolve().as_uri()}?mode=ro&immutable=1", uri=True)
            try:
                row = con.execute("SELECT value FROM meta WHERE key = 'format'").fetchone()
            finally:
                con.close()
            return str(row[0]) if row else None
        if head.lstrip()[:1] == b"{":
            with open(p, "rb") as fh:
                data = json.loads(fh.read(FORMAT_PEEK_BYTES))
            kind = data.get("format") if isinstance(data, dict) else None
            return kind if isinstance(kind, str) and kind.startswith("footfall") else None
    except Exception:  # not a file of any kind footfall reads: no kind to protect
        return None
    return None


def distinct_inputs(paths: Iterable[str | os.PathLike], what: str = "input") -> list:
    """``paths`` as given, refused where one file is named twice -- by the same name, another
    path to it, a symbolic or a hard link -- since its contents would count twice.

    Raises
    ------
    FootfallError
        Naming the file given twice, and ``what`` it was given as.
    """
    seen: list = []
    for p in paths:
        for q in seen:
            if same_file(p, q):
                also = "" if os.fspath(p) == os.fspath(q) else f" (also as {q})"
                raise FootfallError(f"{what} {p} is given twice{also}: its contents would "
                                    f"count twice")
        seen.append(p)
    return seen


def writable_path(path: str | os.PathLike, suffixes: tuple[str, ...] = (), *, what: str = "",
                  kind: str = "file", inputs: Iterable[str | os.PathLike | None] = (),
                  writes: str | None = None) -> Path:
    """``path`` as a file to write, refused before any work whose result could not be kept.

    ``suffixes`` (lower case, with the dot, e.g. ``(".mp4",)``), if given, are
    the only file types the writer knows; ``what`` (e.g. ``"--video"``) and
    ``kind`` (e.g. ``"video"``) name the output in messages. ``inputs`` are the
    files the same work reads (None entries are skipped): writing over one of
    them -- by its name, a symbolic link or a hard link -- would destroy it.
    ``writes`` is the footfall kind written (e.g. ``footfall.model``): an existing
    file of another footfall kind (:func:`footfall_format`) is refused, one of
    its own kind may be written over.

    Raises
    ------
    FootfallError
        If ``path`` is a directory, its directory does not exist or cannot be
        written to, its suffix is not one of ``suffixes``, it is one of ``inputs``,
        or it is a footfall file of another kind than ``writes``.
    """
    p = Path(path)
    lead = f"{what}: " if what else ""
    for source in inputs:
        if source is not None and same_file(p, source):
            raise FootfallError(f"{lead}{p} is also an input ({source}): writing it would "
                                f"destroy it; choose another output")
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
    if writes is not None:
        found = footfall_format(p)
        if found is not None and found != writes:
            raise FootfallError(f"{lead}{p} is a {found} file, not a {writes}: writing it "
                                f"would destroy it; choose another output")
    return p
