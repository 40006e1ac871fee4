"""Declared configuration: every config field states its unit, range and meaning once.

A config is a frozen dataclass deriving from :class:`Params`, its fields made by :func:`param`;
validation, ``to_dict`` / ``from_dict`` and the tables of docs/configuration.md (``python -m
footfall.core.params docs/configuration.md``) all read those declarations.

A field's type comes from its annotation: ``float`` (any finite real number unless its
range says otherwise; ints are accepted), ``int`` (a Python int, not a bool), ``bool``,
``str``, a nested :class:`Params` config, any of these ``| None``; other types (tuples) are
checked only by the field's own ``check``.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import importlib
import math
import numbers
import re
import sys
import types
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError

_KEY = "footfall.param"  # where a field's Param sits in its dataclass metadata


@dataclass(frozen=True)
class Interval:
    """A range of numbers [the field's unit], each end open or closed.

    ``Interval()`` holds every finite number; :func:`above`, :func:`at_least` and
    :func:`within` make the usual ones. A closed infinite end admits infinity itself
    (``within(0, math.inf)`` takes ``inf`` for "never"); NaN is never inside.
    """

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = True
    high_open: bool = True

    def __contains__(self, value: float) -> bool:
        above_low = value > self.low if self.low_open else value >= self.low
        below_high = value < self.high if self.high_open else value <= self.high
        return bool(above_low and below_high)

    def __str__(self) -> str:
        if self.high == math.inf and self.high_open and self.low > -math.inf:
            return f"{'>' if self.low_open else '>='} {self.low:g}"
        if self.low == -math.inf and self.low_open and self.high < math.inf:
            return f"{'<' if self.high_open else '<='} {self.high:g}"
        return (f"in {'(' if self.low_open else '['}{self.low:g}, "
                f"{self.high:g}{')' if self.high_open else ']'}")


def above(low: float) -> Interval:
    """``(low, inf)``: finite numbers greater than ``low``."""
    return Interval(low, math.inf, low_open=True)


def at_least(low: float) -> Interval:
    """``[low, inf)``: finite numbers from ``low`` on."""
    return Interval(low, math.inf, low_open=False)


def within(low: float, high: float, *, low_open: bool = False, high_open: bool = False
           ) -> Interval:
    """``[low, high]``, either end open on request; a closed infinite end admits infinity."""
    return Interval(low, high, low_open, high_open)


@dataclass(frozen=True)
class Param:
    """What a field declares besides its type and default (see :func:`param`)."""

    unit: str
    doc: str
    range: Interval | None = None
    choices: tuple | None = None
    check: Callable[[Any], bool] | None = None
    must: str | None = None
    encode: Callable[[Any], Any] | None = None
    decode: Callable[[Any], Any] | None = None


def param(default: Any = dataclasses.MISSING, *, doc: str, unit: str = "",
          range: Interval | None = None, choices: tuple | None = None,
          check: Callable[[Any], bool] | None = None, must: str | None = None,
          factory: Callable[[], Any] | None = None, encode: Callable[[Any], Any] | None = None,
          decode: Callable[[Any], Any] | None = None) -> Any:
    """A config field with its meaning, unit and accepted values, declared once.

    Parameters
    ----------
    default : object
        The default value (or give ``factory``, e.g. for a nested config).
    doc : str
        One line of meaning (the "meaning" column of the docs table).
    unit : str
        "m", "rad", "s", "-" for a dimensionless number, "" where no unit applies.
    range : Interval, optional
        Accepted numbers (:func:`above`, :func:`at_least`, :func:`within`); without it a
        ``float`` field takes any finite number and an ``int`` field any integer.
    choices : tuple, optional
        The accepted values of a ``str`` field.
    check, must : callable and str, optional
        A further rule ``check(value) -> bool`` (after the type and range), and the whole
        requirement in words for messages and the docs ("an even integer >= 4").
    encode, decode : callable, optional
        Plain-data form of a value for :func:`to_dict` and its inverse for :func:`from_dict`
        (default: the value itself; nested configs become dicts).
    """
    meta = {_KEY: Param(unit, doc, range, None if choices is None else tuple(choices), check,
                        must, encode, decode)}
    if factory is not None:
        return dataclasses.field(default_factory=factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


# ---------------------------------------------------------------- field specs
@dataclass(frozen=True)
class _Spec:
    """One declared field of a config class, its annotation resolved."""

    name: str
    kind: type | None  # float, int, bool, str, a Params class, or None (checked by `check`)
    optional: bool  # None is accepted
    param: Param

    def accepts(self, value: Any) -> bool:
        if value is None:
            return self.optional
        p, kind = self.param, self.kind
        if kind is float:
            ok = isinstance(value, numbers.Real) and not isinstance(value, bool) \
                and value in (p.range or Interval())
        elif kind is int:
            ok = isinstance(value, int) and not isinstance(value, bool) \
                and (p.range is None or value in p.range)
        elif kind is str:
            ok = isinstance(value, str) and (p.choices is None or value in p.choices)
        elif kind is not None:
            ok = isinstance(value, kind)
        else:
            ok = True
        return ok and (p.check is None or bool(p.check(value)))

    def describe(self) -> str:
        """What the field accepts, in words: "> 0", "an integer >= 1 or None", ..."""
        p, kind = self.param, self.kind
        if p.must is not None:
            text = p.must
        elif kind is float:
            text = str(p.range) if p.range is not None else "a finite number"
        elif kind is int:
            text = "an integer" + ("" if p.range is None else f" {p.range}")
        elif kind is bool:
            text = "True or False"
        elif kind is str:
            text = ("a string" if p.choices is None
                    else "one of " + ", ".join(repr(c) for c in p.choices))
        elif kind is not None:
            text = f"a {kind.__name__}"
        else:
            text = "any value"
        return text + (" or None" if self.optional else "")


def _resolve(annotation: Any) -> tuple[type | None, bool]:
    """(kind, optional) of a field annotation."""
    optional = False
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        optional = len(args) < len(typing.get_args(annotation))
        annotation = args[0] if len(args) == 1 else None
    if annotation in (float, int, bool, str) or (
            isinstance(annotation, type) and issubclass(annotation, Params)):
        return annotation, optional
    return None, optional


@functools.cache
def specs(cls: type) -> tuple[_Spec, ...]:
    """The declared fields of a config class, in order; every field must come from param()."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if _KEY not in f.metadata:
            raise TypeError(f"{cls.__name__}.{f.name} is not declared with param()")
        kind, optional = _resolve(hints[f.name])
        out.append(_Spec(f.name, kind, optional, f.metadata[_KEY]))
    return tuple(out)


def label(cls: type) -> str:
    """How messages name a config: ``BodyPathConfig`` -> "body path config"."""
    words = re.findall(r"[A-Z][a-z0-9]*", cls.__name__.removesuffix("Config"))
    return " ".join(w.lower() for w in words) + " config"


# ------------------------------------------------------- checks and plain data
def validate(config: Any) -> None:
    """Refuse a config any of whose fields is outside its declaration (a FootfallError)."""
    for spec in specs(type(config)):
        value = getattr(config, spec.name)
        if not spec.accepts(value):
            raise FootfallError(f"{label(type(config))}: {spec.name} must be "
                                f"{spec.describe()}, got {value!r}")


def to_dict(config: Any) -> dict:
    """The config as plain data, field by field (nested configs as dicts)."""
    out = {}
    for spec in specs(type(config)):
        value = getattr(config, spec.name)
        if value is not None and spec.param.encode is not None:
            value = spec.param.encode(value)
        elif isinstance(value, Params):
            value = to_dict(value)
        out[spec.name] = value
    return out


def _decode(cls: type, spec: _Spec, value: Any) -> Any:
    if value is None:
        return None
    if spec.param.decode is not None:
        try:
            return spec.param.decode(value)
        except (TypeError, ValueError, KeyError, AttributeError):
            raise FootfallError(f"{label(cls)}: {spec.name} must be {spec.describe()}, "
                                f"got {value!r}") from None
    if isinstance(spec.kind, type) and issubclass(spec.kind, Params):
        return from_dict(spec.kind, value)
    if spec.kind is float and isinstance(value, numbers.Real) and not isinstance(value, bool):
        return float(value)
    if spec.kind is None and isinstance(value, list):
        return _tuples(value)
    return value


def _tuples(value: Any) -> Any:
    """Lists, nested too, as tuples: JSON has no tuples, and frozen configs hold them."""
    return tuple(_tuples(v) for v in value) if isinstance(value, list) else value


def from_dict(cls: type, data: Any) -> Any:
    """The config of class ``cls`` that :func:`to_dict` wrote (e.g. read back from a file).

    Every field must be given and no other; values are checked as by the constructor.
    """
    if not isinstance(data, dict):
        raise FootfallError(f"{label(cls)}: expected a mapping of settings, "
                            f"got {type(data).__name__}")
    names = [s.name for s in specs(cls)]
    unknown = sorted(set(data) - set(names), key=str)
    if unknown:
        raise FootfallError(f"{label(cls)}: unknown setting {', '.join(map(repr, unknown))}")
    missing = [n for n in names if n not in data]
    if missing:
        raise FootfallError(f"{label(cls)}: missing setting {', '.join(map(repr, missing))}")
    return cls(**{s.name: _decode(cls, s, data[s.name]) for s in specs(cls)})


class Params:
    """Base of a frozen dataclass config whose fields are all :func:`param` declarations.

    Construction validates; a config with a check no declaration can state (one field
    against another) extends ``__post_init__`` after calling this one.
    """

    def __post_init__(self) -> None:
        validate(self)

    def to_dict(self) -> dict:
        """Plain JSON-serialisable settings (see :func:`to_dict`)."""
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Any:
        """Inverse of :meth:`to_dict` (see :func:`from_dict`)."""
        return from_dict(cls, data)


# ------------------------------------------------------------------ docs tables
def _show(value: Any, spec: _Spec) -> str:
    """A default as the docs table shows it."""
    if value is not None and spec.param.encode is not None:
        value = spec.param.encode(value)
    if isinstance(value, Params):
        base = type(value)()
        changed = [f"{s.name}={_show(getattr(value, s.name), s)}" for s in specs(type(value))
                   if getattr(value, s.name) != getattr(base, s.name)]
        return f"{type(value).__name__}({', '.join(changed)})"
    if isinstance(value, float) and len(repr(value)) > 10:
        return f"{value:.6g}"  # math.radians(0.3) reads better as 0.00523599
    return repr(value)


def markdown_table(cls: type) -> str:
    """The fields of a config class as a Markdown table: name, default, unit, range, meaning."""
    defaults = cls()
    rows = ["| field | default | unit | accepted | meaning |", "|---|---|---|---|---|"]
    for s in specs(cls):
        cells = (f"`{s.name}`", f"`{_show(getattr(defaults, s.name), s)}`", s.param.unit,
                 s.describe(), s.param.doc)
        rows.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(rows) + "\n"


_TABLE = re.compile(r"(<!-- params ([\w.]+) -->\n)(.*?)(<!-- /params -->)", re.DOTALL)


def _config_class(dotted: str) -> type:
    module, _, name = dotted.rpartition(".")
    try:
        cls = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError, ValueError):
        raise FootfallError(f"no config class {dotted!r}") from None
    if not (isinstance(cls, type) and issubclass(cls, Params)):
        raise FootfallError(f"{dotted} is not a declared config (Params)")
    return cls


def refresh_tables(text: str) -> str:
    """Markdown ``text`` with every table between its markers generated anew.

    A table is marked ``<!-- params footfall.sim.episode.WalkConfig -->`` ... ``<!-- /params
    -->``; the class is imported by that name. Everything outside the markers is kept.
    """
    return _TABLE.sub(lambda m: m.group(1) + markdown_table(_config_class(m.group(2)))
                      + m.group(4), text)


def main(argv: list[str] | None = None) -> int:
    """Rewrite the config tables of Markdown files (``--check``: only report stale ones)."""
    parser = argparse.ArgumentParser(prog="python -m footfall.core.params",
                                     description=main.__doc__)
    parser.add_argument("files", nargs="+")
    parser.add_argument("--check", action="store_true")
    args = parser.parse_args(argv)
    stale = []
    for path in args.files:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        try:
            fresh = refresh_tables(text)
        except FootfallError as exc:
            print(f"{path}: {exc}", file=sys.stderr)
            return 2
        if fresh != text:
            stale.append(path)
            if not args.check:
                write_text_atomic(path, fresh)
    for path in stale:
        print(f"{path}: {'out of date' if args.check else 'tables rewritten'}")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    # the importable copy of this module: the configs derive from its Params, not __main__'s
    from footfall.core.params import main as _main

    sys.exit(_main())
