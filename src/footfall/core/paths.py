"""A file to read, checked before it is opened: it exists, is a regular file, and is small enough.

Every reader (:mod:`footfall.core.npz` for archives, :mod:`footfall.terrain.scans` for scans)
asks :func:`readable_file` first, so a missing, unreadable or oversized file fails with one
line naming it, against the ``max_file_bytes`` limit (:mod:`footfall.core.limits`).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from footfall.core.errors import FootfallError
from footfall.core.limits import current_limits


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
    except ValueError:  # a name the file system cannot hold (NUL, an unpaired surrogate)
        raise FootfallError(f"{ascii(str(p))}: not a file name this system can hold") from None
    if not stat.S_ISREG(st.st_mode):
        raise FootfallError(f"{p}: not a regular file")
    if not os.access(p, os.R_OK):
        raise FootfallError(f"{p}: permission denied")
    limit = current_limits().max_file_bytes
    if st.st_size > limit:
        raise FootfallError(f"{p}: the file is {st.st_size} bytes, above the limit of {limit} "
                            f"(raise it with --limit max_file_bytes=N)")
    return p
