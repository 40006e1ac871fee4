"""The three length scales of terrain features and templates (paper §III-A, §V).

small (24 x 24 mm) is the size of the ball foot: slip and micro-features;
medium (54 x 54 mm): clearance from obstacles and drop-offs; large
(144 x 54 mm, long side along the body's x axis): shin and knee collisions.
Features and templates are computed on the same scales, sampled on a patch
grid of ``FeatureConfig.template_resolution``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from footfall.core.errors import FootfallError
from footfall.core.heightmap import PatchGrid


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

# 3 mm samples: the ball foot (10 mm radius) spans 7 samples across, enough to
# see whether it sits in a hollow or on a ridge, while the large patch stays at
# 49 x 19 = 931 samples, so that dense scoring of a whole board is a cheap
# matrix product. At 1 mm (the scan resolution) it would be 9x the work for
# detail the foot cannot feel; at 5 mm the small patch would have 5 x 5 samples.
DEFAULT_TEMPLATE_RESOLUTION = 0.003  # [m]
# A patch needs at least this fraction of its samples on measured terrain; below
# it the foothold is not a candidate (its features would be a guess).
DEFAULT_MIN_COVERAGE = 0.5  # [-] fraction of samples that hold data


@dataclass(frozen=True)
class FeatureConfig:
    """How foothold features are computed; stored with every model."""

    template_resolution: float = DEFAULT_TEMPLATE_RESOLUTION  # [m] patch sample spacing
    min_coverage: float = DEFAULT_MIN_COVERAGE  # [-] least fraction of samples with data
    scales: tuple[Scale, ...] = field(default=SCALES)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.template_resolution) and self.template_resolution > 0):
            raise FootfallError(f"template resolution must be > 0, got {self.template_resolution}")
        if not 0 < self.min_coverage <= 1:
            raise FootfallError(f"min_coverage must be in (0, 1], got {self.min_coverage}")

    @property
    def grids(self) -> tuple[PatchGrid, ...]:
        """The patch grid of each scale, in the order of ``scales``."""
        return tuple(PatchGrid(s.length_x, s.length_y, self.template_resolution)
                     for s in self.scales)

    @property
    def scale_names(self) -> tuple[str, ...]:
        """Names of the scales, in order."""
        return tuple(s.name for s in self.scales)

    def to_dict(self) -> dict:
        """Plain data for model files."""
        return {"template_resolution": self.template_resolution,
                "min_coverage": self.min_coverage,
                "scales": [[s.name, s.length_x, s.length_y] for s in self.scales]}

    @classmethod
    def from_dict(cls, data: dict) -> "FeatureConfig":
        """Inverse of :meth:`to_dict`."""
        try:
            return cls(float(data["template_resolution"]), float(data["min_coverage"]),
                       tuple(Scale(str(n), float(a), float(b)) for n, a, b in data["scales"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise FootfallError(f"malformed feature configuration ({exc})") from None
