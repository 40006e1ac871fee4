"""``footfall score``: a foothold scorer's value at every cell of a map, written as a layer."""

from __future__ import annotations

import math

import click

import footfall.expert.scorer  # noqa: F401  (registers the expert's own value as a scorer)
from footfall.cli.choices import LEG, Finite
from footfall.cli.output import emit, json_option
from footfall.core.errors import FootfallError
from footfall.core.files import writable_path
from footfall.core.robot import LITTLEDOG
from footfall.features.map_scores import score_layer
from footfall.features.scorer import SCORERS
from footfall.learning.model import FootholdModel
from footfall.terrain.grid_map import DEFAULT_LAYER, SCORE_LAYER
from footfall.terrain.layer_files import LAYER_SUFFIXES, write_layers
from footfall.terrain.scans import import_terrain


@click.command("score")
@click.argument("source", metavar="MAP")
@click.option("--model", "model_path", default=None, metavar="MODEL.npz",
              help="Score with a learned model's function for the leg.")
@click.option("--reward", default=None, metavar="NAME",
              help="Score with a named scorer instead: hand-tuned (the default) or expert.")
@click.option("--leg", type=LEG, default="LF", show_default=True,
              help="The leg whose footholds are scored (right legs mirror the patches).")
@click.option("--heading", type=Finite(-2 * math.pi, 2 * math.pi), default=0.0,
              show_default=True, help="The body's heading [rad] that orients the patches.")
@click.option("-o", "--output", required=True,
              help="Output: .npz, a GeoTIFF (.tif) or a ROS 2 bag (.mcap or .db3) with the "
                   "layers elevation and footfall_score.")
@json_option
def score_cmd(source: str, model_path: str | None, reward: str | None, leg: str,
              heading: float, output: str, as_json: bool) -> None:
    """Score every cell of MAP with a foothold scorer and write the scores as a layer.

    MAP is any map `footfall terrain import` reads with its defaults (a footfall .npz,
    a GeoTIFF in metres, a bag with one GridMap topic ...). A cell's score is the
    scorer's terrain value of a foothold there; no score (NaN) where it is not a valid
    foothold. A GeoTIFF keeps the input's georeference, a bag the map's frame.
    """
    if model_path is not None and reward is not None:
        raise FootfallError("give --model or --reward, not both")
    out = writable_path(output, LAYER_SUFFIXES, kind="score layer", inputs=(source, model_path))
    hmap = import_terrain(source)
    if model_path is not None:
        model = FootholdModel.load(model_path)
        model.check_compatible(robot=LITTLEDOG)
        scorer, name = model.reward_for(leg), f"model {model_path}"
    else:
        name = reward or "hand-tuned"
        scorer = SCORERS.get(name)(None)
    layer = score_layer(hmap, scorer, leg, heading)
    write_layers(out, {DEFAULT_LAYER: hmap.heights, SCORE_LAYER: layer.values}, hmap,
                 {"scorer": name, "leg": leg, "heading": heading,
                  "interpolated": layer.interpolated})
    note = (f"; the map's {hmap.resolution * 1000:g} mm cells are coarser than the scorer's "
            f"{scorer.config.template_resolution * 1000:g} mm patch samples: its heights are "
            "interpolated" if layer.interpolated else "")
    emit(as_json, {"file": str(out), "source": source, "scorer": name, "leg": leg,
                   "heading": heading, "shape": list(hmap.shape),
                   "valid_share": layer.valid_share, "interpolated": layer.interpolated},
         f"wrote {out}: {SCORE_LAYER} of {name} for {leg} at heading {heading:g} rad, "
         f"{hmap.shape[0]} x {hmap.shape[1]} cells, {layer.valid_share:.1%} valid footholds"
         f"{note}")
