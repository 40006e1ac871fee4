"""The three length scales of terrain features and templates (paper §III-A, §V).

small (24 x 24 mm) is the size of the ball foot: slip and micro-features;
medium (54 x 54 mm): clearance from obstacles and drop-offs; large
(144 x 54 mm, long side along the body's x axis): shin and knee collisions.
Features and templates are computed on the same scales, sampled on a patch
grid of ``FeatureConfig.template_resolution``.
"""

from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass

from footfall.core.errors import FootfallError
from footfall.core.heightmap import PatchGrid
from footfall.core.params import Params, param, within

MAX_SCALE_LENGTH = 1.0  # [m] the longest side of a window: a foothold patch, not a terrain
MAX_PATCH_SAMPLES = 250_000  # the most samples a window may hold (500 x 500)
_SCALE_NAME = re.compile(r"^[A-Za-z0-9_-]+$")  # scale names appear in column and array names


@dataclass(frozen=True)
class Scale:
    """A named rectangular window around a foothold."""

    name: str
    length_x: float  # [m] along the body's x axis
    length_y: float  # [m] along the body's y axis


SCALES: tuple[Scale, ...] = (
    Scale("small", 0.024, 0.024),
    Scale("medium", 0.054, 0.054),
    Scale("large", 0.144, 0.054),
)


def _scales_data(scales: tuple[Scale, ...]) -> list:
    return [[s.name, s.length_x, s.length_y] for s in scales]


def _scales_from_data(data: list) -> tuple[Scale, ...]:
    if not isinstance(data, list) or not all(isinstance(s, list) and len(s) == 3 for s in data):
        raise TypeError("scales must be a list of [name, length_x, length_y]")
    if not all(isinstance(n, str) and _is_real(a) and _is_real(b) for n, a, b in data):
        raise TypeError("a scale is [str, number, number]")
    return tuple(Scale(n, float(a), float(b)) for n, a, b in data)


def _is_real(value: object) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _scales_ok(scales: object) -> bool:
    """A non-empty tuple of Scale with distinct plain names and lengths in (0, 1] m."""
    if not isinstance(scales, tuple) or not scales:
        return False
    names = [getattr(s, "name", None) for s in scales]
    return all(isinstance(s, Scale) and isinstance(s.name, str) and _SCALE_NAME.match(s.name)
               and all(_is_real(v) and math.isfinite(v) and 0 < v <= MAX_SCALE_LENGTH
                       for v in (s.length_x, s.length_y)) for s in scales) \
        and len(set(names)) == len(names)


@dataclass(frozen=True)
class FeatureConfig(Params):
    """How foothold features are computed; stored with every model (docs/configuration.md)."""

    template_resolution: float = param(
        0.003, unit="m", range=within(1e-4, 0.01),
        doc="spacing of the patch samples of every scale (0.1 mm, finer than any scan, to "
            "1 cm, at which the small window still has a sample each side of its centre)")
    min_coverage: float = param(
        0.5, unit="-", range=within(0, 1, low_open=True),
        doc="least fraction of a patch's samples on measured terrain for a candidate")
    scales: tuple[Scale, ...] = param(
        SCALES, doc="the named windows features and templates are computed on",
        check=_scales_ok, must="a non-empty list of distinct [name, length_x, length_y], "
                               "names of letters, digits, '_' or '-', lengths in (0, 1] m",
        encode=_scales_data, decode=_scales_from_data)

    def __post_init__(self) -> None:
        super().__post_init__()
        for scale, grid in zip(self.scales, self.grids):
            if min(grid.half_counts) < 1:
                raise FootfallError(
                    f"feature config: the {scale.name} window has no sample beside its centre "
                    f"at template_resolution {self.template_resolution:g} m; use at most "
                    f"{min(scale.length_x, scale.length_y) / 2:g} m")
            if grid.size > MAX_PATCH_SAMPLES:
                raise FootfallError(
                    f"feature config: the {scale.name} window holds {grid.size:.3g} samples at "
                    f"template_resolution {self.template_resolution:g} m, more than "
                    f"{MAX_PATCH_SAMPLES}")

    @property
    def grids(self) -> tuple[PatchGrid, ...]:
        """The patch grid of each scale, in the order of ``scales``."""
        return tuple(PatchGrid(s.length_x, s.length_y, self.template_resolution)
                     for s in self.scales)

    @property
    def scale_names(self) -> tuple[str, ...]:
        """Names of the scales, in order."""
        return tuple(s.name for s in self.scales)
