"""Terrain templates (paper §III): height patches of footholds, matched by an RBF.

A template is the patch around a foothold on one scale, heights relative to
the foothold's own height. A library holds one matrix of templates per scale;
the feature of a candidate for a template is Eq. 4 of the paper,

    x = exp(-h * sum_i (t_i - c_i)^2),

one bandwidth h [1/m^2] per scale. The sum is evaluated for a whole candidate
set as ``sum t^2 + sum c^2 - 2 c @ t``: one matrix product.

NaN rules: library templates are complete (a foothold whose patch has a hole
is not put in the library). A candidate patch with holes is compared over the
samples that hold data and the sum is scaled by ``taps / n_valid``, so a hole
neither zeroes nor NaNs the feature; a candidate whose coverage is below
``FeatureConfig.min_coverage`` is not a valid foothold at all.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.heightmap import HeightMap, PatchGrid
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.core.validate import require_float_array, require_keys, require_number, require_type
from footfall.features.config import FeatureConfig
from footfall.features.family import Candidates, DenseTerms, FeatureFamily, register_family
from footfall.features.patches import foothold_patches

FORMAT = "footfall.templates"
VERSION = 1

BANDWIDTH_RANGE = (1e-6, 1e12)
"""[1/m^2] the RBF bandwidths h a template family accepts. Learning sets h = 1 / (taps * rms^2)
from RMS height differences of 1 to 32 mm, about 1 to 1.3e4 on the default scales; the range
admits every RMS difference in :data:`RMS_RANGE` on every window up to
:data:`footfall.features.config.MAX_PATCH_SAMPLES` samples, and keeps h * sum(t^2) and the dense
scorer's float32 products far from overflow."""
RMS_RANGE = (1e-5, 1.0)  # [m] RMS height differences a bandwidth may be set from
MAX_TEMPLATE_HEIGHT = 1000.0  # [m] largest |height| of a template sample relative to its foothold
_SHA256 = re.compile(r"[0-9a-f]{64}")  # a map's content hash (HeightMap.content_hash)
PROVENANCE_TOLERANCE = 1e-9  # [m] a template is the patch its source names if no sample differs
# by more (the same arithmetic on the same map gives the same patch)


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


def squared_distances(candidates: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """Sum of squared height differences between patches, (n, taps) x (T, taps) -> (n, T) [m^2].

    NaN samples of a candidate are left out and the sum is scaled by
    ``taps / n_valid``; rows without any data give NaN.
    """
    c = np.asarray(candidates, dtype=np.float64)
    t = np.asarray(templates, dtype=np.float64)
    taps = c.shape[1]
    holes = np.isnan(c)
    if not holes.any():
        d = (t * t).sum(axis=1)[None, :] + (c * c).sum(axis=1)[:, None] - 2.0 * (c @ t.T)
        return np.maximum(d, 0.0)
    mask = (~holes).astype(np.float64)
    c0 = np.where(holes, 0.0, c)
    d = mask @ (t * t).T + (c0 * c0).sum(axis=1)[:, None] - 2.0 * (c0 @ t.T)
    n_valid = mask.sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.maximum(d, 0.0) * (taps / n_valid)[:, None]
    d[n_valid == 0] = np.nan
    return d


def rbf_features(candidates: np.ndarray, templates: np.ndarray, h: float) -> np.ndarray:
    """Eq. 4 of the paper for every candidate and template, (n, taps) x (T, taps) -> (n, T)."""
    return np.exp(-h * squared_distances(candidates, templates))


@dataclass(frozen=True, eq=False)
class TemplateLibrary:
    """Templates on each scale: one matrix (T_s, taps_s) of relative heights [m] per scale.

    ``sources[s]`` (T_s, 4) records where each template came from: foothold
    x, y [m], body yaw [rad], and 1.0 if it was mirrored (right leg).
    """

    config: FeatureConfig
    templates: tuple[np.ndarray, ...]  # per scale (T_s, taps_s) [m]
    sources: tuple[np.ndarray, ...]  # per scale (T_s, 4): x [m], y [m], yaw [rad], mirrored
    terrain_hashes: tuple[str, ...] = field(default=())  # content hashes of source maps

    def __post_init__(self) -> None:
        grids = self.config.grids
        if len(self.templates) != len(grids) or len(self.sources) != len(grids):
            raise FootfallError("template library needs one matrix per scale")
        for t, src, g, name in zip(self.templates, self.sources, grids, self.config.scale_names):
            if t.ndim != 2 or t.shape[1] != g.size:
                raise FootfallError(f"{name} templates must have shape (T, {g.size}), got {t.shape}")
            if not np.isfinite(t).all():
                raise FootfallError(f"{name} templates must be complete (no NaN)")
            if src.shape != (t.shape[0], 4):
                raise FootfallError(f"{name} template sources must have shape ({t.shape[0]}, 4)")

    @property
    def counts(self) -> tuple[int, ...]:
        """Number of templates on each scale."""
        return tuple(t.shape[0] for t in self.templates)

    def names(self) -> tuple[str, ...]:
        """Feature names of the templates: ``scale.template_k``."""
        return tuple(f"{s}.template_{k}" for s, t in zip(self.config.scale_names, self.templates)
                     for k in range(t.shape[0]))

    def subset(self, keep: tuple[np.ndarray, ...]) -> "TemplateLibrary":
        """The library restricted to the templates selected by per-scale index arrays."""
        return TemplateLibrary(self.config,
                               tuple(t[k] for t, k in zip(self.templates, keep)),
                               tuple(s[k] for s, k in zip(self.sources, keep)),
                               self.terrain_hashes)

    def features(self, rel_patches: tuple[np.ndarray, ...], bandwidths: Any) -> np.ndarray:
        """Template features of candidates from their per-scale relative patches -> (n, sum T_s)."""
        h = np.broadcast_to(np.asarray(bandwidths, dtype=np.float64), (len(self.templates),))
        return np.concatenate([rbf_features(c, t, hs)
                               for c, t, hs in zip(rel_patches, self.templates, h)], axis=1)

    # --------------------------------------------------------------------- I/O
    def arrays(self, prefix: str = "") -> dict[str, np.ndarray]:
        """The library as named arrays (for embedding in other files)."""
        out = {}
        for name, t, s in zip(self.config.scale_names, self.templates, self.sources):
            out[f"{prefix}{name}_templates"] = t
            out[f"{prefix}{name}_sources"] = s
        return out

    def meta(self) -> dict:
        """The library's JSON-serialisable description."""
        return {"config": self.config.to_dict(), "terrain_hashes": list(self.terrain_hashes),
                "units": {"templates": "m (relative to the foothold)",
                          "sources": "x [m], y [m], yaw [rad], mirrored [0/1]"}}

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], meta: dict, prefix: str = "",
                    what: str = "library") -> "TemplateLibrary":
        """Inverse of :meth:`arrays` and :meth:`meta`, every array and field checked.

        Per scale, the arrays ``<prefix><scale>_templates`` (T, taps) must be finite
        heights within :data:`MAX_TEMPLATE_HEIGHT` and ``<prefix><scale>_sources``
        (T, 4) real numbers (NaN: origin unknown); arrays with ``prefix`` beyond
        those are refused. ``what`` names ``meta`` in messages.
        """
        require_keys(meta, what, required=("config",), optional=("terrain_hashes", "units"))
        config = FeatureConfig.from_dict(meta["config"])
        hashes = meta.get("terrain_hashes", [])
        require_type(hashes, list, f"{what}.terrain_hashes")
        for k, h in enumerate(hashes):
            require_type(h, str, f"{what}.terrain_hashes[{k}]")
            if not _SHA256.fullmatch(h):
                raise FootfallError(f"{what}.terrain_hashes[{k}] must be a map's content hash "
                                    f"(64 hexadecimal digits), got {h[:80]!r}")
        expected = [f"{prefix}{n}_{kind}" for n in config.scale_names
                    for kind in ("templates", "sources")]
        missing = [k for k in expected if k not in arrays]
        extra = sorted(k for k in arrays if k.startswith(prefix) and k not in expected)
        problems = [f"lacks array {k}" for k in missing] + [f"has unexpected array {k}"
                                                           for k in extra]
        if problems:
            raise FootfallError(f"the template library {'; '.join(problems)}")
        t, s = [], []
        for name, grid in zip(config.scale_names, config.grids):
            t.append(require_float_array(arrays[f"{prefix}{name}_templates"],
                                         f"array {prefix}{name}_templates", (None, grid.size),
                                         bound=MAX_TEMPLATE_HEIGHT))
            src = require_float_array(arrays[f"{prefix}{name}_sources"],
                                      f"array {prefix}{name}_sources", (t[-1].shape[0], 4),
                                      finite=False)
            if np.isinf(src).any():
                raise FootfallError(f"array {prefix}{name}_sources must not be infinite")
            s.append(src)
        return cls(config, tuple(t), tuple(s), tuple(hashes))

    def save(self, path: str | os.PathLike) -> None:
        """Write the library as a versioned ``.npz`` (atomically)."""
        save_npz(path, FORMAT, VERSION, self.arrays(), self.meta())

    @classmethod
    def load(cls, path: str | os.PathLike) -> "TemplateLibrary":
        """Read a library written by :meth:`save`."""
        _, arrays, meta = load_npz(path, FORMAT, VERSION)
        try:
            return cls.from_arrays(arrays, meta, what="meta")
        except FootfallError as exc:
            raise FootfallError(f"{path}: malformed template library: {exc}") from None


def extract_templates(hmap: HeightMap, positions: Any, yaw: Any, mirror: Any,
                      config: FeatureConfig) -> TemplateLibrary:
    """Build a library from footholds on a map: each complete patch becomes a template.

    Footholds whose patch on a scale has any hole or runs off the map give no
    template on that scale (templates are always complete).
    """
    p = np.asarray(positions, dtype=np.float64).reshape(-1, np.shape(positions)[-1])[:, :2]
    n = p.shape[0]
    yaw = np.broadcast_to(np.asarray(yaw, dtype=np.float64), (n,))
    mirror = np.broadcast_to(np.asarray(mirror, dtype=bool), (n,))
    fp = foothold_patches(hmap, p, yaw, mirror, config)
    src = np.column_stack([p, yaw, mirror.astype(np.float64)])
    templates, sources = [], []
    for rel in fp.relative:
        complete = np.isfinite(rel).all(axis=1)
        templates.append(rel[complete])
        sources.append(src[complete])
    return TemplateLibrary(config, tuple(templates), tuple(sources), (hmap.content_hash(),))


def reproduced_on(library: TemplateLibrary, hmap: HeightMap) -> tuple[np.ndarray, ...]:
    """Per scale (T_s,) bools: which templates are the patch their source (x, y [m], yaw [rad],
    mirrored) names on ``hmap``, to :data:`PROVENANCE_TOLERANCE` [m]. A template whose source is
    unknown (NaN) or off the map is not reproduced. One vectorised pass per scale."""
    out = []
    for s, (t, src) in enumerate(zip(library.templates, library.sources)):
        known = np.isfinite(src).all(axis=1)
        ok = np.zeros(t.shape[0], dtype=bool)
        if known.any():
            k = src[known]
            rel = foothold_patches(hmap, k[:, :2], k[:, 2], k[:, 3] > 0.5,
                                   library.config).relative[s]
            with np.errstate(invalid="ignore"):
                ok[known] = np.all(np.abs(rel - t[known]) <= PROVENANCE_TOLERANCE, axis=1)
        out.append(ok)
    return tuple(out)


def merge_libraries(libraries: list[TemplateLibrary]) -> TemplateLibrary:
    """Concatenate libraries built with the same feature configuration."""
    if not libraries:
        raise FootfallError("no template libraries to merge")
    config = libraries[0].config
    if any(lib.config != config for lib in libraries):
        raise FootfallError("cannot merge template libraries of different feature configurations")
    hashes = tuple(dict.fromkeys(h for lib in libraries for h in lib.terrain_hashes))
    return TemplateLibrary(
        config,
        tuple(np.concatenate([lib.templates[s] for lib in libraries]) for s in range(len(config.scales))),
        tuple(np.concatenate([lib.sources[s] for lib in libraries]) for s in range(len(config.scales))),
        hashes)


DEFAULT_LIBRARY_SIZE = 1000  # templates over the three scales before L1 selection (the paper had 946)
BANDWIDTH_RMS_GRID = (0.002, 0.004, 0.008, 0.016)  # [m] shared RMS differences the search tries first


def library_from_demonstrations(maps: Sequence[HeightMap], states: Sequence[RobotState],
                                candidates: Sequence[np.ndarray], chosen: Sequence[int],
                                config: FeatureConfig, rng: np.random.Generator,
                                size: int = DEFAULT_LIBRARY_SIZE,
                                robot: RobotDescription = LITTLEDOG) -> TemplateLibrary:
    """A template library from training demonstrations (paper §III-A).

    Every chosen foothold, then a random sample of the other reachable ones
    up to ``size / 3`` per scale (so more than ``size`` templates when there
    are more demonstrations than that); right-leg footholds are mirrored.
    Footholds whose patch on a scale is incomplete give no template there.
    ``maps[k]`` is the terrain of demonstration k.
    """
    if not states:
        raise FootfallError("no demonstrations to build a template library from")
    per_scale = max(1, size // len(config.scales))
    n_demo = len(states)
    chosen_rows = [(k, int(chosen[k])) for k in range(n_demo)]
    sizes = np.array([c.shape[0] for c in candidates])
    extra = max(0, per_scale - n_demo)
    # Sample "other" candidates uniformly over all demonstrations, without a
    # Python loop over candidates: draw flat indices and map them back.
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    flat = rng.choice(offsets[-1], size=min(offsets[-1], extra + n_demo), replace=False)
    demo = np.searchsorted(offsets, flat, side="right") - 1
    row = flat - offsets[demo]
    keep = row != np.asarray(chosen)[demo]
    picks = chosen_rows + list(zip(demo[keep][:extra].tolist(), row[keep][:extra].tolist()))
    libraries = []
    by_map: dict[int, list[tuple[int, int]]] = {}
    for k, j in picks:
        by_map.setdefault(id(maps[k]), []).append((k, j))
    for group in by_map.values():  # one extraction per terrain map
        k0 = group[0][0]
        pos = np.array([candidates[k][j, :2] for k, j in group])
        yaw = np.array([states[k].yaw for k, _ in group])
        mirror = np.array([robot.leg(states[k].swing_leg).mirrored for k, _ in group])
        libraries.append(extract_templates(maps[k0], pos, yaw, mirror, config))
    return merge_libraries(libraries)


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
    fit_options: ClassVar[tuple[str, ...]] = ("library_size", "bandwidth_rms")
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

        def add_full(g: np.ndarray, cc: np.ndarray, total: np.ndarray, r: np.ndarray) -> None:
            if ttw.size:
                # Eq. 4: -h sum (t - c)^2 = 2h c.t - h t.t - h c.c, never above 0.
                arg = g - hs_tt[:, None]
                arg -= (hs * cc).astype(dtype, copy=False)
                np.minimum(arg, 0.0, out=arg)
                np.exp(arg, out=arg)
                r += ttw_d @ arg

        def masked(zt: np.ndarray, mt: np.ndarray, zz: np.ndarray, count: np.ndarray) -> np.ndarray:
            if not ttw.size:
                return np.zeros(np.shape(zz)[0])
            d = mt.astype(np.float64) + zz - 2.0 * zt  # sum over the samples with data
            d = np.maximum(d, 0.0) * (grid.size / count.astype(np.float64))
            return ttw @ np.exp(-hs * d)

        return DenseTerms(full_columns=t.T * (2.0 * hs), masked_z=t.T, masked_m=(t ** 2).T,
                          add_full=add_full, masked=masked)

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
            robot: RobotDescription = LITTLEDOG, log: Callable[[str], None] = lambda s: None
            ) -> TemplateFeatures:
        """A library from the training demonstrations; bandwidths fixed if ``bandwidth_rms``."""
        library = library_from_demonstrations(maps, states, candidates, chosen, self.config, rng,
                                              size=library_size, robot=robot)
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
             log: Callable[[str], None] = lambda s: None) -> TemplateFeatures:
        """Bandwidths by cross-validation: one shared RMS difference first, then each scale alone.

        Tries :data:`BANDWIDTH_RMS_GRID` for all scales at once, then halves and
        doubles each scale's in turn, keeping a change that lowers the error.
        A family whose bandwidths are set already is returned as it is.
        """
        if self.bandwidths:
            return self
        n_scales = len(self.config.scales)
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
