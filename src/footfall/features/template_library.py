"""The template library (paper §III-A): height patches of footholds on each scale, Eq. 4.

A template is the patch around a foothold on one scale, heights relative to
the foothold's own height. A library holds one matrix of templates per scale
(and its file); the feature of a candidate for a template is Eq. 4 of the
paper,

    x = exp(-h * sum_i (t_i - c_i)^2),

one bandwidth h [1/m^2] per scale. The sum is evaluated for a whole candidate
set as ``sum t^2 + sum c^2 - 2 c @ t``: one matrix product.

NaN rules: library templates are complete (a foothold whose patch has a hole
is not put in the library). A candidate patch with holes is compared over the
samples that hold data and the sum is scaled by ``taps / n_valid``, so a hole
neither zeroes nor NaNs the feature; a candidate whose coverage is below
``FeatureConfig.min_coverage`` is not a valid foothold at all.

The learned feature family that reads a library is
:class:`footfall.features.templates.TemplateFeatures`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.core.state import RobotState
from footfall.core.validate import require_float_array, require_keys, require_type
from footfall.features.config import FeatureConfig
from footfall.features.patches import foothold_patches

FORMAT = "footfall.templates"
VERSION = 1
MAX_TEMPLATE_HEIGHT = 1000.0  # [m] largest |height| of a template sample relative to its foothold
_SHA256 = re.compile(r"[0-9a-f]{64}")  # a map's content hash (HeightMap.content_hash)
PROVENANCE_TOLERANCE = 1e-9  # [m] a template is the patch its source names if no sample differs
# by more (the same arithmetic on the same map gives the same patch)


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


def library_from_demonstrations(maps: Sequence[HeightMap], states: Sequence[RobotState],
                                candidates: Sequence[np.ndarray], chosen: Sequence[int],
                                config: FeatureConfig, rng: np.random.Generator,
                                size: int = DEFAULT_LIBRARY_SIZE, capped: bool = False,
                                robot: RobotDescription = LITTLEDOG) -> TemplateLibrary:
    """A template library from training demonstrations (paper §III-A).

    Every chosen foothold, then a random sample of the other reachable ones
    up to ``size / 3`` per scale (so more than ``size`` templates when there
    are more demonstrations than that); right-leg footholds are mirrored.
    ``capped``: never more than ``size / 3`` a scale -- with more
    demonstrations than that, a uniform random sample of their chosen
    footholds without replacement (fewer demonstrations: the same library as
    uncapped). Footholds whose patch on a scale is incomplete give no
    template there. ``maps[k]`` is the terrain of demonstration k.
    """
    if not states:
        raise FootfallError("no demonstrations to build a template library from")
    per_scale = max(1, size // len(config.scales))
    n_demo = len(states)
    if capped and n_demo > per_scale:
        kept = np.sort(rng.choice(n_demo, size=per_scale, replace=False))
        return library_from_demonstrations(
            [maps[k] for k in kept], [states[k] for k in kept], [candidates[k] for k in kept],
            [chosen[k] for k in kept], config, rng, size=size, robot=robot)
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
