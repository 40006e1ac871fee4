"""``footfall features``: the terrain features and template patches of one foothold."""

from __future__ import annotations

import math

import click

from footfall.cli.choices import LEG, Finite
from footfall.cli.output import emit, json_option
from footfall.core.heightmap import HeightMap
from footfall.features.config import FeatureConfig
from footfall.features.describe import describe_foothold


@click.command()
@click.argument("source")
@click.option("--at", "at", nargs=2, type=Finite(-1e6, 1e6), required=True, metavar="X Y",
              help="Foothold position [m].")
@click.option("--yaw", type=Finite(-2 * math.pi, 2 * math.pi), default=0.0, show_default=True,
              help="Body heading [rad] that orients the patches, in [-2 pi, 2 pi].")
@click.option("--leg", type=LEG, default="LF", show_default=True,
              help="Swing leg (right legs see mirrored patches).")
@click.option("--template-resolution", type=Finite(min=0, min_open=True), default=None,
              help="Patch sample spacing [m] (default 0.003).")
@json_option
def features(source: str, at: tuple[float, float], yaw: float, leg: str,
             template_resolution: float | None, as_json: bool) -> None:
    """The 27 terrain features and three template patches of a foothold."""
    hmap = HeightMap.load(source)
    config = FeatureConfig() if template_resolution is None else FeatureConfig(template_resolution)
    info = describe_foothold(hmap, at[0], at[1], yaw, leg, config)
    lines = [f"foothold ({at[0]:.4f}, {at[1]:.4f}) m, height {info['height'] * 1000:.2f} mm, "
             f"leg {leg}, yaw {yaw:.3f} rad"]
    lines += [f"  {name:24s} {value: .6g}" for name, value in info["terrain_features"].items()]
    lines += [f"  patch {n}: {p['shape'][0]} x {p['shape'][1]} samples at "
              f"{p['resolution'] * 1000:g} mm (use --json for the heights)"
              for n, p in info["patches"].items()]
    emit(as_json, info, "\n".join(lines))
