"""Benchmark of the compiled support features against the NumPy definitions they replace.

:func:`triangle_margins_reference` and :func:`hull_area_reference` are the
whole-array NumPy evaluations of the support triangles' margins and the four
feet's hull area (footfall's before they were compiled): the baseline here and
the specification the tests compare the kernels of
:mod:`footfall.features.support_kernels` with, bit for bit. ``bench_pose``
times both on a footstep planner's candidate sets, in the same process, beside
the 26 pose features' whole call.
"""

from __future__ import annotations

import os
import platform

import numpy as np

from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import nominal_state
from footfall.experiments.bench.timing import best_time
from footfall.features import pose_features as pose
from footfall.features.candidates import reachable_footholds
from footfall.terrain import make_board


def triangle_margins_reference(tri: np.ndarray, point: np.ndarray
                               ) -> tuple[np.ndarray, np.ndarray]:
    """Inradius [m] and signed edge distance [m] of a point (2,) [m], triangles (n, 3, 2) [m],
    NumPy over whole arrays."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, bc, ca = b - a, c - b, a - c
    la, lb, lc = (np.linalg.norm(e, axis=1) for e in (ab, bc, ca))
    cross = ab[:, 0] * (c - a)[:, 1] - ab[:, 1] * (c - a)[:, 0]
    area = 0.5 * np.abs(cross)
    semi = 0.5 * (la + lb + lc)
    inradius = np.divide(area, semi, out=np.zeros_like(area), where=semi > 0)
    orient = np.where(cross >= 0, 1.0, -1.0)
    dists = []
    for start, edge, length in ((a, ab, la), (b, bc, lb), (c, ca, lc)):  # three edges
        rel = point[None, :] - start
        signed = orient * (edge[:, 0] * rel[:, 1] - edge[:, 1] * rel[:, 0])
        dists.append(np.divide(signed, length, out=np.zeros_like(signed), where=length > 0))
    return inradius, np.min(np.stack(dists), axis=0)


def hull_area_reference(points: np.ndarray) -> np.ndarray:
    """Area [m^2] of the convex hull of 4 points (n, 4, 2) [m], NumPy over whole arrays: the
    largest shoelace area of three quadrilaterals and four triangles."""
    def shoelace(order):
        q = points[:, order]
        x, y = q[..., 0], q[..., 1]
        return 0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1))
    quads = [shoelace(o) for o in ((0, 1, 2, 3), (0, 1, 3, 2), (0, 2, 1, 3))]
    tris = [shoelace(o) for o in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3))]
    return np.max(np.stack(quads + tris), axis=0)


def _support_terms(margins, hull, state, f: np.ndarray) -> list[np.ndarray]:
    """The support features of footholds f (n, 3) [m] in ``state`` (see
    :func:`footfall.features.pose_features.pose_features`) by the given functions: the next two
    swings' triangles' inradius and margin, and the hull area after the step."""
    order = list(LITTLEDOG.gait_order)
    after = np.broadcast_to(state.feet[:, :2], (f.shape[0], 4, 2)).copy()
    after[:, state.swing_index] = f[:, :2]
    out = []
    for ahead in (1, 2):
        lifted = LEG_NAMES.index(order[(order.index(state.swing_leg) + ahead) % 4])
        out += margins(after[:, [k for k in range(4) if k != lifted]], state.body_position[:2])
    return out + [hull(after)]


def bench_pose(states: int = 8, repeats: int = 20, seed: int = 0) -> dict:
    """The support features of a planning step's candidate sets, compiled against the NumPy
    definitions, on a rocky 0.5 module, beside the 26 pose features' whole call.

    At ``states`` robot states (swing legs in turn) the footstep planner's two
    set sizes -- the first step's 128 candidates and a later step's 32 (the
    reachable footholds nearest the swing foot) -- each timed ``repeats``
    times, best counts; medians over the states [us a call], their ratio,
    whether the support features are equal bit for bit, and the whole pose
    features' call (compiled) for scale.
    """
    board = make_board([("rocky", 0.5)], seed)
    sizes = (128, 32)
    rows: dict[str, list[float]] = {f"{k}_{n}": [] for k in ("numpy", "compiled", "whole")
                                    for n in sizes}
    equal = True
    for i, x in enumerate(np.linspace(0.75, 1.10, states)):
        st = nominal_state(board, (float(x), 0.0), 0.0, LEG_NAMES[i % 4])
        f = reachable_footholds(board, st)
        home = st.feet[st.swing_index, :2]
        order = np.argsort(np.linalg.norm(f[:, :2] - home, axis=1), kind="stable")
        for n in sizes:
            sub = f[order[:n]]
            ours = _support_terms(pose.triangle_margins, pose.hull_area, st, sub)
            theirs = _support_terms(triangle_margins_reference, hull_area_reference, st, sub)
            equal &= all(np.array_equal(a, b, equal_nan=True) for a, b in zip(ours, theirs))
            rows[f"numpy_{n}"].append(best_time(lambda: _support_terms(
                triangle_margins_reference, hull_area_reference, st, sub), repeats))
            rows[f"compiled_{n}"].append(best_time(lambda: _support_terms(
                pose.triangle_margins, pose.hull_area, st, sub), repeats))
            rows[f"whole_{n}"].append(best_time(lambda: pose.pose_features(board, st, sub),
                                                repeats))
    med = {k: float(np.median(v)) * 1e6 for k, v in rows.items()}
    return {"machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
            "states": states, "equal": bool(equal),
            "sets": {str(n): {"numpy_us": med[f"numpy_{n}"], "compiled_us": med[f"compiled_{n}"],
                              "speedup": med[f"numpy_{n}"] / med[f"compiled_{n}"],
                              "pose_features_us": med[f"whole_{n}"]}
                     for n in sizes}}


def format_pose(r: dict) -> str:
    """Human-readable lines of :func:`bench_pose`."""
    lines = [f"support features (two triangles' margins, the hull), median of {r['states']} "
             f"states; compiled equal to NumPy bit for bit: {'yes' if r['equal'] else 'NO'}"]
    for n, s in r["sets"].items():
        lines.append(f"{n} candidates: NumPy {s['numpy_us']:.0f} us, compiled "
                     f"{s['compiled_us']:.0f} us (x{s['speedup']:.1f}); all 26 pose features "
                     f"{s['pose_features_us']:.0f} us a call")
    return "\n".join(lines)
