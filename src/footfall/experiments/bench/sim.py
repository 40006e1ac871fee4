"""Benchmark of the walking stack: its real-time factor against bare MuJoCo stepping, and the
physics' fidelity.

``bench_sim``: seeded runs of the hand-tuned reward over a rocky board with
where their CPU time goes, bare stepping of the same model (the ceiling), a
run on flat ground, and how faithfully the contact follows the map
(:mod:`footfall.sim.fidelity`); optionally for a physics variant against the
documented model (:func:`footfall.sim.variants.physics_variant`).
"""

from __future__ import annotations

import os
import platform
import time
from dataclasses import replace

import mujoco
import numpy as np

from footfall.core.seeds import check_seed_span
from footfall.core.state import nominal_state
from footfall.features.reward import default_reward
from footfall.sim.episode import Walk, WalkConfig
from footfall.sim.fidelity import ball_rest_errors, slope_creep
from footfall.sim.simulation import Simulation, bench_stepping
from footfall.sim.variants import physics_variant
from footfall.terrain import make_board


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

    Before the timed runs, a short walk on flat ground warms the process up
    (imports, the compiled kernels loaded from Numba's cache): a cost paid
    once per process -- a batch's worker pays it once for all its runs --
    reported apart as ``process_start_s`` [s] CPU.

    ``physics`` (MuJoCo ``<option>`` attributes as text), ``hfield_spacing``
    [m] and ``foot_contact`` ("pads": :mod:`footfall.sim.foot_pads`) walk and
    measure another physics
    (:func:`footfall.sim.variants.physics_variant`), each rocky seed also walked
    with the documented model in turn (``documented``: the baseline); the
    bare stepping stays the documented model's, the reference.
    """
    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                             "mujoco": mujoco.__version__},
                 "physics": dict(physics or {}), "hfield_spacing": hfield_spacing,
                 "foot_contact": foot_contact}
    check_seed_span(seed, runs)
    out["process_start_s"] = _warm_up(seed)
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


def _warm_up(seed: int) -> float:
    """CPU [s] of a process's first walk: two steps on a flat board (imports, kernels)."""
    cpu = time.process_time()
    board = make_board([("flat", 0.0)] * 3, seed=seed)
    reward = default_reward()
    Walk(board, lambda leg: reward, seed, replace(WalkConfig(), max_steps=2)).run()
    return time.process_time() - cpu


_RUN_KEYS = ("success", "real_time_factor", "batch_real_time_factor", "physics_us_per_step")


def _timed_runs(board, seeds, variant: tuple[dict, float | None, str], baseline: bool = True
                ) -> tuple[list[dict], list[dict]]:
    """Timed runs of ``seeds`` with the physics ``variant`` (options, height-field spacing);
    with ``baseline`` and a variant, each seed also with the documented model, first and
    second in turn (the first run on a board also scores its reward grids)."""
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
    lines = [f"process start-up (imports, compiled kernels; once per process, before the runs): "
             f"{r['process_start_s']:.2f} s CPU"]
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
        runs = r["walk_rocky_runs"]
        lines.append("rocky runs: " + "; ".join(
            f"{'success' if w['success'] else 'failure'} {w['real_time_factor']:.1f}x "
            f"({w['physics_us_per_step']:.0f} us/step)" for w in runs)
            + f"; median {np.median([w['real_time_factor'] for w in runs]):.1f}x")
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
