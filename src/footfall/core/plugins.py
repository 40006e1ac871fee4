"""Plugins: other packages' feature families, learners and terrain kinds, found at run time.

A package adds parts to footfall by registering them when one of its modules
is imported (``register_family``, ``register_learner``, ``register_kind``)
and naming that module as an entry point of the group ``footfall.plugins``
in its own ``pyproject.toml``::

    [project.entry-points."footfall.plugins"]
    craters = "mypackage.footfall_parts"

Every registry loads the plugins before it answers, so the command line and
its worker processes (which read model files) see the same parts.
"""

from __future__ import annotations

import importlib.metadata
import threading

from footfall.core.errors import FootfallError

GROUP = "footfall.plugins"  # the entry-point group that names plugin modules
_loaded: list[str] = []  # names of the plugin entry points imported in this process
_lock = threading.Lock()
_done = False


def _entry_points() -> list[importlib.metadata.EntryPoint]:
    return sorted(importlib.metadata.entry_points(group=GROUP), key=lambda e: e.name)


def load_plugins() -> list[str]:
    """Import every plugin module once per process; return the names of those imported.

    Raises :class:`FootfallError` naming the plugin whose import failed.
    """
    global _done
    if _done:
        return list(_loaded)
    with _lock:
        if not _done:
            _done = True  # before importing: a plugin's own registry calls must not recurse
            for entry in _entry_points():
                try:
                    entry.load()
                except Exception as exc:  # a broken plugin is the user's error, said in a line
                    raise FootfallError(f"footfall plugin {entry.name!r} ({entry.value}) "
                                        f"failed to load: {exc!r}") from None
                _loaded.append(entry.name)
    return list(_loaded)
