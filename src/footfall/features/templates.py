"""Terrain templates as a learned feature family (paper §III): one RBF column per template.

The library the family reads, Eq. 4 and its NaN rules are in
:mod:`footfall.features.template_library`; here the bandwidths (set from an
RMS height difference or chosen by cross-validation), the family's columns,
its dense form for the planners, its file, and the library built from the
training demonstrations at fit time.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import PatchGrid
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.validate import require_keys, require_number, require_type
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates, DenseTerms, FeatureFamily, register_family
from footfall.features.template_library import (
    DEFAULT_LIBRARY_SIZE,
    TemplateLibrary,
    library_from_demonstrations,
    squared_distances,
)

BANDWIDTH_RANGE = (1e-6, 1e12)
"""[1/m^2] the RBF bandwidths h a template family accepts. Learning sets h = 1 / (taps * rms^2)
from RMS height differences of 1 to 32 mm, about 1 to 1.3e4 on the default scales; the range
admits every RMS difference in :data:`RMS_RANGE` on every window up to
:data:`footfall.features.config.MAX_PATCH_SAMPLES` samples, and keeps h * sum(t^2) and the dense
scorer's float32 products far from overflow."""
RMS_RANGE = (1e-5, 1.0)  # [m] RMS height differences a bandwidth may be set from


def bandwidth_for_rms(rms: float, grid: PatchGrid) -> float:
    """Bandwidth h [1/m^2] at which a patch differing by ``rms`` [m] everywhere scores exp(-1).

    ``rms`` must be a finite number in :data:`RMS_RANGE`.
    """
    rms = require_number(rms, "RMS height difference [m]", *RMS_RANGE)
    return 1.0 / (grid.size * rms * rms)


def check_bandwidths(values: Any, n_scales: int, what: str = "bandwidths") -> tuple[float, ...]:
    """One bandwidth [1/m^2] per scale, each a finite number in :data:`BANDWIDTH_RANGE`."""
    require_type(values, (list, tuple), what)
    if len(values) != n_scales:
        raise FootfallError(f"{what} must hold one bandwidth per scale ({n_scales}), "
                            f"got {len(values)}")
    return tuple(require_number(h, f"{what}[{k}] [1/m^2]", *BANDWIDTH_RANGE)
                 for k, h in enumerate(values))


BANDWIDTH_RMS_GRID = (0.002, 0.004, 0.008, 0.016)  # [m] shared RMS differences the search tries first
ORDER_ONLY_RMS = BANDWIDTH_RMS_GRID[-1]
"""[m] the RMS difference every scale's bandwidth is set from for a learner that reads only each
column's order (trees), where no bandwidth is searched: the grid's largest, at which no patch
within 14 cm RMS of a template underflows to a similarity below 1e-35 (LightGBM's zero) and
float32 scoring still tells similarities 10 um RMS apart."""


@register_family
@dataclass(frozen=True, eq=False)
class TemplateFeatures(FeatureFamily):
    """Terrain templates as a feature family: one column per template, Eq. 4 of the paper.

    Before learning the family has no library; :meth:`fit` builds one from
    the training demonstrations, :meth:`tune` chooses the bandwidth of each
    scale by cross-validation (the paper tuned it by hand), and :meth:`select`
    keeps the templates the L1 learner gave a weight (§III-B).
    """

    name: ClassVar[str] = "templates"
    fit_options: ClassVar[tuple[str, ...]] = ("library_size", "bandwidth_rms", "capped")
    config: FeatureConfig = field(default_factory=FeatureConfig)
    library: TemplateLibrary | None = None  # None until fitted
    bandwidths: tuple[float, ...] = ()  # [1/m^2] per scale; () until chosen
    rms: tuple[float, ...] | None = None  # [m] per scale: the RMS height differences the
    # bandwidths were set from (bandwidth_for_rms); None when only the bandwidths are known
    library_counts: tuple[int, ...] = ()  # templates per scale of the library selected from
    search: tuple[dict, ...] = ()  # the bandwidth search's record: [{"rms_m", "cv_error"}]

    def __post_init__(self) -> None:
        if self.library is not None:
            if self.library.config != self.config:
                raise FootfallError("template library and feature family use different "
                                    "feature settings")
        if self.bandwidths:
            object.__setattr__(self, "bandwidths",
                               check_bandwidths(self.bandwidths, len(self.config.scales)))

    @classmethod
    def create(cls, config: FeatureConfig, robot: RobotDescription = LITTLEDOG) -> TemplateFeatures:
        return cls(config)

    def _fitted(self) -> TemplateLibrary:
        if self.library is None or not self.bandwidths:
            raise FootfallError("the template family has no library or bandwidths yet (fit it)")
        return self.library

    def with_rms(self, rms: Sequence[float]) -> TemplateFeatures:
        """The family with bandwidths set from RMS height differences [m] per scale."""
        rms = tuple(float(r) for r in rms)
        return replace(self, rms=rms, bandwidths=tuple(
            bandwidth_for_rms(r, g) for r, g in zip(rms, self.config.grids)))

    # ---------------------------------------------------------------- features
    def columns(self) -> tuple[str, ...]:
        return self._fitted().names()

    def compute(self, c: Candidates) -> np.ndarray:
        return self._fitted().features(c.patches.relative, self.bandwidths)

    def memo_key(self) -> tuple | None:
        """The templates' contents and the bandwidths: two fitted families with the same
        library (two models learned from the same draw) compute the same columns once per
        candidate set. None until fitted."""
        if self.library is None or not self.bandwidths:
            return None
        key = self.__dict__.get("_memo_key")
        if key is None:  # hashed once per family: the templates do not change
            digest = hashlib.sha1()
            for t in self.library.templates:
                digest.update(np.ascontiguousarray(t, dtype=np.float64).tobytes())
            key = (self.name, digest.hexdigest(), self.bandwidths, repr(self.config.to_dict()))
            object.__setattr__(self, "_memo_key", key)
        return key

    def dense(self, scale: int, weights: np.ndarray, dtype: np.dtype) -> DenseTerms:
        library = self._fitted()
        grid = self.config.grids[scale]
        start = sum(library.counts[:scale])
        ttw = np.asarray(weights, dtype=np.float64)[start:start + library.counts[scale]]
        t = library.templates[scale]
        hs = self.bandwidths[scale]
        hs_tt = (hs * (t ** 2).sum(axis=1)).astype(dtype)
        ttw_d = ttw.astype(dtype)
        dtype = np.dtype(dtype)

        def add_full(zt: np.ndarray, zz: np.ndarray, total: np.ndarray, r: np.ndarray) -> None:
            if ttw.size:
                # Eq. 4: -h sum (t - c)^2 = 2h c.t - h t.t - h c.c, never above 0.
                arg = zt * dtype.type(2.0 * hs)
                arg -= hs_tt[:, None]
                arg -= (hs * zz).astype(dtype, copy=False)
                np.minimum(arg, 0.0, out=arg)
                np.exp(arg, out=arg)
                r += ttw_d @ arg

        def masked(zt: np.ndarray, mt: np.ndarray, zz: np.ndarray, count: np.ndarray) -> np.ndarray:
            if not ttw.size:
                return np.zeros(np.shape(zz)[0])
            d = mt.astype(np.float64) + zz - 2.0 * zt  # sum over the samples with data
            d = np.maximum(d, 0.0) * (grid.size / count.astype(np.float64))
            return ttw @ np.exp(-hs * d)

        return DenseTerms(z_columns=t.T, m_columns=(t ** 2).T, add_full=add_full, masked=masked)

    # ------------------------------------------------------------------- files
    def params(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        library = self._fitted()
        return library.arrays(), {"library": library.meta(), "bandwidths": list(self.bandwidths)}

    @classmethod
    def from_params(cls, config: FeatureConfig, robot: RobotDescription,
                    arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any]) -> TemplateFeatures:
        require_keys(meta, "params", required=("library", "bandwidths"))
        library = TemplateLibrary.from_arrays(dict(arrays), meta["library"],
                                              what="params.library")
        if library.config != config:
            raise FootfallError("params.library.config: the template library was built with "
                                "other feature settings than the model")
        return cls(config, library, check_bandwidths(meta["bandwidths"], len(config.scales),
                                                     "params.bandwidths"))

    # ---------------------------------------------------------------- learning
    def fit(self, maps, states, candidates, chosen, rng: np.random.Generator, *,
            library_size: int = DEFAULT_LIBRARY_SIZE, bandwidth_rms: Sequence[float] | None = None,
            capped: bool = False, robot: RobotDescription = LITTLEDOG,
            log: Callable[[str], None] = lambda s: None) -> TemplateFeatures:
        """A library from the training demonstrations (``capped``: at most ``library_size``
        templates, see :func:`library_from_demonstrations`); bandwidths fixed if
        ``bandwidth_rms``."""
        library = library_from_demonstrations(maps, states, candidates, chosen, self.config, rng,
                                              size=library_size, capped=capped, robot=robot)
        log(f"template library: {sum(library.counts)} templates {library.counts}")
        fitted = replace(self, library=library, library_counts=library.counts)
        return fitted if bandwidth_rms is None else fitted.with_rms(bandwidth_rms)

    def prepare(self, c: Candidates) -> tuple[np.ndarray, ...]:
        """Squared patch distances to every template (n, T_s) [m^2] per scale: free of h."""
        library = self.library
        if library is None:
            raise FootfallError("the template family has no library yet (fit it)")
        return tuple(squared_distances(rel, t) for rel, t in zip(c.patches.relative,
                                                                 library.templates))

    def from_prepared(self, prepared: tuple[np.ndarray, ...]) -> np.ndarray:
        return np.concatenate([np.exp(-h * d) for h, d in zip(self.bandwidths, prepared)], axis=1)

    def tune(self, error: Callable[[FeatureFamily], float],
             log: Callable[[str], None] = lambda s: None, *,
             order_only: bool = False) -> TemplateFeatures:
        """Bandwidths by cross-validation: one shared RMS difference first, then each scale alone.

        Tries :data:`BANDWIDTH_RMS_GRID` for all scales at once, then halves and
        doubles each scale's in turn, keeping a change that lowers the error.
        A family whose bandwidths are set already is returned as it is. For a
        learner that reads only each column's order (``order_only``: trees) a
        bandwidth re-maps every column by a decreasing function, which changes
        nothing but the differences it rounds away, so no search is made: the
        bandwidths are set from :data:`ORDER_ONLY_RMS` on every scale.
        """
        if self.bandwidths:
            return self
        n_scales = len(self.config.scales)
        if order_only:
            log(f"  bandwidth rms {ORDER_ONLY_RMS * 1000:g} mm on every scale, not searched: "
                "the learner reads only the order of each column's values")
            return self.with_rms((ORDER_ONLY_RMS,) * n_scales)
        tried: dict[tuple, float] = {}

        def err(rms: tuple) -> float:
            if rms not in tried:
                tried[rms] = error(self.with_rms(rms))
                log(f"  bandwidth rms {tuple(round(r * 1000, 1) for r in rms)} mm: "
                    f"cv error {tried[rms]:.4f}")
            return tried[rms]

        best = min((tuple([r] * n_scales) for r in BANDWIDTH_RMS_GRID), key=err)
        for s in range(n_scales):  # then each scale on its own, halving and doubling
            for factor in (0.5, 2.0):
                trial = tuple(r * factor if k == s else r for k, r in enumerate(best))
                if err(trial) < err(best):
                    best = trial
        record = tuple({"rms_m": list(k), "cv_error": v} for k, v in tried.items())
        return replace(self.with_rms(best), search=record)

    def select(self, nonzero: np.ndarray) -> tuple[TemplateFeatures, np.ndarray]:
        library = self._fitted()
        keep = np.asarray(nonzero, dtype=bool)
        bounds = np.cumsum((0,) + library.counts)
        per_scale = tuple(np.flatnonzero(keep[a:b]) for a, b in zip(bounds[:-1], bounds[1:]))
        return replace(self, library=library.subset(per_scale),
                       library_counts=self.library_counts or library.counts), keep

    def info(self) -> dict[str, Any]:
        library = self._fitted()
        return {"library_counts": list(self.library_counts or library.counts),
                "kept_counts": list(library.counts),
                "bandwidth_rms_m": None if self.rms is None else list(self.rms),
                "bandwidth_search": [dict(r) for r in self.search]}
