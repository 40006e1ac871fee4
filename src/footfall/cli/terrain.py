"""``footfall terrain``: make, import and look at terrain height maps."""

from __future__ import annotations

import click

from footfall.cli.choices import SEED, TERRAIN_KIND, ChoiceArgument, Finite
from footfall.cli.output import emit, json_option
from footfall.core.errors import FootfallError
from footfall.plots.relief import save_relief_of_file
from footfall.terrain.saving import MapSummary, save_board, save_imported, save_module


@click.group()
def terrain() -> None:
    """Make, import and look at terrain height maps."""


def _emit_map(as_json: bool, summary: MapSummary, notes: tuple[str, ...] = ()) -> None:
    """A written map's summary: JSON, or one line with its size [mm, m] and heights [mm]
    (then any ``notes``, one a line)."""
    text = (f"wrote {summary.file}: {summary.shape[0]} x {summary.shape[1]} cells at "
            f"{summary.resolution * 1000:g} mm, {summary.length[0]:.3f} x "
            f"{summary.length[1]:.3f} m, heights {summary.height_min * 1000:.1f} .. "
            f"{summary.height_max * 1000:.1f} mm")
    emit(as_json, summary.as_dict(), "\n".join((text, *notes)))


def _file_module_notes(summary: MapSummary) -> tuple[str, ...]:
    """One line per module of a board made from a file: where it lies and how it was fitted."""
    notes = []
    for k, m in enumerate(summary.metadata.get("modules", [])):
        if m.get("kind") == "file":
            fit = {"exact": "as wide as the board", "padded": "padded with no data to the "
                   "board's width", "cropped": "cropped to the board's width"}[m["width_fit"]]
            notes.append(f"  module {k}: {m['file']} ({m['resolution'] * 1000:g} mm, "
                         f"{m['width']:.3f} m wide) at x {m['x_start']:.3f} .. "
                         f"{m['x_end']:.3f} m, {fit} (centred in y), heights shifted by "
                         f"{m['z_shift'] * 1000:+.1f} mm")
    return tuple(notes)


@terrain.command("make")
@click.argument("kind", type=TERRAIN_KIND, cls=ChoiceArgument)
@click.option("--difficulty", type=Finite(0.0, 1.0), default=0.5, show_default=True,
              help="Difficulty in [0, 1].")
@click.option("--seed", type=SEED, required=True, help="Random seed.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_make(kind: str, difficulty: float, seed: int, output: str, as_json: bool) -> None:
    """Make one 61 x 61 cm terrain module of KIND."""
    _emit_map(as_json, save_module(kind, difficulty, seed, output))


@terrain.command("board")
@click.argument("specs", nargs=-1, required=True, metavar="KIND[:DIFFICULTY]|FILE.npz...")
@click.option("--seed", type=SEED, required=True, help="Random seed.")
@click.option("--flat-ends/--no-flat-ends", default=True, show_default=True,
              help="Add a flat start and end module unless the row already has them.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_board(specs: tuple[str, ...], seed: int, flat_ends: bool, output: str,
                  as_json: bool) -> None:
    """Make a board: modules in a row along x, e.g. `rocky:0.5 rocky:0.8`.

    KIND is one of the kinds `footfall terrain make --help` lists. A FILE.npz
    (a footfall height map, e.g. from `footfall terrain import`) is a module
    too, e.g. `flat my_scan.npz rocky:0.5`: resampled to 1 mm, its own length,
    padded (no data) or cropped to the board's width, lowest point at z = 0.
    """
    summary = save_board(specs, seed, output, flat_ends=flat_ends)
    _emit_map(as_json, summary, _file_module_notes(summary))


def _classes(value: str | None) -> tuple[int, ...] | None:
    """``--classes 2,6`` as class numbers 0-255; refused in one line otherwise."""
    if value is None:
        return None
    try:
        classes = tuple(int(c) for c in value.split(","))
    except ValueError:
        raise FootfallError(f"--classes must be class numbers separated by commas (e.g. 2 or "
                            f"2,6), got {value!r}") from None
    if not all(0 <= c <= 255 for c in classes):
        raise FootfallError(f"--classes must be ASPRS class numbers 0 .. 255, got {value!r}")
    return classes


def _import_notes(summary: MapSummary) -> tuple[str, ...]:
    """What an import chose where the user did not: a bag's topic and message, a cloud's
    class filter, a raster's band and window, and where a georeferenced map lies."""
    meta = summary.metadata
    notes = []
    if meta.get("source_format") == "ros2-bag":
        notes.append(f"  {meta['topic']}, layer {meta['layer']} (of "
                     f"{', '.join(meta['layers'])}), message {meta['message']} of "
                     f"{meta['messages']} (at {meta['time']:.3f} s)")
    if "class_filter" in meta:
        notes.append(f"  points kept: {meta['class_filter']}, {meta['points_used']} of "
                     f"{meta['points_in_file']}; {meta['rasterization']}")
    if "band" in meta:
        notes.append(f"  band {meta['band']} ({meta['band_dtype']}), window "
                     f"{meta['window']} of {meta['raster_size']} pixels; cell size from "
                     f"{meta['cell_size_from']}")
    if "georeference" in meta:
        t = meta["georeference"]["transform"]
        notes.append(f"  local frame: cell (0, 0) at (0, 0); the raster's top-left corner at "
                     f"({t[2]:.3f}, {t[5]:.3f}) in the file's coordinates, kept in the map")
    return tuple(notes)


@terrain.command("import")
@click.argument("source")
@click.option("--resolution", type=Finite(min=0.0, min_open=True), default=None,
              help="Cell size [m] (required for .npy, .png and point clouds; for a GeoTIFF "
                   "in degrees or feet, its pixel size in metres).")
@click.option("--z-scale", type=Finite(min=0.0, min_open=True), default=None,
              help="Metres per raw height unit (required for 16-bit PNG).")
@click.option("--nodata", type=Finite(), default=None, help="Raw value that means no data.")
@click.option("--topic", default=None, help="ROS 2 bag: the GridMap topic (needed where the "
              "bag holds several; they are listed).")
@click.option("--layer", default=None,
              help="ROS 2 bag: the map's layer [default: elevation].")
@click.option("--message", type=int, default=None,
              help="ROS 2 bag: the message's index on the topic, negative from the end "
                   "[default: the last].")
@click.option("--time", "at_time", type=Finite(), default=None, metavar="SECONDS",
              help="ROS 2 bag: the last message at or before this time since the bag's start.")
@click.option("--classes", default=None, metavar="N[,N...]",
              help="LAS / LAZ: the point classes kept [default: ground (class 2) where the "
                   "file classifies points, else every point].")
@click.option("--statistic", type=click.Choice(["max", "min", "mean"]), default=None,
              help="LAS / LAZ: a cell's height from its points [default: max, the highest "
                   "return].")
@click.option("--band", type=click.IntRange(min=1), default=None,
              help="GeoTIFF: the band read [default: 1].")
@click.option("--bounds", nargs=4, type=Finite(), default=None,
              metavar="XMIN YMIN XMAX YMAX",
              help="GeoTIFF: read only this window, in the file's coordinates.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_import(source: str, resolution: float | None, z_scale: float | None,
                   nodata: float | None, topic: str | None, layer: str | None,
                   message: int | None, at_time: float | None, classes: str | None,
                   statistic: str | None, band: int | None,
                   bounds: tuple[float, ...] | None, output: str, as_json: bool) -> None:
    """Import SOURCE as a footfall height map: .npy, 16-bit .png, .ply, .xyz, .npz, a ROS 2
    bag of grid_map_msgs/GridMap (a bag folder, .mcap or .db3), a LAS / LAZ point cloud or
    a GeoTIFF (.tif)."""
    summary = save_imported(source, output, resolution=resolution, z_scale=z_scale,
                            nodata=nodata, topic=topic, layer=layer, message=message,
                            time=at_time, classes=_classes(classes), statistic=statistic,
                            band=band, bounds=tuple(bounds) if bounds else None)
    _emit_map(as_json, summary, _import_notes(summary))


@terrain.command("show")
@click.argument("source")
@click.option("-o", "--output", required=True, help="Output picture (.png).")
@json_option
def terrain_show(source: str, output: str, as_json: bool) -> None:
    """Draw a shaded relief of a height map with a colour bar."""
    out = save_relief_of_file(source, output)
    emit(as_json, {"file": str(out), "source": str(source)}, f"wrote {out}")
