"""The browser that drives the teaching page in tests and ``footfall bench teach``: Debian's
Chromium under Playwright, headless, WebGL in software (SwiftShader)."""

from __future__ import annotations

import os
import shutil

from footfall.core.errors import FootfallError

FLAGS = ["--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run"]


def chromium_path() -> str | None:
    """Chromium's executable: ``$FOOTFALL_CHROMIUM``, else ``chromium`` or ``chromium-browser``
    on the PATH; None if there is none."""
    return os.environ.get("FOOTFALL_CHROMIUM") or shutil.which("chromium") \
        or shutil.which("chromium-browser")


def require_browser() -> str:
    """Chromium's executable, refused with one line when Chromium or Playwright is missing."""
    path = chromium_path()
    if path is None:
        raise FootfallError("no Chromium: install Debian's chromium (apt-get install chromium) "
                            "or set FOOTFALL_CHROMIUM")
    try:
        import playwright  # noqa: F401
    except ImportError:
        raise FootfallError("Playwright is missing: pip install 'footfall[test]'") from None
    return path
