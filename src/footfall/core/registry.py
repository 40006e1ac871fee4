"""Named parts of one kind: the one registry type every extension point uses.

Feature families, learners, scorers, terrain kinds, executors and controller
variants each live in a :class:`Registry`. A part registers under a name
(``REGISTRY.register("name", part)``, or as a decorator); a lookup loads the
plugins first (:mod:`footfall.core.plugins`), so a part from another package
is found the same way, and an unknown name is one clear error that lists the
choices.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Generic, TypeVar, overload

from footfall.core.errors import FootfallError
from footfall.core.plugins import load_plugins

T = TypeVar("T")


class Registry(Generic[T]):
    """Parts of one kind by name, in the order they registered.

    Parameters
    ----------
    kind : str
        What a part is, for messages ("learner", "terrain kind").
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._parts: dict[str, T] = {}

    @overload
    def register(self, name: str) -> Callable[[T], T]: ...

    @overload
    def register(self, name: str, part: T) -> T: ...

    def register(self, name, part=None):
        """Register ``part`` under ``name`` and return it; without ``part``, a decorator.

        Registering the same object twice is harmless; another object under a
        taken name is an error (a plugin must not silently replace a part).
        """
        if part is None:
            return lambda p: self.register(name, p)
        if not isinstance(name, str) or not name:
            raise ValueError(f"a {self.kind} needs a non-empty name, got {name!r}")
        if name in self._parts and self._parts[name] is not part:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._parts[name] = part
        return part

    def unregister(self, name: str) -> None:
        """Remove a part (tests that register a part of their own remove it again)."""
        self._parts.pop(name, None)

    def get(self, name: str) -> T:
        """The part called ``name`` (plugins loaded first); an unknown name fails clearly."""
        load_plugins()
        try:
            return self._parts[name]
        except (KeyError, TypeError):
            raise FootfallError(f"unknown {self.kind} {name!r}; use one of "
                                f"{', '.join(self._parts) or '(none registered)'}") from None

    def names(self) -> tuple[str, ...]:
        """Every registered name (plugins loaded first), in registration order."""
        load_plugins()
        return tuple(self._parts)

    def items(self) -> list[tuple[str, T]]:
        """(name, part) pairs (plugins loaded first), in registration order."""
        load_plugins()
        return list(self._parts.items())

    def __contains__(self, name: object) -> bool:
        load_plugins()
        return name in self._parts

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self.names())

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self._parts)})"
