"""The three length scales of terrain features and templates (paper §III-A, §V).

small (24 x 24 mm) is the size of the ball foot: slip and micro-features;
medium (54 x 54 mm): clearance from obstacles and drop-offs; large
(144 x 54 mm, long side along the body's x axis): shin and knee collisions.
Features and templates are computed on the same scales, sampled on a patch
grid of ``FeatureConfig.template_resolution``.
"""

from __future__ import annotations

from dataclasses import dataclass

from footfall.core.heightmap import PatchGrid
from footfall.core.params import Params, above, param, within


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
    return tuple(Scale(str(n), float(a), float(b)) for n, a, b in data)


@dataclass(frozen=True)
class FeatureConfig(Params):
    """How foothold features are computed; stored with every model (docs/configuration.md)."""

    template_resolution: float = param(
        0.003, unit="m", range=above(0), doc="spacing of the patch samples of every scale")
    min_coverage: float = param(
        0.5, unit="-", range=within(0, 1, low_open=True),
        doc="least fraction of a patch's samples on measured terrain for a candidate")
    scales: tuple[Scale, ...] = param(
        SCALES, doc="the named windows features and templates are computed on",
        check=lambda v: isinstance(v, tuple) and all(isinstance(s, Scale) for s in v),
        must="a tuple of Scale", encode=_scales_data, decode=_scales_from_data)

    @property
    def grids(self) -> tuple[PatchGrid, ...]:
        """The patch grid of each scale, in the order of ``scales``."""
        return tuple(PatchGrid(s.length_x, s.length_y, self.template_resolution)
                     for s in self.scales)

    @property
    def scale_names(self) -> tuple[str, ...]:
        """Names of the scales, in order."""
        return tuple(s.name for s in self.scales)
