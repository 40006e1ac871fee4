"""Benchmark of dense scoring: the whole board at once against a per-candidate loop.

``bench_scoring``: dense scoring of a 3-module board (flat | rocky | flat,
1.83 x 0.61 m at 1 mm) at 5 mm candidate spacing (~45 000 candidates) with
60 templates (20 per scale) and the 27 terrain features, against a plain
per-candidate loop of the same definitions (timed on a sample of candidates
and extrapolated), with the floating-point work and the peak memory.
"""

from __future__ import annotations

import platform
import time
import tracemalloc

import numpy as np

from footfall.core.compute import usable_cores
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.family import Candidates
from footfall.features.reward import LinearReward
from footfall.features.template_library import TemplateLibrary, extract_templates
from footfall.features.templates import TemplateFeatures
from footfall.features.terrain_features import TerrainFeatures, feature_names
from footfall.terrain import make_board

TEMPLATES_PER_SCALE = 20  # the benchmark: 60 templates in all


BENCH_TEMPLATE_RMS = 0.005  # [m] RMS height difference at which a match scores exp(-1)


def benchmark_reward(board, config: FeatureConfig, rng: np.random.Generator) -> LinearReward:
    """A reward with 20 templates per scale taken from the rocky module and random weights."""
    pos = np.column_stack([rng.uniform(0.65, 1.18, 200), rng.uniform(-0.22, 0.22, 200)])
    lib = extract_templates(board, pos, 0.0, False, config)
    keep = tuple(np.arange(TEMPLATES_PER_SCALE) for _ in lib.templates)
    lib = lib.subset(keep)
    terrain = TerrainFeatures(config)
    templates = TemplateFeatures(config, lib).with_rms((BENCH_TEMPLATE_RMS,) * len(config.scales))
    terrain_weights = rng.normal(size=len(terrain.columns()))
    template_weights = np.concatenate([rng.normal(size=c) for c in lib.counts])
    return LinearReward((terrain, templates), (terrain_weights, template_weights), config,
                        "benchmark")


def _flops(n: int, config: FeatureConfig, lib: TemplateLibrary) -> float:
    """Floating-point operations of dense scoring (multiply-adds count 2)."""
    total = 0.0
    for grid, t in zip(config.grids, lib.templates):
        cols = t.shape[0] + 5  # templates, 4 fit kernels, a sum
        total += n * grid.size * (2 * cols + 3)  # matrix product, squares, centring
        total += n * t.shape[0] * 6  # distances, exponentials, weights
    return total


def bench_scoring(repeats: int = 7, baseline_sample: int = 300, seed: int = 0) -> dict:
    """Time dense scoring against a per-candidate loop; return the figures."""
    rng = np.random.default_rng(seed)
    config = FeatureConfig()
    board = make_board([("rocky", 0.5)], seed)
    reward = benchmark_reward(board, config, rng)

    t0 = time.perf_counter()
    grid = score_grid(board, reward)
    first = time.perf_counter() - t0
    times, times64 = [], []
    for _ in range(repeats):  # alternate the two precisions: both see the same machine load
        t0 = time.perf_counter()
        grid = score_grid(board, reward)
        times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        grid64 = score_grid(board, reward, dtype=np.float64)
        times64.append(time.perf_counter() - t0)
    dense = float(np.median(times))
    finite = np.isfinite(grid64.reward)
    float32_error = float(np.max(np.abs(grid.reward[finite] - grid64.reward[finite]))
                          / np.max(np.abs(grid64.reward[finite])))
    tracemalloc.start()
    score_grid(board, reward)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()

    # Baseline: the same definitions, one candidate at a time.
    pts = grid.positions
    sample = rng.choice(pts.shape[0], size=min(baseline_sample, pts.shape[0]), replace=False)
    loop_values = np.empty(sample.size)
    t0 = time.perf_counter()
    for k, idx in enumerate(sample):  # the slow reference: one candidate per iteration
        loop_values[k] = reward.terrain_values(
            Candidates(board, pts[idx:idx + 1], 0.0, False, config))[0]
    per_candidate = (time.perf_counter() - t0) / sample.size
    loop_total = per_candidate * pts.shape[0]
    dense_values = grid64.reward.ravel()[sample]
    both = np.isfinite(loop_values) & np.isfinite(dense_values)
    library = reward.family("templates")[0].library
    flops = _flops(pts.shape[0], config, library)
    return {
        "board": "flat | rocky 0.5 | flat, 1.83 x 0.61 m at 1 mm",
        "candidates": int(pts.shape[0]),
        "spacing_m": 0.005,
        "templates": list(library.counts),
        "terrain_features": len(feature_names(config)),
        "template_resolution_m": config.template_resolution,
        "dense_seconds_median": dense,
        "dense_seconds_all": times,
        "dense_seconds_first_call": first,
        "dense_float64_seconds_median": float(np.median(times64)),
        "float32_max_relative_difference": float32_error,
        "target_seconds": 0.04,
        "baseline_per_candidate_seconds": per_candidate,
        "baseline_sample": int(sample.size),
        "baseline_seconds_extrapolated": loop_total,
        "speedup_vs_loop": loop_total / dense,
        "max_abs_difference_vs_loop": float(np.max(np.abs(loop_values[both] - dense_values[both])))
        if both.any() else None,
        "gflop": flops / 1e9,
        "gflop_per_second": flops / dense / 1e9,
        "peak_memory_mib": peak / 2 ** 20,
        "cores": usable_cores(),
        "machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
        "numpy": np.__version__,
    }


def format_scoring(r: dict) -> str:
    """Human-readable summary of :func:`bench_scoring`."""
    return "\n".join([
        f"dense scoring: {r['candidates']} candidates ({r['board']}), "
        f"{sum(r['templates'])} templates + {r['terrain_features']} terrain features",
        f"  dense:    {r['dense_seconds_median'] * 1000:8.1f} ms median of "
        f"{len(r['dense_seconds_all'])} (first call {r['dense_seconds_first_call'] * 1000:.1f} ms;"
        f" target {r['target_seconds'] * 1000:.0f} ms)",
        f"  float64:  {r['dense_float64_seconds_median'] * 1000:8.1f} ms median "
        f"(float32 differs by {r['float32_max_relative_difference']:.1e} of the reward scale)",
        f"  loop:     {r['baseline_seconds_extrapolated'] * 1000:8.1f} ms extrapolated from "
        f"{r['baseline_sample']} candidates ({r['baseline_per_candidate_seconds'] * 1e6:.0f} us each)",
        f"  speed-up: {r['speedup_vs_loop']:8.1f} x   (max |dense float64 - loop| = "
        f"{r['max_abs_difference_vs_loop']:.2e})",
        f"  work:     {r['gflop']:8.2f} GFLOP, {r['gflop_per_second']:.1f} GFLOP/s;"
        f" peak memory {r['peak_memory_mib']:.1f} MiB; {r['cores']} cores",
    ])
