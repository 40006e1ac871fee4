"""Benchmark of the walking expert: what a run with it choosing every foothold costs.

``bench_expert`` walks the controller test board with the hand-tuned reward
(the baseline) and with the walking expert choosing every foothold, alternately
in one process, and compares their CPU time a run (target: the expert at most
1.5 x); then it times the expert's terrain terms of the candidate sets it
judged, computed by the compiled ray terms against the whole-array NumPy rules
they replaced (:func:`ray_terms_reference`), and checks they give the same bits.
"""

from __future__ import annotations

import math
import os
import platform
import time

import numpy as np

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.core.sphere_surface import SphereSurface, board_sphere, no_data, sample_surface
from footfall.experiments.batch import chooser_expert, expert_judge, walk_config
from footfall.experiments.runs import reward_source
from footfall.expert import terms as expert_terms
from footfall.expert.rays import RaySamples, no_data_share, ray_terms
from footfall.sim.episode import Walk
from footfall.terrain import make_board

TEST_BOARD = ([("rocky", 0.7), ("steps", 0.7)], 500)  # the controller test board and its seed
EXPERT_RUN_TARGET = 1.5  # [-] an expert run's CPU time at most this many hand-tuned runs'


def bench_expert(runs: int = 2, seed: int = 5000, sets: int = 60) -> dict:
    """CPU time of a run with the walking expert choosing every foothold, against the
    hand-tuned reward, and of the expert's terrain terms compiled against NumPy.

    ``runs`` seeds from ``seed`` on the controller test board (rocky 0.7 | steps 0.7,
    board seed 500), F within 3 cm as the reproduction walks; each seed walked by the
    hand-tuned reward and by a fresh walking expert (nothing remembered from an earlier
    run), alternately; the cost of a run is its CPU seconds per simulated second (a run that
    falls early is short, not cheap), the median over the seeds. Then the terrain terms of ``sets`` candidate sets the first expert
    run judged, evenly spaced through it, by :func:`ray_terms` and :func:`no_data_share`
    against :func:`ray_terms_reference` (best of 3 each).
    """
    board = make_board(*TEST_BOARD)
    config = walk_config(None, True, 0.03)
    reward = reward_source(None, board)
    cpu: dict[str, list[float]] = {"hand": [], "expert": []}
    results: dict[str, list[dict]] = {"hand": [], "expert": []}
    judged: list[tuple[np.ndarray, float]] = []
    for i in range(runs):
        for who in ("hand", "expert"):
            judge = expert_judge(chooser_expert(config, True)) if who == "expert" else None
            walk = Walk(board, reward, seed + i, config, judge=judge)
            t = time.process_time()
            if who == "expert" and i == 0:
                record, judged = _recording(walk)
            else:
                record = walk.run()
            cpu[who].append(time.process_time() - t)
            results[who].append({"seed": seed + i, "success": record.result["success"],
                                 "simulated_s": record.result["time"]})
    # CPU seconds per simulated second: a run that falls early is short, not cheap
    rate = {w: float(np.median([c / r["simulated_s"] for c, r in zip(cpu[w], results[w])]))
            for w in cpu}
    out: dict = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
                 "board": "rocky:0.7 steps:0.7 --seed 500", "runs": runs,
                 "hand_cpu_s": cpu["hand"], "expert_cpu_s": cpu["expert"],
                 "hand_cpu_per_simulated_s": rate["hand"],
                 "expert_cpu_per_simulated_s": rate["expert"],
                 "ratio": rate["expert"] / rate["hand"], "target": EXPERT_RUN_TARGET,
                 "results": results}
    out["terms"] = _bench_terms(board, judged, sets)
    return out


def _recording(walk: Walk):
    """The walk's run record, and the placements (m, 3) [m] and headings [rad] whose terrain
    terms the expert computed in it (copying them costs the run a little)."""
    seen: list[tuple[np.ndarray, float]] = []
    original = expert_terms.terrain_terms

    def record(hmap, f, cfg, robot, yaw=0.0):
        seen.append((np.array(f), float(yaw)))
        return original(hmap, f, cfg, robot, yaw)

    expert_terms.terrain_terms = record
    try:
        return walk.run(), seen
    finally:
        expert_terms.terrain_terms = original


def _bench_terms(board: HeightMap, judged: list[tuple[np.ndarray, float]], sets: int) -> dict:
    """The compiled ray terms against the NumPy rules on ``sets`` of the ``judged`` sets."""
    cfg = chooser_expert(walk_config(None, True, 0.03), True)
    k = int(cfg.directions)
    angles = 2 * np.pi * np.arange(k) / k
    dirs = np.column_stack([np.cos(angles), np.sin(angles)])
    rays = RaySamples.of(cfg)
    ball = board_sphere(board, LITTLEDOG.foot_radius)
    picks = [judged[int(i)] for i in np.linspace(0, len(judged) - 1, min(sets, len(judged)))]
    times = {"numpy": [], "compiled": []}
    same = True
    points = 0
    for f, _ in picks:
        xy = np.ascontiguousarray(f[:, :2])
        seat = sample_surface(ball, xy)
        seat = np.where(np.isnan(seat), np.nan_to_num(f[:, 2]) + LITTLEDOG.foot_radius, seat)
        points += xy.shape[0]
        best = {w: math.inf for w in times}
        for _ in range(3):
            t = time.perf_counter()
            want = ray_terms_reference(board, ball, xy, seat, dirs, rays)
            best["numpy"] = min(best["numpy"], time.perf_counter() - t)
            t = time.perf_counter()
            got = (*ray_terms(ball, xy, seat, dirs, rays),
                   no_data_share(board.heights, board.origin[0], board.origin[1],
                                 board.resolution, xy, dirs, rays.unknown))
            best["compiled"] = min(best["compiled"], time.perf_counter() - t)
        same = same and all(np.array_equal(a, b) for a, b in zip(want, got))
        for w in times:
            times[w].append(best[w] * 1e3)
    numpy_ms, compiled_ms = sum(times["numpy"]), sum(times["compiled"])
    return {"sets": len(picks), "sets_judged": len(judged), "points": points,
            "numpy_ms": numpy_ms, "compiled_ms": compiled_ms,
            "speedup": numpy_ms / max(compiled_ms, 1e-12), "same_bits": bool(same)}


def format_expert(r: dict) -> str:
    """Human-readable lines of :func:`bench_expert`."""
    t = r["terms"]
    return "\n".join([
        f"controller test board ({r['board']}), {r['runs']} run(s) each, CPU seconds a simulated "
        f"second (median): hand-tuned reward {r['hand_cpu_per_simulated_s']:.3f}, walking expert "
        f"choosing every foothold {r['expert_cpu_per_simulated_s']:.3f}: x{r['ratio']:.2f} "
        f"(target x{r['target']:.1f})",
        f"the expert's terrain terms of {t['sets']} of the {t['sets_judged']} candidate sets it "
        f"computed ({t['points']} placements): NumPy rules {t['numpy_ms']:.0f} ms, compiled "
        f"{t['compiled_ms']:.0f} ms (x{t['speedup']:.1f}), same bits: "
        f"{'yes' if t['same_bits'] else 'NO'}"])


def ray_terms_reference(hmap: HeightMap, ball: SphereSurface | None, xy: np.ndarray,
                        seat: np.ndarray, dirs: np.ndarray, rays: RaySamples
                        ) -> tuple[np.ndarray, ...]:
    """The expert's ray terms as whole-array NumPy, the rules the compiled
    :func:`~footfall.expert.rays.ray_terms` and :func:`~footfall.expert.rays.no_data_share`
    replaced: hold, pinch, trap, drop, unknown share (n,) each."""
    n, s = xy.shape[0], rays.s
    k = dirs.shape[0]
    along = np.full((n, k, s.size), np.nan) if ball is None else ball.along_rays(xy, dirs, s)
    rise = np.nan_to_num(along - seat[:, None, None], nan=0.0)  # (n, K, J) [m]
    secant = rise / s
    hold = secant[:, :, rays.near].max(axis=2).min(axis=1)
    tilt = secant[:, :, rays.jp]
    pinch = np.minimum(tilt[:, : k // 2], tilt[:, k // 2:]).max(axis=1)
    trap = rise[:, :, rays.in_trap].max(axis=2).min(axis=1)
    fall = -rise[:, :, rays.in_edge] - rays.edge_offset
    drop = (fall * rays.edge_weight).max(axis=(1, 2))
    probe = xy[:, None, None, :] + rays.unknown[None, None, :, None] * dirs[None, :, None, :]
    unknown = no_data(hmap, np.concatenate([xy[:, None, :], probe.reshape(n, -1, 2)],
                                           axis=1)).mean(axis=1)
    return hold, pinch, trap, drop, unknown

