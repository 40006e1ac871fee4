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

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.files import load_npz, save_npz
from footfall.core.heightmap import HeightMap, PatchGrid
from footfall.features.patches import foothold_patches
from footfall.features.config import FeatureConfig

FORMAT = "footfall.templates"
VERSION = 1


def bandwidth_for_rms(rms: float, grid: PatchGrid) -> float:
    """Bandwidth h [1/m^2] at which a patch differing by ``rms`` [m] everywhere scores exp(-1)."""
    if rms <= 0:
        raise FootfallError(f"RMS height difference must be > 0, got {rms}")
    return 1.0 / (grid.size * rms * rms)


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
    def from_arrays(cls, arrays: dict[str, np.ndarray], meta: dict, prefix: str = ""
                    ) -> "TemplateLibrary":
        """Inverse of :meth:`arrays` and :meth:`meta`."""
        config = FeatureConfig.from_dict(meta["config"])
        try:
            t = tuple(np.asarray(arrays[f"{prefix}{n}_templates"], dtype=np.float64)
                      for n in config.scale_names)
            s = tuple(np.asarray(arrays[f"{prefix}{n}_sources"], dtype=np.float64)
                      for n in config.scale_names)
        except KeyError as exc:
            raise FootfallError(f"template library lacks array {exc}") from None
        return cls(config, t, s, tuple(meta.get("terrain_hashes", ())))

    def save(self, path: str | os.PathLike) -> None:
        """Write the library as a versioned ``.npz`` (atomically)."""
        save_npz(path, FORMAT, VERSION, self.arrays(), self.meta())

    @classmethod
    def load(cls, path: str | os.PathLike) -> "TemplateLibrary":
        """Read a library written by :meth:`save`."""
        _, arrays, meta = load_npz(path, FORMAT, VERSION)
        return cls.from_arrays(arrays, meta)


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
