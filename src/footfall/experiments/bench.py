"""Benchmarks: figures printed, with a baseline measured in the same process.

``bench_scoring``: dense scoring of a 3-module board (flat | rocky | flat,
1.83 x 0.61 m at 1 mm) at 5 mm candidate spacing (~45 000 candidates) with
60 templates (20 per scale) and the 27 terrain features, against a plain
per-candidate loop of the same definitions (timed on a sample of candidates
and extrapolated), with the floating-point work and the peak memory.
"""

from __future__ import annotations

import os
import platform
import time
import tracemalloc
from typing import Callable, TypeVar

import numpy as np

from footfall.core.compute import usable_cores
from footfall.features.config import FeatureConfig
from footfall.features.dense import score_grid
from footfall.features.family import Candidates
from footfall.features.reward import LinearReward
from footfall.features.templates import TemplateFeatures, TemplateLibrary, extract_templates
from footfall.features.terrain_features import TerrainFeatures, feature_names
from footfall.terrain import make_board

TEMPLATES_PER_SCALE = 20  # the benchmark: 60 templates in all
BENCH_TEMPLATE_RMS = 0.005  # [m] RMS height difference at which a match scores exp(-1)
_Result = TypeVar("_Result")  # what a timed piece of work returns


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
        "target_seconds": 0.1,
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


def bench_learning(n_demos: int = 100, library_size: int = 1000, seed: int = 0) -> dict:
    """Paper-scale learning: the L1 path with 5-fold grouped CV, against LogisticRegressionCV.

    Demonstrations come from the synthetic expert on rocky, steps, barrier
    and slope boards (not timed); the timed part is the learning of one
    ranking function (front and hind legs together, as one problem) on the
    templates + features set with a ~1000-template library.
    """
    from footfall.learning.ranker import FootholdRanker

    n, library, (X, y, groups), collect, features = _learning_problem(n_demos, library_size, seed)
    ours, ours_s, ours_peak = _timed(
        lambda: FootholdRanker(learner="l1", Cs=10, cv=5).fit(X, y, groups))
    ref, ref_s, ref_peak, n_pairs = _sklearn_baseline(X, y, groups, ours)
    return {
        "demonstrations": n, "library": list(library.counts),
        "features": int(X.shape[1]), "candidate_rows": int(X.shape[0]),
        "pairs_mirrored": n_pairs,
        "collect_seconds_untimed_part": collect, "feature_seconds": features,
        "learn_seconds": ours_s, "target_seconds": 30.0,
        "path_points_evaluated": len(ours.path_), "lambda": ours.lambda_,
        "cv_error": ours.cv_error_, "non_zero": int(np.count_nonzero(ours.coef_)),
        "learn_peak_memory_mib": ours_peak / 2 ** 20,
        "baseline": "sklearn LogisticRegressionCV(l1, liblinear) on the same mirrored pairs, "
                    "folds and C values",
        "baseline_seconds": ref_s, "baseline_peak_memory_mib": ref_peak / 2 ** 20,
        "baseline_non_zero": int(np.count_nonzero(ref.coef_)),
        "speedup_vs_baseline": ref_s / ours_s,
    }


def _learning_problem(n_demos: int, library_size: int, seed: int
                      ) -> tuple[int, TemplateLibrary, tuple[np.ndarray, ...], float, float]:
    """The benchmark's learning problem: demonstrations on five boards, the templates + features
    families fitted to them and their candidate rows.

    Returns the number of demonstrations, the template library, the stacked (X, y, groups), and
    the seconds spent collecting and computing the features.
    """
    from footfall.expert.collect import collect_demonstrations
    from footfall.expert.synthetic import SyntheticExpert
    from footfall.learning.dataset import create_families, make_example, stack, training_rows

    rng = np.random.default_rng(seed)
    config = FeatureConfig()
    boards = [make_board([(k, d)], seed + i) for i, (k, d) in
              enumerate([("rocky", 0.5), ("rocky", 0.8), ("steps", 0.6), ("barrier", 0.6),
                          ("slope", 0.6)])]
    maps = {b.content_hash(): b for b in boards}
    t0 = time.perf_counter()
    demos = collect_demonstrations(boards, SyntheticExpert(), n_demos, seed)
    collect = time.perf_counter() - t0
    hmaps = [maps[d.terrain_hash] for d in demos]
    t0 = time.perf_counter()
    families = tuple(f.fit(hmaps, [d.state for d in demos], [d.candidates for d in demos],
                           [d.chosen for d in demos], rng, library_size=library_size,
                           bandwidth_rms=(0.004,) * len(config.scales))
                     for f in create_families("both", config))
    examples = [make_example(h, d.state, d.candidates, d.chosen, families, config,
                             training_rows(d.candidates.shape[0], d.chosen, 100, rng))
                for h, d in zip(hmaps, demos)]
    rows = stack(examples, families)
    return len(demos), families[1].library, rows, collect, time.perf_counter() - t0


def _sklearn_baseline(X: np.ndarray, y: np.ndarray, groups: np.ndarray, ours
                      ) -> tuple[object, float, int, int]:
    """scikit-learn's own cross-validated L1 logistic regression on the same standardised
    mirrored pairs, folds and C values as the fitted ranker ``ours``, without early stop.

    Returns the fitted estimator, its seconds and peak memory [bytes], and the number of pairs.
    """
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.linear_model import LogisticRegressionCV

    from footfall.learning.ranker import grouped_folds, pairwise_transform

    pairs, labels, pair_groups = pairwise_transform(X, y, groups)
    scale = pairs.std(axis=0)
    scale[scale < 1e-12] = 1.0
    Cs = np.array([p.C for p in ours.path_])
    Cs = np.concatenate([Cs, Cs[-1] * np.logspace(0.41, 0.41 * (10 - Cs.size), 10 - Cs.size)]) \
        if Cs.size < 10 else Cs

    def fit():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            warnings.simplefilter("ignore", FutureWarning)
            return LogisticRegressionCV(Cs=Cs, cv=grouped_folds(pair_groups, 5), l1_ratios=(1.0,),
                                        solver="liblinear", fit_intercept=False, tol=1e-4,
                                        max_iter=2000, random_state=0).fit(pairs / scale, labels)

    ref, seconds, peak = _timed(fit)
    return ref, seconds, peak, int(pairs.shape[0])


def _timed(work: Callable[[], _Result]) -> tuple[_Result, float, int]:
    """Run ``work``: its result, its wall-clock time [s] and its peak traced memory [bytes]."""
    tracemalloc.start()
    t0 = time.perf_counter()
    out = work()
    seconds = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return out, seconds, peak


def format_learning(r: dict) -> str:
    """Human-readable summary of :func:`bench_learning`."""
    return "\n".join([
        f"learning: {r['demonstrations']} demonstrations, library {sum(r['library'])} "
        f"{tuple(r['library'])}, {r['features']} features, {r['pairs_mirrored']} mirrored pairs",
        f"  features: {r['feature_seconds']:7.1f} s (patches, template distances, pose)",
        f"  footfall: {r['learn_seconds']:7.1f} s for the L1 path ({r['path_points_evaluated']} "
        f"values x 5 grouped folds; target {r['target_seconds']:.0f} s), lambda "
        f"{r['lambda']:.3g}, {r['non_zero']} non-zero, peak {r['learn_peak_memory_mib']:.0f} MiB",
        f"  sklearn:  {r['baseline_seconds']:7.1f} s LogisticRegressionCV, "
        f"peak {r['baseline_peak_memory_mib']:.0f} MiB -> speed-up {r['speedup_vs_baseline']:.1f} x",
    ])


def bench_sim(seed: int = 0, difficulty: float = 0.5, bare_seconds: float = 5.0,
              probes: int = 400, runs: int = 1, physics: dict | None = None,
              hfield_spacing: float | None = None, foot_contact: str = "terrain") -> dict:
    """Real-time factor of the whole walking stack against bare MuJoCo stepping (the ceiling).

    ``runs`` seeded runs (seeds ``seed``, ``seed + 1``, ...) of the
    hand-tuned reward over a flat | rocky | flat board (planning, control and
    physics, on this process's one core: CPU time), the first with where its
    time goes (set-up, planning, physics split by MuJoCo's own timers, and the
    control periods around it); bare stepping of the documented model on the
    same terrain with the robot standing on the rocky module, and on the flat
    start module; a run on a flat board, for the walking speed on flat ground;
    and the physics' fidelity (:mod:`footfall.sim.fidelity`): ``probes`` ball
    feet lowered onto the rocky module, and the robot standing on a 0.3 slope.

    ``physics`` (MuJoCo ``<option>`` attributes as text), ``hfield_spacing``
    [m] and ``foot_contact`` ("pads": :mod:`footfall.sim.foot_pads`) walk and
    measure another physics
    (:func:`footfall.sim.mjcf.physics_variant`), each rocky seed also walked
    with the documented model in turn (``documented``: the baseline); the
    bare stepping stays the documented model's, the reference.
    """
    import mujoco

    from footfall.core.state import nominal_state
    from footfall.sim.simulation import Simulation, bench_stepping

    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                             "mujoco": mujoco.__version__},
                 "physics": dict(physics or {}), "hfield_spacing": hfield_spacing,
                 "foot_contact": foot_contact}
    board = make_board([("rocky", difficulty)], seed=seed)
    variant = (dict(physics or {}), hfield_spacing, foot_contact)
    rocky, documented = _timed_runs(board, range(seed, seed + runs), variant)
    out["walk_rocky"] = rocky[0]
    out["walk_rocky_runs"] = [{k: w[k] for k in _RUN_KEYS} for w in rocky]
    out["walk_flat"] = _timed_runs(make_board([("flat", 0.0)] * 3, seed=seed), [seed],
                                   variant, baseline=False)[0][0]
    out["fidelity"] = _fidelity(board, seed, probes, variant)
    if documented:
        out["documented"] = {
            "walk_rocky_runs": documented,
            **_fidelity(board, seed, probes, ({}, None, "terrain")),
            # (a run of a batch: the board's grids scored once, whichever model walked first)
            "variant_over_documented": {
                key: float(np.median([v[key] / d[key] for v, d in
                                      zip(out["walk_rocky_runs"], documented)]))
                for key in ("batch_real_time_factor", "physics_us_per_step")}}
    for where, x in (("rocky", 0.915), ("flat", 0.3)):  # the documented model: the reference
        sim = Simulation(hmap=board)
        st = nominal_state(board, (x, 0.0), 0.0, "LF")
        sim.stand(st.body_position, st.body_rpy, st.feet)
        sim.advance(0.2)
        out[f"bare_{where}"] = bench_stepping(sim, bare_seconds)
        sim.close()
    out["stack_over_bare_rocky"] = (out["walk_rocky"]["real_time_factor"]
                                    / out["bare_rocky"]["real_time_factor"])
    return out


_RUN_KEYS = ("success", "real_time_factor", "batch_real_time_factor", "physics_us_per_step")


def _timed_runs(board, seeds, variant: tuple[dict, float | None, str], baseline: bool = True
                ) -> tuple[list[dict], list[dict]]:
    """Timed runs of ``seeds`` with the physics ``variant`` (options, height-field spacing);
    with ``baseline`` and a variant, each seed also with the documented model, first and
    second in turn (the first run on a board also scores its reward grids)."""
    import mujoco

    from footfall.features.reward import default_reward
    from footfall.sim.episode import Walk
    from footfall.sim.mjcf import physics_variant

    reward = default_reward()
    compare = baseline and variant != ({}, None, "terrain")
    done, documented = [], []
    for i, s in enumerate(seeds):
        for which in (("variant",) if not compare else
                      ("documented", "variant") if i % 2 == 0 else ("variant", "documented")):
            if which == "documented":
                documented.append({k: v for k, v in _timed_walk(
                    Walk, board, reward, s, mujoco).items() if k in _RUN_KEYS})
            else:
                with physics_variant(*variant):
                    done.append(_timed_walk(Walk, board, reward, s, mujoco))
    return done, documented


def _fidelity(board, seed: int, probes: int, variant: tuple[dict, float | None, str]) -> dict:
    """:mod:`footfall.sim.fidelity`'s measures with the physics ``variant``: ``probes`` loaded
    balls on the board's rocky module (points drawn from ``seed``), and the slope."""
    from footfall.sim.fidelity import ball_rest_errors, slope_creep
    from footfall.sim.mjcf import physics_variant

    rng = np.random.default_rng(seed)
    module = [m for m in board.metadata["modules"] if m["kind"] == "rocky"][0]
    xy = np.column_stack([rng.uniform(module["x_start"] + 0.02, module["x_end"] - 0.02,
                                      probes), rng.uniform(-0.25, 0.25, probes)])
    with physics_variant(*variant):
        rest = np.abs(ball_rest_errors(board, xy))
        creep = slope_creep()
    return {"rest_error_mean_mm": 1e3 * float(rest.mean()),
            "rest_error_p99_mm": 1e3 * float(np.percentile(rest, 99)),
            "rest_points": int(probes), "slope_creep_max_mm": 1e3 * float(creep.max())}


def _timed_walk(walk_class, board, reward, seed: int, mujoco) -> dict:
    """One run's real-time factor and where its CPU time went (see :func:`bench_sim`)."""
    cpu, wall = time.process_time(), time.perf_counter()
    run = walk_class(board, lambda leg: reward, seed)
    setup = time.process_time() - cpu
    record = run.run()
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    r = record.result
    timer = run.sim.data.timer  # MuJoCo's own timers (wall clock): the split of physics
    step = timer[mujoco.mjtTimer.mjTIMER_STEP]
    physics = run.sim.physics_cpu  # [s] CPU
    share = physics / max(float(step.duration), 1e-12)  # wall -> CPU
    planning = 1e-3 * r["planning_ms_per_step"] * len(record.steps)
    warm = time.process_time()
    walk_class(board, lambda leg: reward, seed).sim.close()  # the same board again: cached grids
    warm = time.process_time() - warm
    return {
        "success": r["success"], "reason": r["reason"], "simulated_s": r["time"],
        "cpu_s": cpu, "wall_s": wall, "real_time_factor": r["time"] / cpu,
        "wall_real_time_factor": r["time"] / wall,
        "planning_ms_per_step": r["planning_ms_per_step"], "steps": r["steps"],
        "speed_cm_s": r["speed_cm_s"], "speed_body_lengths_s": r["speed_body_lengths_s"],
        "parts_s": {
            "setup": setup, "setup_again": warm, "planning": planning, "physics": physics,
            "physics_collision": share * timer[mujoco.mjtTimer.mjTIMER_POS_COLLISION].duration,
            "physics_solver": share * timer[mujoco.mjtTimer.mjTIMER_CONSTRAINT].duration,
            "control": cpu - setup - planning - physics},
        "physics_steps": int(step.number),
        "physics_us_per_step": 1e6 * physics / max(int(step.number), 1),
        # a later run of a batch on the same board: its reward grids already scored
        "batch_real_time_factor": r["time"] / (cpu - setup + warm)}


def format_sim(r: dict) -> str:
    """Human-readable lines of :func:`bench_sim`."""
    lines = []
    for name in ("rocky", "flat"):
        w = r[f"walk_{name}"]
        lines.append(f"whole stack, {name} board: {w['real_time_factor']:.1f}x real time (CPU), "
                     f"{w['wall_real_time_factor']:.1f}x wall; {w['simulated_s']:.1f} s walked "
                     f"({'success' if w['success'] else w['reason']}), {w['steps']} steps, "
                     f"planning {w['planning_ms_per_step']:.1f} ms/step, "
                     f"{w['speed_cm_s']:.1f} cm/s ({w['speed_body_lengths_s']:.2f} body lengths/s)")
        lines.append(f"  a later run of a batch on the same board (grids scored once): "
                     f"{w['batch_real_time_factor']:.1f}x real time")
        p = w["parts_s"]
        lines.append(f"  CPU {w['cpu_s']:.2f} s: set-up {p['setup']:.2f} (again on the same "
                     f"board {p['setup_again']:.2f}), planning {p['planning']:.2f}, physics "
                     f"{p['physics']:.2f} (collision {p['physics_collision']:.2f}, solver "
                     f"{p['physics_solver']:.2f}; {1e6 * p['physics'] / w['physics_steps']:.0f} "
                     f"us per step), control periods {p['control']:.2f}")
    for where in ("rocky", "flat"):
        b = r[f"bare_{where}"]
        lines.append(f"bare MuJoCo stepping, robot on the {where} module: "
                     f"{b['real_time_factor']:.1f}x real time ({b['steps_per_second']:.0f} steps/s)")
    lines.append(f"whole stack / bare stepping on the rocky board: {r['stack_over_bare_rocky']:.2f}")
    if len(r["walk_rocky_runs"]) > 1:
        lines.append("rocky runs: " + "; ".join(
            f"{'success' if w['success'] else 'failure'} {w['real_time_factor']:.1f}x "
            f"({w['physics_us_per_step']:.0f} us/step)" for w in r["walk_rocky_runs"]))
    if "documented" in r:
        d = r["documented"]
        lines.append(f"physics variant: {r['physics']}, height field {r['hfield_spacing']} m, "
                     f"foot contact {r['foot_contact']}; "
                     f"against the documented model walked alternately with it (the same "
                     f"seeds): physics per step x{d['variant_over_documented']['physics_us_per_step']:.2f}"
                     f", whole stack x{d['variant_over_documented']['batch_real_time_factor']:.2f} "
                     f"(medians, runs of a batch)"
                     f"; the documented model's ball rests "
                     f"{d['rest_error_mean_mm']:.2f} / {d['rest_error_p99_mm']:.2f} mm, creeps "
                     f"{d['slope_creep_max_mm']:.2f} mm (bare stepping: the documented model)")
    f = r["fidelity"]
    lines.append(f"fidelity: a loaded ball foot rests {f['rest_error_mean_mm']:.2f} mm from the "
                 f"map's rest height on average, {f['rest_error_p99_mm']:.2f} mm at the 99th "
                 f"percentile ({f['rest_points']} points on rock); standing on a 0.3 slope, "
                 f"a foot creeps {f['slope_creep_max_mm']:.2f} mm in 4 s")
    return "\n".join(lines)


def bench_expert(states: int = 16, repeats: int = 3, seed: int = 0) -> dict:
    """Cost of the walking expert's judgement with its placement error, against without.

    ``states`` robot states standing at evenly spaced places on a rocky 0.5
    module (swing legs in turn); for each, the candidate set F of the
    reproduction (reachable footholds within 3 cm of the gait-nominal one)
    and every reachable foothold (5 mm lattice). Each set is judged by the
    walking expert with no placement error (the baseline) and with the
    default one, alternately, ``repeats`` times; the best time of each
    counts. Medians over the states [ms] and their ratio.
    """
    from footfall.control.footstep import FootstepConfig
    from footfall.core.robot import LEG_NAMES, LITTLEDOG
    from footfall.core.state import nominal_state
    from footfall.expert.synthetic import SyntheticExpert, walking_expert
    from footfall.features.candidates import reachable_footholds

    lead = FootstepConfig().lead
    judges = {"baseline": SyntheticExpert(walking_expert(lead, placement_error=0.0)).values,
              "placement": SyntheticExpert(walking_expert(lead)).values}
    board = make_board([("rocky", 0.5)], seed)
    xs = np.linspace(0.75, 1.10, states)
    times: dict[str, dict[str, list[float]]] = {s: {j: [] for j in judges} for s in ("F", "all")}
    sizes: dict[str, list[int]] = {"F": [], "all": []}
    for i, x in enumerate(xs):
        leg = LEG_NAMES[i % 4]
        st = nominal_state(board, (float(x), 0.0), 0.0, leg)
        every = reachable_footholds(board, st)
        nominal = st.body_position[:2] + np.asarray(LITTLEDOG.nominal_foot(leg)[:2]) + (lead, 0.0)
        sets = {"all": every,
                "F": every[np.linalg.norm(every[:, :2] - nominal, axis=1) <= 0.03]}
        for name, cand in sets.items():
            sizes[name].append(int(cand.shape[0]))
            best = {j: np.inf for j in judges}
            for _ in range(repeats):
                for j, judge in judges.items():
                    t = time.perf_counter()
                    judge(board, st, cand)
                    best[j] = min(best[j], time.perf_counter() - t)
            for j in judges:
                times[name][j].append(best[j] * 1000)
    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
                 "states": states}
    for name in ("F", "all"):
        med = {j: float(np.median(times[name][j])) for j in judges}
        out[name] = {"candidates_median": float(np.median(sizes[name])),
                     "baseline_ms": med["baseline"], "placement_ms": med["placement"],
                     "ratio": med["placement"] / med["baseline"]}
    return out


def format_expert(r: dict) -> str:
    """Human-readable lines of :func:`bench_expert`."""
    labels = {"F": "the reproduction's F (3 cm)", "all": "every reachable foothold"}
    return "\n".join(
        f"{labels[k]}: {r[k]['candidates_median']:.0f} candidates, walking expert "
        f"{r[k]['placement_ms']:.1f} ms with its placement error, {r[k]['baseline_ms']:.1f} ms "
        f"without (x{r[k]['ratio']:.2f}; medians over {r['states']} states)" for k in ("F", "all"))


def bench_executors(runs: int = 8, seed: int = 0, difficulty: float = 0.5,
                    processes: int = 2) -> dict:
    """Runs per minute of one batch on the local process pool and on a Ray cluster started here.

    ``runs`` hand-tuned runs over a flat | rocky | flat board, first on the
    local pool of ``processes`` workers (the baseline), then the same jobs on
    a Ray cluster of ``processes`` CPUs started in this process on loopback
    (its start-up timed apart). Both give the same records (checked).
    """
    import tempfile
    from pathlib import Path

    from footfall.experiments.batch import batch_jobs
    from footfall.experiments.executors import LocalPool, RayCluster
    from footfall.sim.episode import WALL_CLOCK_FIELDS

    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
                 "runs": runs, "processes": processes}
    with tempfile.TemporaryDirectory() as folder:
        board = Path(folder) / "board.npz"
        make_board([("rocky", difficulty)], seed=seed).save(board)
        jobs = batch_jobs(board, None, runs, seed)
        results = {}
        ray = RayCluster(processes=processes)
        try:
            start = time.perf_counter()
            ray._connect()
            out["ray_start_s"] = time.perf_counter() - start
            for name, executor in (("local", LocalPool(processes)), ("ray", ray)):
                start = time.perf_counter()
                results[name] = {job.seed: rec for job, (rec, _) in executor.map(jobs)}
                wall = time.perf_counter() - start
                out[name] = {"wall_s": wall, "runs_per_minute": 60.0 * runs / wall}
        finally:
            ray.close()
    strip = lambda rec: {k: v for k, v in rec.result.items() if k not in WALL_CLOCK_FIELDS}
    out["same_records"] = all(strip(results["local"][s]) == strip(results["ray"][s])
                              for s in results["local"])
    out["successes"] = sum(bool(r.result["success"]) for r in results["local"].values())
    out["ray_over_local"] = out["ray"]["runs_per_minute"] / out["local"]["runs_per_minute"]
    return out


def format_executors(r: dict) -> str:
    """Human-readable lines of :func:`bench_executors`."""
    return "\n".join([
        f"{r['runs']} runs on a rocky board ({r['successes']} crossed), {r['processes']} "
        f"processes each:",
        f"local process pool: {r['local']['runs_per_minute']:.1f} runs/min "
        f"({r['local']['wall_s']:.1f} s)",
        f"Ray cluster started here: {r['ray']['runs_per_minute']:.1f} runs/min "
        f"({r['ray']['wall_s']:.1f} s, after {r['ray_start_s']:.1f} s to start it)",
        f"Ray / local pool: {r['ray_over_local']:.2f}; the same records on both: "
        f"{'yes' if r['same_records'] else 'NO'}"])
