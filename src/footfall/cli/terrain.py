"""``footfall terrain``: make, import and look at terrain height maps."""

from __future__ import annotations

import click

from footfall.cli.choices import SEED, TERRAIN_KIND, ChoiceArgument, Finite
from footfall.cli.output import emit, json_option
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


@terrain.command("import")
@click.argument("source")
@click.option("--resolution", type=Finite(min=0.0, min_open=True), default=None,
              help="Cell size [m] (required for .npy, .png and point clouds).")
@click.option("--z-scale", type=Finite(min=0.0, min_open=True), default=None,
              help="Metres per raw height unit (required for 16-bit PNG).")
@click.option("--nodata", type=Finite(), default=None, help="Raw value that means no data.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_import(source: str, resolution: float | None, z_scale: float | None,
                   nodata: float | None, output: str, as_json: bool) -> None:
    """Import SOURCE (.npy, 16-bit .png, .ply, .xyz, .npz) as a footfall height map."""
    _emit_map(as_json, save_imported(source, output, resolution=resolution, z_scale=z_scale,
                                     nodata=nodata))


@terrain.command("show")
@click.argument("source")
@click.option("-o", "--output", required=True, help="Output picture (.png).")
@json_option
def terrain_show(source: str, output: str, as_json: bool) -> None:
    """Draw a shaded relief of a height map with a colour bar."""
    out = save_relief_of_file(source, output)
    emit(as_json, {"file": str(out), "source": str(source)}, f"wrote {out}")
