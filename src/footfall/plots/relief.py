"""Shaded-relief pictures of height maps.

A hillshade (matplotlib's LightSource, light from the north-west) blended
with a terrain colour map, drawn in metres with x to the right and y up.
Uses matplotlib figure objects directly (no pyplot), so it is safe headless.
"""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colors import LightSource, ListedColormap, Normalize
from matplotlib.figure import Figure
from matplotlib.image import AxesImage

from footfall.core.atomic import atomic_path
from footfall.core.errors import FootfallError
from footfall.core.files import writable_path
from footfall.core.heightmap import HeightMap

# Land part of matplotlib's "terrain" map (its low end is sea blue).
RELIEF_CMAP = ListedColormap(matplotlib.colormaps["terrain"](np.linspace(0.25, 0.95, 256)),
                             name="footfall_relief")
NO_DATA_RGB = (0.55, 0.55, 0.58)  # [-] RGB of cells with no data (NaN): a neutral grey
LIGHT_AZIMUTH = 315.0  # [deg] direction the light comes from, clockwise from +y (north-west)
LIGHT_ALTITUDE = 45.0  # [deg] elevation of the light above the horizon
VERTICAL_EXAGGERATION = 2.0  # [-] slope exaggeration for the hillshade only
MM_PER_M = 1000.0  # [mm/m] heights are shown in millimetres
DPI = 150  # [dots/inch] resolution of saved pictures


def draw_relief(ax: Axes, hmap: HeightMap, *, vmin: float | None = None,
                vmax: float | None = None, title: str | None = None,
                colorbar: bool = True) -> AxesImage:
    """Draw a height map as a shaded relief on ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on (of a :class:`matplotlib.figure.Figure`).
    hmap : HeightMap
        The map; ``heights[i, j]`` is at (x_i, y_j), x is drawn to the right
        and y up, axes in [m] spanning ``hmap.bounds``.
    vmin, vmax : float, optional
        Heights [m] at the ends of the colour scale; default the map's
        minimum and maximum (ignoring NaN).
    title : str, optional
        Axes title.
    colorbar : bool
        Add a colour bar labelled "height [mm]" beside ``ax``.

    Returns
    -------
    matplotlib.image.AxesImage
        The RGB image drawn (cells with no data in grey).
    """
    heights = hmap.heights.T  # rows y, columns x: imshow with origin="lower"
    missing = np.isnan(heights)
    lo = float(np.nanmin(heights)) if vmin is None else float(vmin)
    hi = float(np.nanmax(heights)) if vmax is None else float(vmax)
    if hi <= lo:  # a flat map: centre it on a small band
        lo, hi = lo - 0.001, hi + 0.001
    filled = np.where(missing, np.nanmean(heights), heights)
    light = LightSource(azdeg=LIGHT_AZIMUTH, altdeg=LIGHT_ALTITUDE)
    norm = Normalize(lo * MM_PER_M, hi * MM_PER_M, clip=True)
    # LightSource assumes row 0 at the top; ours is at the bottom, hence dy < 0.
    rgb = light.shade(filled * MM_PER_M, cmap=RELIEF_CMAP, norm=norm, blend_mode="soft",
                      vert_exag=VERTICAL_EXAGGERATION, dx=hmap.resolution * MM_PER_M,
                      dy=-hmap.resolution * MM_PER_M)[..., :3]
    rgb[missing] = NO_DATA_RGB
    image = ax.imshow(rgb, origin="lower", extent=hmap.bounds, interpolation="antialiased")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if title is not None:
        ax.set_title(title, parse_math=False)  # a file name is text, not mathtext
    if colorbar:
        mappable = ScalarMappable(norm=norm, cmap=RELIEF_CMAP)
        ax.figure.colorbar(mappable, ax=ax, label="height [mm]", shrink=0.9)
    return image


def save_relief(hmap: HeightMap, path: str | os.PathLike, title: str | None = None) -> None:
    """Write a shaded relief of ``hmap`` as a PNG file (atomically).

    Parameters
    ----------
    hmap : HeightMap
        The map to draw.
    path : str or os.PathLike
        Output file; written as PNG whatever its suffix.
    title : str, optional
        Picture title.

    Raises
    ------
    FootfallError
        If the output directory does not exist.
    """
    x_len, y_len = hmap.length  # [m]
    width = 8.0  # [inch]
    height = float(np.clip(width * y_len / x_len, 1.5, 12.0)) + 1.0  # [inch] with labels
    fig = Figure(figsize=(width + 1.5, height), layout="constrained")
    draw_relief(fig.add_subplot(), hmap, title=title)
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=DPI)
    except OSError as exc:
        raise FootfallError(f"cannot write {path}: {exc}") from None


def save_relief_of_file(source: str | os.PathLike, path: str | os.PathLike) -> Path:
    """Write the shaded relief of the height-map file ``source``, titled with its name.

    Returns the path written. Raises :class:`FootfallError` for a bad output
    path (checked first) or a file that is not a readable height map.
    """
    out = writable_path(path, (".png",), kind="picture", inputs=(source,))
    save_relief(HeightMap.load(source), out, title=Path(source).name)
    return out
