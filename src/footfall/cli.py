"""The ``footfall`` command line.

Every command has ``--help`` and ``--json``. A user error (a bad file, a bad
argument) prints one line on standard error and exits with status 2; a
traceback only with ``--debug``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import click

from footfall.errors import FootfallError

EXIT_USER_ERROR = 2


def _emit(as_json: bool, data: dict[str, Any], text: str) -> None:
    if as_json:
        click.echo(json.dumps(data, indent=2, allow_nan=False))
    else:
        click.echo(text)


def _out_path(path: str) -> Path:
    p = Path(path)
    if p.exists() and p.is_dir():
        raise FootfallError(f"output path is a directory: {p}")
    if not p.parent.exists():
        raise FootfallError(f"output directory does not exist: {p.parent}")
    return p


json_option = click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks for errors.")
@click.version_option(package_name="footfall")
def cli(debug: bool) -> None:
    """footfall: learning where a legged robot should put its feet, with terrain templates."""


# ------------------------------------------------------------------- terrain
@cli.group()
def terrain() -> None:
    """Make, import and look at terrain height maps."""


def _map_summary(hmap, path: Path) -> tuple[dict, str]:
    import numpy as np

    h = hmap.heights
    data = {"file": str(path), "shape": list(hmap.shape), "resolution": hmap.resolution,
            "origin": list(hmap.origin), "bounds": list(hmap.bounds),
            "height_min": float(np.nanmin(h)), "height_max": float(np.nanmax(h)),
            "no_data_fraction": float(np.isnan(h).mean()), "hash": hmap.content_hash(),
            "metadata": hmap.metadata}
    text = (f"wrote {path}: {hmap.shape[0]} x {hmap.shape[1]} cells at "
            f"{hmap.resolution * 1000:g} mm, {hmap.length[0]:.3f} x {hmap.length[1]:.3f} m, "
            f"heights {data['height_min'] * 1000:.1f} .. {data['height_max'] * 1000:.1f} mm")
    return data, text


@terrain.command("make")
@click.argument("kind")
@click.option("--difficulty", type=float, default=0.5, show_default=True,
              help="Difficulty in [0, 1].")
@click.option("--seed", type=int, required=True, help="Random seed.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_make(kind: str, difficulty: float, seed: int, output: str, as_json: bool) -> None:
    """Make one 61 x 61 cm terrain module of KIND (flat, steps, barrier, slope, logs, rocky)."""
    from footfall.terrain import make_module

    out = _out_path(output)
    hmap = make_module(kind, difficulty, seed)
    hmap.save(out)
    _emit(as_json, *_map_summary(hmap, out))


@terrain.command("board")
@click.argument("specs", nargs=-1, required=True, metavar="KIND[:DIFFICULTY]...")
@click.option("--seed", type=int, required=True, help="Random seed.")
@click.option("--flat-ends/--no-flat-ends", default=True, show_default=True,
              help="Add a flat start and end module unless the row already has them.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_board(specs: tuple[str, ...], seed: int, flat_ends: bool, output: str,
                  as_json: bool) -> None:
    """Make a board: modules in a row along x, e.g. `rocky:0.5 rocky:0.8`."""
    from footfall.terrain import make_board, parse_module_spec

    out = _out_path(output)
    hmap = make_board([parse_module_spec(s) for s in specs], seed, flat_ends=flat_ends)
    hmap.save(out)
    _emit(as_json, *_map_summary(hmap, out))


@terrain.command("import")
@click.argument("source")
@click.option("--resolution", type=float, default=None,
              help="Cell size [m] (required for .npy, .png and point clouds).")
@click.option("--z-scale", type=float, default=None,
              help="Metres per raw height unit (required for 16-bit PNG).")
@click.option("--nodata", type=float, default=None, help="Raw value that means no data.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_import(source: str, resolution: float | None, z_scale: float | None,
                   nodata: float | None, output: str, as_json: bool) -> None:
    """Import SOURCE (.npy, 16-bit .png, .ply, .xyz, .npz) as a footfall height map."""
    from footfall.terrain_io import import_terrain

    out = _out_path(output)
    hmap = import_terrain(source, resolution=resolution, z_scale=z_scale, nodata=nodata)
    hmap.save(out)
    _emit(as_json, *_map_summary(hmap, out))


@terrain.command("show")
@click.argument("source")
@click.option("-o", "--output", required=True, help="Output picture (.png).")
@json_option
def terrain_show(source: str, output: str, as_json: bool) -> None:
    """Draw a shaded relief of a height map with a colour bar."""
    from footfall.heightmap import HeightMap
    from footfall.plots.relief import save_relief

    out = _out_path(output)
    hmap = HeightMap.load(source)
    save_relief(hmap, out, title=Path(source).name)
    _emit(as_json, {"file": str(out), "source": str(source)}, f"wrote {out}")


# ------------------------------------------------------------------ features
@cli.command()
@click.argument("source")
@click.option("--at", "at", nargs=2, type=float, required=True, metavar="X Y",
              help="Foothold position [m].")
@click.option("--yaw", type=float, default=0.0, show_default=True,
              help="Body heading [rad] that orients the patches.")
@click.option("--leg", type=click.Choice(["LF", "RF", "LH", "RH"]), default="LF",
              show_default=True, help="Swing leg (right legs see mirrored patches).")
@click.option("--template-resolution", type=float, default=None,
              help="Patch sample spacing [m] (default 0.003).")
@json_option
def features(source: str, at: tuple[float, float], yaw: float, leg: str,
             template_resolution: float | None, as_json: bool) -> None:
    """The 27 terrain features and three template patches of a foothold."""
    from footfall.foothold_info import describe_foothold
    from footfall.heightmap import HeightMap
    from footfall.scales import FeatureConfig

    hmap = HeightMap.load(source)
    config = FeatureConfig() if template_resolution is None else FeatureConfig(template_resolution)
    info = describe_foothold(hmap, at[0], at[1], yaw, leg, config)
    lines = [f"foothold ({at[0]:.4f}, {at[1]:.4f}) m, height {info['height'] * 1000:.2f} mm, "
             f"leg {leg}, yaw {yaw:.3f} rad"]
    lines += [f"  {name:24s} {value: .6g}" for name, value in info["terrain_features"].items()]
    lines += [f"  patch {n}: {p['shape'][0]} x {p['shape'][1]} samples at "
              f"{p['resolution'] * 1000:g} mm (use --json for the heights)"
              for n, p in info["patches"].items()]
    _emit(as_json, info, "\n".join(lines))


# --------------------------------------------------------------------- bench
@cli.group()
def bench() -> None:
    """Benchmarks: print figures, compared with a baseline run in the same process."""


@bench.command("scoring")
@click.option("--repeats", type=click.IntRange(1, 100), default=7, show_default=True)
@click.option("--baseline-sample", type=click.IntRange(10, 100000), default=300,
              show_default=True, help="Candidates timed with the per-candidate loop.")
@json_option
def bench_scoring_cmd(repeats: int, baseline_sample: int, as_json: bool) -> None:
    """Dense scoring of a 3-module board at 5 mm with 60 templates and 27 features."""
    from footfall.bench import bench_scoring, format_scoring

    result = bench_scoring(repeats=repeats, baseline_sample=baseline_sample)
    _emit(as_json, result, format_scoring(result))


# ---------------------------------------------------------------------- demo
@cli.command()
@click.option("--out", "out", default="out/demo", show_default=True, help="Output folder.")
@click.option("--seed", type=int, default=0, show_default=True)
@json_option
def demo(out: str, seed: int, as_json: bool) -> None:
    """Build a board, score it densely and draw the terrain, features and templates."""
    from footfall.demo import run_demo

    result = run_demo(Path(out), seed=seed)
    _emit(as_json, result, "\n".join(f"wrote {p}" for p in result["files"]))


def main(argv: list[str] | None = None) -> int:
    """Entry point: run the CLI, turning user errors into one line and exit status 2."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    try:
        cli.main(args=args, prog_name="footfall", standalone_mode=False)
    except FootfallError as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {exc}", err=True)
        return EXIT_USER_ERROR
    except click.exceptions.Abort:
        click.echo("footfall: interrupted", err=True)
        return 130
    except click.ClickException as exc:
        if debug:
            raise
        message = " ".join(exc.format_message().split())
        click.echo(f"footfall: error: {message} (see --help)", err=True)
        return EXIT_USER_ERROR
    except (OSError, MemoryError) as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {exc}", err=True)
        return EXIT_USER_ERROR
    return 0


def _console() -> None:  # pragma: no cover - the console script
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
