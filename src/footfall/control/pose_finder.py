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
steps, every round evaluating all its poses at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import (
    legs_inverse_kinematics,
    legs_joint_limit_margin,
    legs_knee_position,
    rotation_matrix,
)
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

    Unless ``exact``, the trunk clearance of a pose whose lowest possible
    underside point clears the highest cell by the wanted clearance is
    reported as that lower bound (its cost is zero either way).
    """
    robot, cfg = problem.robot, problem.config
    n = poses.shape[0]
    body = np.column_stack([np.broadcast_to(problem.body_xy, (n, 2)), poses[:, 0]])
    rot = rotation_matrix(poses[:, 1:])  # (n, 3, 3)
    local = (problem.centres[None] - body[:, None]) @ rot  # (n, 4, 3) body-frame foot centres

    frac = np.linspace(0.0, cfg.shin_fraction, cfg.shin_samples)
    q, ok = legs_inverse_kinematics(robot, local)  # the four legs and all poses at once
    ok_all = ok.all(axis=1)
    margin = legs_joint_limit_margin(robot, q)
    joint = np.where(np.isnan(margin), _NO_SOLUTION_MARGIN, margin)  # (n, 4)
    hips = np.array([leg.hip for leg in robot.legs])
    reach = robot.max_reach - np.linalg.norm(local - hips, axis=2)  # (n, 4)
    knee = legs_knee_position(robot, q)
    leg_points = knee[:, :, None] + frac[None, None, :, None] * (local - knee)[:, :, None]
    world = (leg_points.reshape(n, -1, 3) @ rot.transpose(0, 2, 1)).reshape(leg_points.shape)
    world += body[:, None, None]
    ground = problem.hmap.height_at(world[..., :2])
    clear = world[..., 2] - ground - robot.lower_leg_radius
    # No data below (or no IK solution, already charged as unreachable): no collision.
    clear = np.where(np.isnan(clear), np.inf, clear).min(axis=(1, 2))

    return {"joint": joint.min(axis=1), "reach": reach.min(axis=1), "leg_clearance": clear,
            "trunk_clearance": _trunk_clearance(problem, poses, body, rot, exact),
            "reachable": ok_all}


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
    r, b = rot[todo], body[todo]
    normal = r[:, :, 2]  # body z axis in the world
    centre = b - lz * normal  # a point of the underside plane
    gx, gy = -normal[:, 0] / normal[:, 2], -normal[:, 1] / normal[:, 2]
    # Which cells are under the trunk depends on x, y and yaw only: one mask per distinct yaw
    # (a search round has a handful). A cell counts if its centre lies within the footprint
    # grown by half a cell diagonal; the tilt's few-mm shift of the footprint is neglected.
    pad = cfg.trunk_cell / np.sqrt(2.0)
    yaws, group = np.unique(poses[todo, 3], return_inverse=True)
    xy, h = problem.cells_xy, problem.cells_h
    d = xy - problem.body_xy
    u = np.cos(yaws)[:, None] * d[:, 0] + np.sin(yaws)[:, None] * d[:, 1]
    v = -np.sin(yaws)[:, None] * d[:, 0] + np.cos(yaws)[:, None] * d[:, 1]
    under = (np.abs(u) <= lx + pad) & (np.abs(v) <= ly + pad)
    cells = under.any(axis=0)  # under the trunk at one of these yaws: the only cells that count
    if not cells.any():
        return out  # no cell with data under the trunk: nothing to clear
    xy, h, under = xy[cells], h[cells], under[:, cells]
    # Underside height above each cell centre: (m, 3) @ (3, p), one matrix product.
    coef = np.column_stack([centre[:, 2] - gx * centre[:, 0] - gy * centre[:, 1], gx, gy])
    plane = coef @ np.vstack([np.ones(h.size), xy.T])
    offset = np.where(under, -h, np.inf)  # (distinct yaws, p)
    out[todo] = (plane + offset[group]).min(axis=1)
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
