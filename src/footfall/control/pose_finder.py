"""The pose finder (paper §IV-B 3): the body pose for the stance after a step.

For four given footholds it picks the body height, roll, pitch and yaw that
keep every foothold comfortably reachable and the knees, shins and trunk
clear of the terrain, while staying close to a preferred pose: the nominal
height above the feet, a body tilted part way toward the plane of the feet,
heading along the hint. Each wish is a cost term; reachability and clearance
terms are hinges that cost nothing once a margin is met, so a pose that
meets every margin at the preferred pose *is* the optimum (and on flat
ground in the nominal stance, that pose is the nominal one).

The search is vectorised: a coarse grid of (height, roll, pitch, yaw) around
the preferred pose, then a few rounds of a 3^4 pattern search with halving
steps, every round evaluating all its poses at once -- the legs' and the
trunk's terms in compiled passes over the poses (Numba), the arithmetic of
:mod:`footfall.core.kinematics` and :meth:`HeightMap.height_at
<footfall.core.heightmap.HeightMap.height_at>` point by point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from footfall.core.bilinear import _map_point
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import _leg_arrays, leg_angles, rotation_matrix
from footfall.core.params import Params, above, at_least, param, within
from footfall.core.robot import LITTLEDOG, RobotDescription

TERMS = ("joint", "reach", "leg_clearance", "trunk_clearance", "height", "attitude", "yaw")
# names of the cost terms, in the order of Pose.terms
_NO_SOLUTION_MARGIN = -np.pi  # [rad] joint margin charged to a leg the IK cannot solve at all


def _odd_counts(grid: object) -> bool:
    return isinstance(grid, tuple) and len(grid) == 4 and all(
        isinstance(n, int) and not isinstance(n, bool) and n >= 1 and n % 2 == 1 for n in grid)


@dataclass(frozen=True)
class PoseConfig(Params):
    """Every knob of the pose finder (docs/configuration.md).

    Costs are dimensionless; each margin is a hinge.
    """

    # Search.
    height_range: float = param(0.04, unit="m", range=above(0),
                                doc="coarse-grid half-range of body height around the preferred "
                                    "one")
    roll_range: float = param(0.3, unit="rad", range=above(0),
                              doc="coarse-grid half-range of roll around the preferred roll")
    pitch_range: float = param(0.3, unit="rad", range=above(0),
                               doc="coarse-grid half-range of pitch around the preferred pitch")
    yaw_range: float = param(0.15, unit="rad", range=above(0),
                             doc="coarse-grid half-range of yaw around the hint")
    grid: tuple[int, int, int, int] = param((3, 3, 3, 3), unit="-", check=_odd_counts,
                                            must="four odd integers >= 1",
                                            doc="coarse-grid points (height, roll, pitch, yaw)")
    refinements: int = param(4, unit="-", range=at_least(0),
                             doc="rounds of 3^4 pattern search after the grid, each halving the "
                                 "step")
    # Reachability: a margin below the wanted one costs weight * (shortfall / wanted)^2.
    joint_margin: float = param(0.25, unit="rad", range=above(0),
                                doc="wanted smallest distance of any joint from its limits")
    reach_margin: float = param(0.015, unit="m", range=above(0),
                                doc="wanted distance of every foot centre inside its leg's reach")
    # Collisions.
    leg_clearance: float = param(0.01, unit="m", range=above(0),
                                 doc="wanted clearance of the knees and upper shins (surface)")
    trunk_clearance: float = param(0.02, unit="m", range=above(0),
                                   doc="wanted clearance of the trunk's underside")
    shin_samples: int = param(4, unit="-", range=at_least(1),
                              doc="points checked per leg, from the knee (first) down the shin")
    shin_fraction: float = param(0.75, unit="-", range=within(0, 1),
                                 doc="how far from knee to foot centre the shin is checked")
    trunk_cell: float = param(0.01, unit="m", range=above(0),
                              doc="terrain under the trunk is max-pooled into cells of this size")
    # Preferences: deviation / tolerance, squared, times the weight.
    height_tolerance: float = param(0.02, unit="m", range=above(0),
                                    doc="height deviation from the preferred height costing 1 "
                                        "weight")
    attitude_tolerance: float = param(0.2, unit="rad", range=above(0),
                                      doc="roll/pitch deviation from the preferred one costing 1")
    yaw_tolerance: float = param(0.1, unit="rad", range=above(0),
                                 doc="yaw deviation from the hint costing 1 weight")
    attitude_follow: float = param(0.5, unit="-", range=within(0, 1),
                                   doc="preferred tilt: 0 level, 1 parallel to the feet's "
                                       "best-fit plane")
    # Weights of the cost terms (see TERMS).
    weight_joint: float = param(10.0, unit="-", range=at_least(0), doc="joint-limit margin")
    weight_reach: float = param(10.0, unit="-", range=at_least(0), doc="workspace (reach) margin")
    weight_leg_clearance: float = param(10.0, unit="-", range=at_least(0),
                                        doc="knee and shin clearance")
    weight_trunk_clearance: float = param(10.0, unit="-", range=at_least(0),
                                          doc="trunk clearance")
    weight_height: float = param(1.0, unit="-", range=at_least(0),
                                 doc="deviation from the preferred height")
    weight_attitude: float = param(1.0, unit="-", range=at_least(0),
                                   doc="deviation from the preferred roll and pitch")
    weight_yaw: float = param(1.0, unit="-", range=at_least(0), doc="deviation from the yaw hint")

    @property
    def weights(self) -> dict[str, float]:
        """The weight [-] of each term of TERMS."""
        return {t: getattr(self, f"weight_{t}") for t in TERMS}


@dataclass(frozen=True, eq=False)
class Pose:
    """A body pose found for a stance, with what it costs and how it scores on every margin."""

    body_xy: np.ndarray  # (2,) [m] world x, y of the body origin (given, not searched)
    height: float  # [m] world z of the body origin
    rpy: np.ndarray  # (3,) [rad] roll, pitch, yaw (Z-Y-X)
    score: float  # [-] minus the total cost; 0: every margin met at the preferred pose
    terms: dict[str, float]  # [-] cost of each term of TERMS (score = -sum)
    joint_margin: float  # [rad] smallest distance of any joint of any leg from its limits
    reach_margin: float  # [m] smallest distance of a foot centre inside its leg's reach
    leg_clearance: float  # [m] least clearance of a knee or upper shin above the terrain
    trunk_clearance: float  # [m] least clearance of the trunk's underside (inf: no terrain data)
    reachable: bool  # every foot within its leg's workspace and joint limits

    @property
    def position(self) -> np.ndarray:
        """World position [m] (3,) of the body origin."""
        return np.array([self.body_xy[0], self.body_xy[1], self.height])


def feet_plane(feet: np.ndarray, yaw: float) -> tuple[float, float, float]:
    """Least-squares plane through contact points (n, 3) [m], in the heading frame of ``yaw``.

    Returns ``(z0, gx, gy)``: the plane is ``z = z0 + gx * u + gy * v`` with
    (u, v) the heading-frame offsets from the points' mean xy, so ``z0`` [m]
    is the plane's height there and ``gx``, ``gy`` [-] its forward and
    leftward slopes.
    """
    c, s = np.cos(yaw), np.sin(yaw)
    d = feet[:, :2] - feet[:, :2].mean(axis=0)
    u, v = c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]
    design = np.column_stack([np.ones(len(feet)), u, v])
    coef = np.linalg.lstsq(design, feet[:, 2], rcond=None)[0]
    return float(coef[0]), float(coef[1]), float(coef[2])


def preferred_pose(feet: np.ndarray, body_xy: np.ndarray, yaw_hint: float,
                   robot: RobotDescription, config: PoseConfig) -> np.ndarray:
    """The pose (4,) = (height [m], roll, pitch, yaw [rad]) the search starts from and pulls toward.

    Height: ``robot.nominal_height`` above the feet's best-fit plane at
    ``body_xy``. Tilt: ``attitude_follow`` times the roll and pitch that make
    the body parallel to that plane (nose up where the feet rise ahead).
    """
    z0, gx, gy = feet_plane(feet, yaw_hint)
    c, s = np.cos(yaw_hint), np.sin(yaw_hint)
    d = body_xy - feet[:, :2].mean(axis=0)
    z = z0 + gx * (c * d[0] + s * d[1]) + gy * (-s * d[0] + c * d[1]) + robot.nominal_height
    pitch = -np.arctan(gx)
    roll = np.arctan(gy / np.sqrt(1.0 + gx * gx))  # exact for Z-Y-X angles on the plane
    k = config.attitude_follow
    return np.array([z, k * roll, k * pitch, yaw_hint])


def _trunk_cells(hmap: HeightMap, body_xy: np.ndarray, radius: float, cell: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """Terrain within ``radius`` [m] (square) of ``body_xy``, max-pooled into cells of ~``cell`` [m].

    Returns the centres (p, 2) [m] and highest heights (p,) [m] of the
    pooled cells that hold data; cells without data (NaN) are no obstacle.
    """
    k = max(int(round(cell / hmap.resolution)), 1)
    n = int(np.ceil(2 * radius / (k * hmap.resolution))) + 1
    i0, j0 = hmap.position_to_index(np.asarray(body_xy) - radius)
    nx, ny = hmap.shape
    a0, a1 = min(max(i0, 0), nx), min(max(i0 + n * k, 0), nx)
    b0, b1 = min(max(j0, 0), ny), min(max(j0 + n * k, 0), ny)
    if a1 <= a0 or b1 <= b0:  # entirely off the map: no data, no obstacle
        return np.zeros((0, 2)), np.zeros(0)
    block = hmap.heights[a0:a1, b0:b1]
    if block.shape != (n * k, n * k):  # near the border: off the map is no data
        block = np.pad(block, ((a0 - i0, i0 + n * k - a1), (b0 - j0, j0 + n * k - b1)),
                       constant_values=np.nan)
    # fmax ignores NaN; a cell with no data at all stays NaN. Two 1-D reductions are fast.
    pooled = np.fmax.reduce(block.reshape(n, k, n * k), axis=1)
    pooled = np.fmax.reduce(pooled.reshape(n, n, k), axis=2)
    ci = i0 + k * np.arange(n) + (k - 1) / 2
    cj = j0 + k * np.arange(n) + (k - 1) / 2
    centres = hmap.index_to_position(np.stack(np.meshgrid(ci, cj, indexing="ij"), axis=-1))
    keep = np.isfinite(pooled)
    return centres[keep], pooled[keep]


@dataclass(frozen=True)
class _Problem:
    """Everything fixed during one search."""

    hmap: HeightMap
    centres: np.ndarray  # (4, 3) [m] world ball-foot centres, LEG_NAMES order
    body_xy: np.ndarray  # (2,) [m]
    preferred: np.ndarray  # (4,) height [m], roll, pitch, yaw [rad]
    cells_xy: np.ndarray  # (p, 2) [m] pooled terrain cells near the trunk
    cells_h: np.ndarray  # (p,) [m] their highest heights
    robot: RobotDescription
    config: PoseConfig


def _measures(problem: _Problem, poses: np.ndarray, exact: bool = False) -> dict[str, np.ndarray]:
    """Margins and clearances of poses (n, 4) = (height, roll, pitch, yaw) -> dict of (n,).

    The legs' terms -- joint margins, reach, the shins' clearance above the
    map -- by one compiled pass over the poses (:func:`_leg_measures`); the
    trunk's by :func:`_trunk_clearance`. Unless ``exact``, the trunk clearance
    of a pose whose lowest possible underside point clears the highest cell by
    the wanted clearance is reported as that lower bound (its cost is zero
    either way).
    """
    robot, cfg, hmap = problem.robot, problem.config, problem.hmap
    n = poses.shape[0]
    body = np.column_stack([np.broadcast_to(problem.body_xy, (n, 2)), poses[:, 0]])
    rot = rotation_matrix(poses[:, 1:])  # (n, 3, 3)
    hips, side, knee, lower, upper = _leg_arrays(robot)
    joint, reach, clear, ok_all = _leg_measures(
        np.ascontiguousarray(problem.centres, dtype=np.float64), body, rot, hips, side, knee,
        lower, upper, np.array([robot.upper_leg, robot.lower_leg, robot.hip_offset,
                                robot.max_reach, robot.lower_leg_radius]),
        np.linspace(0.0, cfg.shin_fraction, cfg.shin_samples), hmap.heights,
        np.array([hmap.origin[0], hmap.origin[1], hmap.resolution]))
    return {"joint": joint, "reach": reach, "leg_clearance": clear,
            "trunk_clearance": _trunk_clearance(problem, poses, body, rot, exact),
            "reachable": ok_all}


@numba.njit(cache=True, nogil=True)
def _leg_measures(centres, body, rot, hips, side, knee, lower, upper, lengths, frac, heights,
                  grid):  # pragma: no cover - compiled
    """Per pose (n,): the least joint margin [rad] of the four legs (a leg without an IK
    solution counts ``_NO_SOLUTION_MARGIN``), the least reach margin [m], the least
    clearance [m] of the shin samples (``frac`` (S,) of the way from knee to foot) above the
    map ``heights`` (``grid``: origin x, y [m], resolution [m/cell]; no data: no collision),
    and whether every leg reaches within its limits.

    ``centres`` (4, 3) [m] world ball-foot centres; ``body`` (n, 3) [m] and ``rot`` (n, 3, 3)
    the poses; ``hips`` (4, 3) [m], ``side`` (4,) [m], ``knee`` (4,) [-], ``lower``, ``upper``
    (4, 3) [rad] the legs (:func:`footfall.core.kinematics.legs_inverse_kinematics`);
    ``lengths``: upper leg, lower leg, hip offset, max reach, lower-leg radius [m]."""
    l1, l2, d, max_reach, radius = lengths[0], lengths[1], lengths[2], lengths[3], lengths[4]
    ox, oy, res = grid[0], grid[1], grid[2]
    n = body.shape[0]
    joint = np.empty(n)
    reach = np.empty(n)
    clear = np.empty(n)
    ok_all = np.empty(n, dtype=np.bool_)
    local = np.empty(3)
    for i in range(n):
        joint[i] = np.inf
        reach[i] = np.inf
        clear[i] = np.inf
        ok_all[i] = True
        for k in range(4):
            for j in range(3):  # the foot centre in the body frame: (centre - body) @ rot
                local[j] = (centres[k, 0] - body[i, 0]) * rot[i, 0, j] \
                    + (centres[k, 1] - body[i, 1]) * rot[i, 1, j] \
                    + (centres[k, 2] - body[i, 2]) * rot[i, 2, j]
            px, py, pz = local[0] - hips[k, 0], local[1] - hips[k, 1], local[2] - hips[k, 2]
            reach[i] = min(reach[i], max_reach - math.sqrt(px * px + py * py + pz * pz))
            q1, q2, q3, solved = leg_angles(px, py, pz, side[k], knee[k], l1, l2, d)
            if not solved:  # no solution: charged, and its shin collides with nothing
                joint[i] = min(joint[i], _NO_SOLUTION_MARGIN)
                ok_all[i] = False
                continue
            margin = min(q1 - lower[k, 0], upper[k, 0] - q1, q2 - lower[k, 1], upper[k, 1] - q2,
                         q3 - lower[k, 2], upper[k, 2] - q3)
            joint[i] = min(joint[i], margin)
            if margin < 0:
                ok_all[i] = False
            c, s = math.cos(q1), math.sin(q1)  # the knee, body frame
            kx, ky0, kz0 = -l1 * math.sin(q2), side[k], -l1 * math.cos(q2)
            knee_b = (kx + hips[k, 0], c * ky0 - s * kz0 + hips[k, 1], s * ky0 + c * kz0 + hips[k, 2])
            for f in range(frac.shape[0]):
                b0 = knee_b[0] + frac[f] * (local[0] - knee_b[0])
                b1 = knee_b[1] + frac[f] * (local[1] - knee_b[1])
                b2 = knee_b[2] + frac[f] * (local[2] - knee_b[2])
                wx = b0 * rot[i, 0, 0] + b1 * rot[i, 0, 1] + b2 * rot[i, 0, 2] + body[i, 0]
                wy = b0 * rot[i, 1, 0] + b1 * rot[i, 1, 1] + b2 * rot[i, 1, 2] + body[i, 1]
                wz = b0 * rot[i, 2, 0] + b1 * rot[i, 2, 1] + b2 * rot[i, 2, 2] + body[i, 2]
                gap = wz - _map_point(heights, ox, oy, res, wx, wy) - radius
                if gap < clear[i]:  # (no data below: NaN, no collision)
                    clear[i] = gap
    return joint, reach, clear, ok_all


def _trunk_clearance(problem: _Problem, poses: np.ndarray, body: np.ndarray, rot: np.ndarray,
                     exact: bool) -> np.ndarray:
    """Least height [m] (n,) of the trunk's underside plane above the pooled cells under it."""
    robot, cfg = problem.robot, problem.config
    n = poses.shape[0]
    out = np.full(n, np.inf)
    if problem.cells_h.size == 0:
        return out
    lx, ly, lz = (0.5 * s for s in robot.trunk_size)
    tilt = np.abs(poses[:, 1:3])
    # Lowest the underside can reach anywhere: corner dropped by the tilt.
    lowest = body[:, 2] - lz * np.cos(tilt).prod(axis=1) - lx * np.sin(tilt[:, 1]) - ly * np.sin(tilt[:, 0])
    bound = lowest - problem.cells_h.max()
    todo = np.ones(n, dtype=bool) if exact else bound < cfg.trunk_clearance
    out[~todo] = bound[~todo]
    if not todo.any():
        return out
    pad = cfg.trunk_cell / np.sqrt(2.0)
    out[todo] = _underside_clearance(
        body[todo], rot[todo], np.ascontiguousarray(poses[todo, 3]), problem.cells_xy,
        problem.cells_h, np.asarray(problem.body_xy, dtype=np.float64),
        np.array([lx + pad, ly + pad, lz]))
    return out


@numba.njit(cache=True, nogil=True)
def _underside_clearance(body, rot, yaw, cells_xy, cells_h, body_xy, box
                         ):  # pragma: no cover - compiled
    """Least height [m] (m,) of each pose's trunk underside plane above the pooled cells
    (``cells_xy`` (p, 2) [m], highest heights ``cells_h`` (p,) [m]) under its footprint; inf
    where none is under it.

    The underside is the plane through ``body`` (m, 3) [m] less the half height
    ``box[2]`` [m] along the body's z axis (``rot`` (m, 3, 3)). Which cells lie under the
    trunk depends on x, y and ``yaw`` (m,) [rad] only: a cell counts if its centre lies
    within the footprint (half sizes ``box[:2]`` [m], grown by half a cell diagonal) around
    ``body_xy`` (2,) [m]; the tilt's few-mm shift of the footprint is neglected."""
    m = body.shape[0]
    out = np.full(m, np.inf)
    for i in range(m):
        nx, ny, nz = rot[i, 0, 2], rot[i, 1, 2], rot[i, 2, 2]  # the body's z axis, world
        cx, cy, cz = body[i, 0] - box[2] * nx, body[i, 1] - box[2] * ny, body[i, 2] - box[2] * nz
        gx, gy = -nx / nz, -ny / nz
        c0 = cz - gx * cx - gy * cy
        c, s = np.cos(yaw[i]), np.sin(yaw[i])
        for k in range(cells_h.shape[0]):
            dx, dy = cells_xy[k, 0] - body_xy[0], cells_xy[k, 1] - body_xy[1]
            if abs(c * dx + s * dy) <= box[0] and abs(-s * dx + c * dy) <= box[1]:
                gap = c0 + gx * cells_xy[k, 0] + gy * cells_xy[k, 1] - cells_h[k]
                if gap < out[i]:
                    out[i] = gap
    return out


def _costs(problem: _Problem, poses: np.ndarray, measures: dict[str, np.ndarray]) -> np.ndarray:
    """Cost of each term of TERMS for each pose, (n, 4) -> (n, len(TERMS))."""
    cfg = problem.config
    pref = problem.preferred

    def hinge(value, wanted):
        return (np.maximum(wanted - value, 0.0) / wanted) ** 2

    unweighted = {
        "joint": hinge(measures["joint"], cfg.joint_margin),
        "reach": hinge(measures["reach"], cfg.reach_margin),
        "leg_clearance": hinge(measures["leg_clearance"], cfg.leg_clearance),
        "trunk_clearance": hinge(measures["trunk_clearance"], cfg.trunk_clearance),
        "height": ((poses[:, 0] - pref[0]) / cfg.height_tolerance) ** 2,
        "attitude": np.sum((poses[:, 1:3] - pref[1:3]) ** 2, axis=1) / cfg.attitude_tolerance ** 2,
        "yaw": ((poses[:, 3] - pref[3]) / cfg.yaw_tolerance) ** 2,
    }
    weights = cfg.weights
    return np.column_stack([weights[t] * unweighted[t] for t in TERMS])


def _search(problem: _Problem) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The lowest-cost pose (1, 4) and its measures: the preferred pose, else grid + pattern search."""
    cfg = problem.config

    def best_of(poses, exact=False):
        measures = _measures(problem, poses, exact)
        i = int(np.argmin(_costs(problem, poses, measures).sum(axis=1)))
        return poses[i:i + 1], {name: m[i:i + 1] for name, m in measures.items()}

    best, measures = best_of(problem.preferred[None], exact=True)
    if _costs(problem, best, measures).sum() == 0.0:
        return best, measures  # every margin met at the preferred pose: nothing can beat it
    half = np.array([cfg.height_range, cfg.roll_range, cfg.pitch_range, cfg.yaw_range])
    counts = np.asarray(cfg.grid)
    axes = [np.linspace(-1.0, 1.0, c) if c > 1 else np.zeros(1) for c in counts]
    unit = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 4)
    best, measures = best_of(problem.preferred + unit * half)
    step = np.where(counts > 1, 2 * half / np.maximum(counts - 1, 1), half)  # grid spacing
    pattern = np.stack(np.meshgrid(*[np.array([-1.0, 0.0, 1.0])] * 4, indexing="ij"),
                       axis=-1).reshape(-1, 4)
    for _ in range(cfg.refinements):
        step = step / 2
        best, measures = best_of(best + pattern * step)
    rot = rotation_matrix(best[:, 1:])
    body = np.column_stack([problem.body_xy[None], best[:, :1]])
    measures["trunk_clearance"] = _trunk_clearance(problem, best, body, rot, exact=True)
    return best, measures


def find_pose(hmap: HeightMap, feet: np.ndarray, body_xy: np.ndarray, yaw_hint: float,
              robot: RobotDescription = LITTLEDOG, config: PoseConfig | None = None) -> Pose:
    """The body pose for a stance on four footholds.

    Parameters
    ----------
    hmap : HeightMap
        The terrain (cells without data are no obstacle).
    feet : array of shape (4, 3)
        World contact points [m] of the four feet, in LEG_NAMES order (the
        ball centres are ``robot.foot_radius`` above them).
    body_xy : array of shape (2,)
        World x, y [m] of the body origin (from the COG planner).
    yaw_hint : float
        Preferred heading [rad], e.g. along the body path.
    robot : RobotDescription
    config : PoseConfig, optional

    Returns
    -------
    Pose
        Height, roll, pitch, yaw, score and the cost terms. ``reachable`` is
        false when the pose found does not reach all four footholds within
        the joint limits -- e.g. feet too far apart, where no pose can; it is
        then the best compromise the search found.
    """
    config = config or PoseConfig()
    feet = np.asarray(feet, dtype=np.float64)
    body_xy = np.asarray(body_xy, dtype=np.float64)
    if feet.shape != (4, 3) or body_xy.shape != (2,):
        raise FootfallError(f"find_pose needs feet (4, 3) and body_xy (2,), "
                            f"got {feet.shape} and {body_xy.shape}")
    if not (np.isfinite(feet).all() and np.isfinite(body_xy).all() and np.isfinite(yaw_hint)):
        raise FootfallError("find_pose: feet, body_xy and yaw_hint must be finite")
    yaw_hint = float(yaw_hint)
    # The trunk's footprint at any searched yaw and tilt lies within this square.
    radius = np.hypot(*robot.trunk_size[:2]) / 2 + config.trunk_cell
    cells_xy, cells_h = _trunk_cells(hmap, body_xy, radius, config.trunk_cell)
    # Keep the cells the trunk can cover at any yaw the search can reach: the grid spans
    # yaw_range either side of the hint, the pattern search at most as much again.
    turn = min(2 * config.yaw_range, np.pi / 2)
    lx, ly = robot.trunk_size[0] / 2, robot.trunk_size[1] / 2
    # Extents of the footprint turned by up to `turn`: lx cos + ly sin peaks at atan2(ly, lx).
    reach_u = (np.hypot(lx, ly) if turn >= np.arctan2(ly, lx)
               else lx * np.cos(turn) + ly * np.sin(turn)) + config.trunk_cell
    reach_v = (np.hypot(lx, ly) if turn >= np.arctan2(lx, ly)
               else lx * np.sin(turn) + ly * np.cos(turn)) + config.trunk_cell
    d = cells_xy - body_xy
    u = np.cos(yaw_hint) * d[:, 0] + np.sin(yaw_hint) * d[:, 1]
    v = -np.sin(yaw_hint) * d[:, 0] + np.cos(yaw_hint) * d[:, 1]
    near = (np.abs(u) <= reach_u) & (np.abs(v) <= reach_v)
    cells_xy, cells_h = cells_xy[near], cells_h[near]
    problem = _Problem(hmap=hmap, centres=feet + np.array([0.0, 0.0, robot.foot_radius]),
                       body_xy=body_xy,
                       preferred=preferred_pose(feet, body_xy, yaw_hint, robot, config),
                       cells_xy=cells_xy, cells_h=cells_h, robot=robot, config=config)
    best, measures = _search(problem)
    costs = _costs(problem, best, measures)[0]
    return Pose(body_xy=body_xy.copy(), height=float(best[0, 0]), rpy=best[0, 1:].copy(),
                score=-float(costs.sum()), terms={t: float(c) for t, c in zip(TERMS, costs)},
                joint_margin=float(measures["joint"][0]), reach_margin=float(measures["reach"][0]),
                leg_clearance=float(measures["leg_clearance"][0]),
                trunk_clearance=float(measures["trunk_clearance"][0]),
                reachable=bool(measures["reachable"][0]))
