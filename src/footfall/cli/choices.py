"""Option choices read from footfall's registries when a command is parsed or its help shown.

Read late on purpose: a name registered after import (a new learner, feature
set or terrain kind, a plugin's) is a valid choice at once.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import Any

import click

from footfall.core.errors import FootfallError
from footfall.core.limits import current_limits
from footfall.core.robot import LEG_NAMES
from footfall.experiments.variants import VARIANTS
from footfall.expert.collect import RECORDED_STEPS
from footfall.expert.teachers import TEACHERS
from footfall.features.family import FEATURE_SETS, feature_set_families
from footfall.learning import ranker
from footfall.learning.learner import LEARNERS
from footfall.learning.supervision import SUPERVISIONS
from footfall.terrain import KINDS


class RegistryChoice(click.Choice):
    """A choice among the names ``names()`` returns at the time of use.

    ``invalid``: the message for a name not among them, with ``{value!r}``
    and ``{choices}`` (comma-separated); click's own message by default.
    """

    def __init__(self, names: Callable[[], Iterable[str]], invalid: str | None = None) -> None:
        # click.Choice.__init__ would freeze the names into a tuple: keep the callable instead.
        self._names = names
        self._invalid = invalid
        self.case_sensitive = True

    @property
    def choices(self) -> tuple[str, ...]:  # type: ignore[override]
        return tuple(self._names())

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if self._invalid is not None and value not in self.choices:
            self.fail(self._invalid.format(value=value, choices=", ".join(self.choices)),
                      param, ctx)
        return super().convert(value, param, ctx)


class FeatureSetChoice(click.ParamType):
    """A registered feature set, or feature family names joined by ``+`` (``terrain+pose``)."""

    name = "feature set"

    def get_metavar(self, param: click.Parameter, ctx: click.Context | None = None) -> str:
        return "[" + "|".join([*FEATURE_SETS, "FAMILY+FAMILY..."]) + "]"

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> str:
        try:
            feature_set_families(value)
        except FootfallError as exc:
            self.fail(str(exc), param, ctx)
        return value


class ChoiceArgument(click.Argument):
    """An argument whose usage line lists its choices while its errors still call it by name."""

    def get_error_hint(self, ctx: click.Context) -> str:
        return f"'{self.human_readable_name.upper()}'"


def _legs() -> tuple[str, ...]:
    return tuple(LEG_NAMES)


def _learners() -> tuple[str, ...]:
    return LEARNERS.names()  # read when used: plugins and later registrations count


def _teachers() -> tuple[str, ...]:
    return TEACHERS.names()  # read when used, as the learners


def _supervisions() -> tuple[str, ...]:
    return SUPERVISIONS.names()


def _variants() -> tuple[str, ...]:
    return VARIANTS.names()


def _selections() -> tuple[str, ...]:
    return tuple(ranker.SELECTIONS)


def _terrain_kinds() -> tuple[str, ...]:
    return tuple(KINDS)


def _recorded_steps() -> tuple[str, ...]:
    return tuple(RECORDED_STEPS)


LEG = RegistryChoice(_legs)  # footfall.core.robot.LEG_NAMES
LEARNER = RegistryChoice(_learners)  # footfall.learning.learner.LEARNERS
TEACHER = RegistryChoice(_teachers)  # footfall.expert.teachers.TEACHERS
SUPERVISION = RegistryChoice(_supervisions)  # footfall.learning.supervision.SUPERVISIONS
VARIANT = RegistryChoice(_variants)  # footfall.experiments.variants.VARIANTS
SELECTION = RegistryChoice(_selections)  # footfall.learning.ranker.SELECTIONS
TERRAIN_KIND = RegistryChoice(  # footfall.terrain.KINDS, refused in the generator's words
    _terrain_kinds, invalid="unknown terrain module kind {value!r}; known kinds: {choices}")
RECORDED_STEP = RegistryChoice(_recorded_steps)  # footfall.expert.collect.RECORDED_STEPS
FEATURE_SET = FeatureSetChoice()  # footfall.features.family: FEATURE_SETS and family names


# A seed: a whole number in [0, 2**63), what footfall.core.seeds keeps exactly in every file.
SEED = click.IntRange(0, 2 ** 63 - 1)


def count_range(minimum: int = 1) -> click.IntRange:
    """A count option's type: from ``minimum`` to the ``max_count`` limit (read when parsed)."""
    return _Count(minimum)


class _Count(click.IntRange):
    """An integer from a minimum to the max_count limit in force when the command is parsed."""

    def __init__(self, minimum: int) -> None:
        super().__init__(min=minimum)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None
                ) -> Any:
        number = super().convert(value, param, ctx)
        limit = current_limits().max_count
        if number > limit:
            self.fail(f"{number} is above the limit of {limit} (raise it with "
                      f"footfall --limit max_count=N)", param, ctx)
        return number


class Finite(click.FloatRange):
    """A finite number (no nan, inf or 1e400) in a range [its unit in the option's help]."""

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None
                ) -> Any:
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


class Budget(Finite):
    """A template budget: a share of the demonstrations above 0 [-], or ``none`` (no budget,
    returned as :data:`NO_BUDGET`)."""

    name = "share|none"

    def __init__(self) -> None:
        super().__init__(min=0.0, min_open=True)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None
                ) -> Any:
        if isinstance(value, str) and value.strip().lower() == "none":
            return NO_BUDGET
        return value if value is NO_BUDGET else super().convert(value, param, ctx)


NO_BUDGET = "none"  # --template-budget none: a function may read any number of templates
BUDGET = Budget()
