"""``footfall demo``: a board scored densely with the hand-tuned reward, drawn.

Builds a flat | rocky | rocky | flat board, scores every 5 mm lattice point
with the hand-tuned default reward, computes dense maps of a few terrain
features, extracts templates at the best and worst footholds, and writes
pictures plus a short report.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from footfall.core.atomic import write_text_atomic
from footfall.core.errors import FootfallError
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.reward import LinearReward, analytic_templates, default_reward
from footfall.features.template_library import extract_templates
from footfall.features.terrain_features import TerrainFeatures
from footfall.plots.maps import save_score_maps, save_template_figure
from footfall.plots.relief import save_relief
from footfall.terrain import make_board

DEMO_BOARD = [("rocky", 0.4), ("rocky", 0.9)]  # between the flat start and end modules
FEATURE_MAPS = ("medium.slope_x_neg", "medium.std", "small.curv_x_pos", "large.std")


def feature_map(board, name: str, config: FeatureConfig, **kwargs):
    """Dense map of one terrain feature: a reward with weight 1 on it and 0 elsewhere."""
    terrain = TerrainFeatures(config)
    reward = LinearReward.from_names((terrain,), {f"terrain.{name}": 1.0}, config, name)
    return score_grid(board, reward, **kwargs)


def run_demo(out: Path, seed: int = 0) -> dict:
    """Write the demo's files into ``out`` and return a summary."""
    if out.exists() and not out.is_dir():
        raise FootfallError(f"output path is not a directory: {out}")
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    board = make_board(DEMO_BOARD, seed)
    board.save(out / "board.npz")
    save_relief(board, out / "terrain.png", title="flat | rocky 0.4 | rocky 0.9 | flat")

    reward = default_reward()
    config = reward.config
    t0 = time.perf_counter()
    grid = score_grid(board, reward)
    scoring_s = time.perf_counter() - t0
    save_score_maps([grid], ["hand-tuned default reward, left legs, heading +x"], ["reward"],
                    out / "reward.png")
    maps = [feature_map(board, n, config) for n in FEATURE_MAPS]
    units = {"slope": "[-]", "curv": "[1/m]", "std": "[m]"}
    save_score_maps(maps, list(FEATURE_MAPS),
                    [units[n.split(".")[1].split("_")[0]] for n in FEATURE_MAPS],
                    out / "features.png", cmap="magma")

    # Templates: the Fig. 2 library, and patches at the best and worst footholds
    # on the rocky modules.
    library, names = analytic_templates(config)
    rocky = (grid.positions[:, 0] > 0.62) & (grid.positions[:, 0] < 1.82)
    flat_reward = grid.reward.ravel()
    order = np.argsort(np.where(rocky & np.isfinite(flat_reward), flat_reward, np.nan))
    order = order[np.isfinite(flat_reward[order]) & rocky[order]]
    picks = {"best foothold": grid.positions[order[-1]],
             "worst foothold": grid.positions[order[0]]}
    rows = [[t[k] for t in library.templates] for k in range(len(names))]
    titles = [n.replace("_", " ") for n in names]
    for label, pos in picks.items():
        lib = extract_templates(board, pos[None], 0.0, False, config)
        if all(c == 1 for c in lib.counts):
            rows.append([t[0] for t in lib.templates])
            titles.append(f"{label}\n({pos[0]:.3f}, {pos[1]:.3f})")
    save_template_figure(rows, config.grids, titles, config.scale_names, out / "templates.png")

    files = [out / f for f in ("board.npz", "terrain.png", "reward.png", "features.png",
                               "templates.png", "summary.json", "README.md")]
    summary = {
        "board": {"modules": board.metadata.get("modules"), "shape": list(board.shape),
                  "resolution_m": board.resolution, "hash": board.content_hash()},
        "lattice_points": int(grid.reward.size), "valid_footholds": int(grid.valid.sum()),
        "dense_scoring_seconds": scoring_s,
        "reward": {"name": reward.name, "weights": reward.named_weights()},
        "best_foothold": [float(v) for v in picks["best foothold"]],
        "worst_foothold": [float(v) for v in picks["worst foothold"]],
        "total_seconds": time.perf_counter() - started,
        "files": [str(f) for f in files],
    }
    write_text_atomic(out / "summary.json", json.dumps(summary, indent=2))
    write_text_atomic(out / "README.md", _report(summary))
    return summary


def _report(s: dict) -> str:
    return f"""# footfall demo

A flat | rocky (0.4) | rocky (0.9) | flat board of {s['board']['shape'][0]} x {s['board']['shape'][1]}
cells at {s['board']['resolution_m'] * 1000:g} mm, scored at {s['lattice_points']} lattice points
(5 mm) with the hand-tuned default reward in {s['dense_scoring_seconds'] * 1000:.0f} ms;
{s['valid_footholds']} points are valid footholds.

![terrain](terrain.png)

Reward (terrain features + the three templates of the paper's Fig. 2):

![reward](reward.png)

Dense terrain feature maps:

![features](features.png)

Templates on the three scales (flat, mild hollow, deep hole; then the patches at the
best and the worst foothold of the rocky modules):

![templates](templates.png)
"""
