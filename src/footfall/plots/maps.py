"""Pictures of what footfall computes on a terrain: reward and feature maps, templates.

Figure objects only (no pyplot), safe headless. Maps are drawn in metres with
x to the right and y up; points that are not valid footholds are grey.
"""

from __future__ import annotations

import os
from typing import Sequence

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from footfall.core.atomic import atomic_path
from footfall.core.heightmap import PatchGrid
from footfall.features.dense import ScoreGrid
from footfall.learning.function import LinearFunction

DPI = 130  # [dots/inch]
INVALID_RGBA = (0.6, 0.6, 0.62, 1.0)  # grey: not a valid foothold


def draw_score_map(ax: Axes, grid: ScoreGrid, *, title: str = "", label: str = "reward",
                   cmap: str = "viridis", robust: bool = True) -> None:
    """Draw a dense score (reward or a feature) over the lattice, with a colour bar.

    ``robust`` clips the colour range to the 1st..99th percentile of valid values
    so that a few extreme points do not wash out the rest.
    """
    values = np.where(grid.valid, grid.reward, np.nan)
    finite = values[np.isfinite(values)]
    lo, hi = ((np.percentile(finite, 1), np.percentile(finite, 99)) if robust and finite.size
              else (np.nanmin(values), np.nanmax(values)))
    if not hi > lo:
        hi = lo + 1e-12
    colours = matplotlib.colormaps[cmap].with_extremes(bad=INVALID_RGBA)
    step_x = grid.x[1] - grid.x[0] if grid.x.size > 1 else 1.0
    step_y = grid.y[1] - grid.y[0] if grid.y.size > 1 else 1.0
    extent = (grid.x[0] - step_x / 2, grid.x[-1] + step_x / 2,
              grid.y[0] - step_y / 2, grid.y[-1] + step_y / 2)
    image = ax.imshow(values.T, origin="lower", extent=extent, cmap=colours, vmin=lo, vmax=hi,
                      interpolation="nearest", aspect="equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if title:
        ax.set_title(title, parse_math=False)  # names may come from files: text, not mathtext
    bar = ax.figure.colorbar(image, ax=ax, shrink=0.85)
    bar.ax.set_ylabel(label, parse_math=False)


def save_score_maps(grids: Sequence[ScoreGrid], titles: Sequence[str], labels: Sequence[str],
                    path: str | os.PathLike, *, cmap: str = "viridis") -> None:
    """Write one or more dense maps, stacked vertically, as a PNG (atomically)."""
    g0 = grids[0]
    aspect = (g0.y[-1] - g0.y[0]) / max(g0.x[-1] - g0.x[0], 1e-9)
    width = 10.0  # [inch]
    fig = Figure(figsize=(width, len(grids) * (width * aspect * 0.85 + 0.9)), layout="constrained")
    for k, (g, t, lab) in enumerate(zip(grids, titles, labels)):
        draw_score_map(fig.add_subplot(len(grids), 1, k + 1), g, title=t, label=lab, cmap=cmap)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)


def save_template_figure(patches: Sequence[Sequence[np.ndarray]], grids: Sequence[PatchGrid],
                         row_titles: Sequence[str], scale_names: Sequence[str],
                         path: str | os.PathLike) -> None:
    """Write template patches as a table: one row per template set, one column per scale.

    ``patches[r][s]`` is a flattened (or (nu, nv)) patch of relative heights [m]
    on ``grids[s]``; a white dot marks the foothold, as in the paper's Fig. 3(b).
    """
    rows, cols = len(patches), len(grids)
    widths = [g.length_x for g in grids]
    fig = Figure(figsize=(2.2 + 8.0, 1.9 * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False, width_ratios=widths)
    finite = [np.abs(p)[np.isfinite(p)] for row in patches for p in row]
    limit = max((float(f.max()) for f in finite if f.size), default=0.0) * 1000 or 1.0
    image = None
    for r in range(rows):
        for s, grid in enumerate(grids):
            ax = axes[r][s]
            patch = np.asarray(patches[r][s]).reshape(grid.shape) * 1000.0  # [mm]
            hu, hv = grid.u[-1] + grid.resolution / 2, grid.v[-1] + grid.resolution / 2
            image = ax.imshow(patch.T, origin="lower", cmap="RdBu_r", vmin=-limit, vmax=limit,
                              extent=(-hu * 1000, hu * 1000, -hv * 1000, hv * 1000),
                              interpolation="nearest")
            ax.plot([0], [0], "o", color="white", markeredgecolor="black", markersize=5)
            ax.set_xticks([-int(hu * 1000), 0, int(hu * 1000)])
            ax.set_yticks([-int(hv * 1000), 0, int(hv * 1000)])
            if r == 0:
                ax.set_title(f"{scale_names[s]} ({grid.length_x * 1000:.0f} x "
                             f"{grid.length_y * 1000:.0f} mm)", parse_math=False)
            if s == 0:
                ax.set_ylabel(f"{row_titles[r]}\nv [mm]", parse_math=False)
            if r == rows - 1:
                ax.set_xlabel("u [mm] (forward)")
    if image is not None:
        fig.colorbar(image, ax=axes, label="height relative to foothold [mm]", shrink=0.8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=DPI)


def save_kept_templates(model, path: str | os.PathLike, group: str = "front", rows: int = 3) -> bool:
    """Draw a model's kept templates with the largest weights, on each of the three scales.

    Row r shows, per scale, the template of rank r by |weight| among the kept
    ones of the ``group`` legs' ranking function (in library order for a
    function without one weight per template; an empty panel where a scale
    kept fewer). Returns False (and writes nothing) if no template was kept.
    """
    f = model.functions[group]
    library = f.library
    if library is None or max(library.counts, default=0) == 0:
        return False
    w = (f.weights("templates") if isinstance(f, LinearFunction)
         else np.zeros(sum(library.counts)))  # equal |weight|: the stable sort keeps the order
    bounds = np.cumsum((0,) + library.counts)
    by_scale = [w[a:b] for a, b in zip(bounds[:-1], bounds[1:])]  # weights of each scale
    patches, titles = [], []
    for rank in range(min(rows, max(library.counts))):
        row = []
        for s, weights in enumerate(by_scale):
            if rank < weights.size:
                order = np.argsort(-np.abs(weights), kind="stable")
                row.append(library.templates[s][order[rank]])
            else:  # fewer templates kept on this scale: an empty (NaN) panel
                row.append(np.full(model.config.grids[s].size, np.nan))
        patches.append(row)
        titles.append(f"#{rank + 1} by |weight|")
    save_template_figure(patches, model.config.grids, titles, model.config.scale_names, path)
    return True
