"""An expert's settings as a file: e.g. the expert an outcome fit grounded, to walk and teach with.

A JSON object: ``format`` (:data:`FORMAT`), ``version`` (:data:`VERSION`), ``expert`` (every
:class:`~footfall.expert.synthetic.ExpertConfig` setting, as :meth:`Params.to_dict` writes
them) and ``provenance`` (how the settings were found: free JSON). Written atomically.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.core.files import parse_json_text, plain_json
from footfall.expert.synthetic import ExpertConfig, check_judges

FORMAT = "footfall.expert"
VERSION = 1


def save_expert(path: str | os.PathLike, config: ExpertConfig, provenance: dict) -> None:
    """Write ``config`` and its ``provenance`` (plain JSON) to ``path``, atomically; settings
    that judge nothing (every weight 0) are refused, not written."""
    check_judges(config, "the expert to write")
    body = {"format": FORMAT, "version": VERSION, "expert": config.to_dict(),
            "provenance": plain_json(provenance, nonfinite="null")}
    write_text_atomic(path, json.dumps(body, indent=1) + "\n")


def load_expert(path: str | os.PathLike) -> ExpertConfig:
    """The expert settings of the file at ``path``.

    Raises
    ------
    FootfallError
        For a missing or unreadable file, another format or a newer version, or settings
        that are not every :class:`ExpertConfig` field with a valid value.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FootfallError(f"cannot read the expert settings {p}: "
                            f"{getattr(exc, 'strerror', None) or exc}") from None
    data = parse_json_text(text, f"expert settings {p}")
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise FootfallError(f"{p} is not a footfall expert settings file")
    version = data.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or not 1 <= version <= VERSION:
        raise FootfallError(f"{p}: expert settings version {version!r} is not one this footfall "
                            f"reads (1 to {VERSION})")
    try:
        config = ExpertConfig.from_dict(data.get("expert"))
    except FootfallError as exc:
        raise FootfallError(f"{p}: {exc}") from None
    return check_judges(config, f"expert settings {p}")
