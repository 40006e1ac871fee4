"""Benchmark of the walking expert: its judgement with its placement error against without.

``bench_expert``: the walking expert judges the reproduction's candidate sets
and every reachable foothold at states on a rocky module, with no placement
error (the baseline) and with the default one; the medians [ms] and their ratio.
"""

from __future__ import annotations

import os
import platform
import time

import numpy as np

from footfall.control.footstep import FootstepConfig
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import nominal_state
from footfall.core.heightmap import HeightMap
from footfall.expert.rays import RaySamples
from footfall.expert.surface import SphereSurface, no_data
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.features.candidates import reachable_footholds
from footfall.terrain import make_board


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

