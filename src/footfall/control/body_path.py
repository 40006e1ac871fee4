"""The approximate body path planner (paper §IV-B.1): a path for the body from start to goal.

The terrain is cut into square cells (1 cm). Each cell gets a reward that
assumes the body centred there, heading along the walking direction, with
the four feet in their default stance: for each leg the sum of the best five
foothold rewards within a small radius of its default foot position, plus
heuristic penalties for trunk and knee clearance. Dijkstra's algorithm on the
8-connected cell grid (:func:`scipy.sparse.csgraph.dijkstra`) then finds the
cheapest path, which is smoothed lightly into a :class:`BodyPath`. The
footstep planner (:mod:`footfall.control.footstep`) follows that path.

The foothold rewards come from dense grids of the scorers' terrain parts
(:func:`footfall.control.grids.terrain_grids`), computed once per board and
shared with the footstep planner.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from footfall.control.grids import grid_index, grid_spacing, terrain_grids
from footfall.control.path import BodyPath
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import inverse_kinematics, knee_position
from footfall.core.params import Params, above, at_least, param
from footfall.core.robot import LEG_NAMES, LITTLEDOG, RobotDescription
from footfall.features.dense import ScoreGrid
from footfall.features.scorer import FootholdScorer, RewardFor
from footfall.features.spread import reward_unit


@dataclass(frozen=True)
class BodyPathConfig(Params):
    """Every knob of the approximate body path planner (docs/configuration.md).

    Rewards of different functions have different scales (a learned ranking
    function has no natural unit), so the planner measures them in a *reward
    unit* of the map: the standard deviation of the per-foothold terrain
    rewards at the lattice points the path can use (see :func:`reward_unit`).
    The clearance weights and the cost weight are in that unit, which makes
    the path independent of the reward's scale.
    """

    cell: float = param(0.01, unit="m", range=above(0),
                        doc="side of a grid cell of the path search (1 cm, as in the paper)")
    spacing: float = param(0.005, unit="m", range=above(0),
                           doc="lattice spacing of the dense foothold reward grids")
    search_radius: float = param(0.025, unit="m", range=above(0),
                                 doc="footholds within this distance of a default foot "
                                     "position count")
    best_k: int = param(5, unit="-", range=at_least(1),
                        doc="best footholds per leg summed into a cell's reward")
    body_margin: float = param(0.01, unit="m", range=at_least(0),
                               doc="clearance the trunk's underside should keep above the "
                                   "terrain")
    body_weight: float = param(1000.0, unit="unit/m", range=at_least(0),
                               doc="penalty per metre the trunk falls short of body_margin")
    knee_margin: float = param(0.01, unit="m", range=at_least(0),
                               doc="clearance each knee (surface) should keep above the terrain")
    knee_radius: float = param(0.015, unit="m", range=above(0),
                               doc="terrain within this horizontal distance of a knee counts "
                                   "under it")
    knee_weight: float = param(500.0, unit="unit/m", range=at_least(0),
                               doc="penalty per metre a knee's clearance falls short, per knee")
    cost_weight: float = param(1.0, unit="-", range=at_least(0),
                               doc="extra path cost per reward unit a cell's footholds lose, "
                                   "on average")
    smoothing: float = param(0.1, unit="m", range=above(0),
                             doc="length of the moving average that smooths the grid path")


def _patch_half_extent(reward: FootholdScorer, yaw: float) -> tuple[float, float]:
    """Half extents [m] along the map's x and y of the largest feature patch at heading ``yaw``."""
    hx = max(s.length_x for s in reward.config.scales) / 2
    hy = max(s.length_y for s in reward.config.scales) / 2
    c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
    return c * hx + s * hy, s * hx + c * hy


def _interior(grid: ScoreGrid, hmap: HeightMap, half: tuple[float, float]) -> np.ndarray:
    """Lattice points (na, nb) whose patches lie wholly within the map's bounds."""
    x0, x1, y0, y1 = hmap.bounds
    ix = (grid.x - half[0] >= x0 - 1e-9) & (grid.x + half[0] <= x1 + 1e-9)
    iy = (grid.y - half[1] >= y0 - 1e-9) & (grid.y + half[1] <= y1 + 1e-9)
    return ix[:, None] & iy[None, :]


# ------------------------------------------------------------ cell rewards
@dataclass(frozen=True, eq=False)
class CellRewards:
    """The reward of every cell of the path search and the terms it is made of."""

    x: np.ndarray  # (nx,) [m] cell-centre x coordinates (multiples of the cell size)
    y: np.ndarray  # (ny,) [m] cell-centre y coordinates
    footholds: np.ndarray  # (nx, ny) sum over legs of the best-k foothold rewards; -inf: a leg has none
    body_clearance: np.ndarray  # (nx, ny) [m] trunk underside above the highest terrain beneath it
    knee_clearance: np.ndarray  # (nx, ny, 4) [m] knee surface above the terrain near it, LEG_NAMES order
    unit: float  # the reward unit (see reward_unit) the heuristic weights are measured in
    reward: np.ndarray  # (nx, ny) footholds + unit * (clearance heuristics); -inf: impassable


def _cell_axis(lo: float, hi: float, cell: float) -> np.ndarray:
    k = np.arange(math.ceil(lo / cell - 1e-9), math.floor(hi / cell - 1e-9) + 1)
    return k * cell


def _pooled_max(hmap: HeightMap, x: np.ndarray, y: np.ndarray, cell: float) -> np.ndarray:
    """Highest terrain [m] among the map cells nearest each path cell, (nx, ny); -inf: no data."""
    h = np.where(np.isnan(hmap.heights), -np.inf, hmap.heights)
    out = h
    for axis, (coords, centres) in enumerate(((hmap.x, x), (hmap.y, y))):
        idx = np.clip(np.floor((coords - centres[0]) / cell + 0.5).astype(np.int64), 0, centres.size - 1)
        starts = np.searchsorted(idx, np.arange(centres.size))  # idx is sorted: one run per cell
        empty = starts >= idx.size
        pooled = np.maximum.reduceat(out, np.minimum(starts, idx.size - 1), axis=axis)
        if empty.any():  # path cells past the map's last row: no data
            pooled = np.moveaxis(pooled, axis, 0)
            pooled[empty] = -np.inf
            pooled = np.moveaxis(pooled, 0, axis)
        out = pooled
    return out


def _offsets_in_rectangle(half_x: float, half_y: float, yaw: float, cell: float) -> np.ndarray:
    """Footprint mask of a rectangle at heading yaw: cells whose square may touch it, (2a+1, 2b+1)."""
    grow = cell / math.sqrt(2.0)  # half a cell's diagonal: conservative at every heading
    reach = math.hypot(half_x, half_y) + grow
    n = int(math.ceil(reach / cell))
    d = np.arange(-n, n + 1) * cell
    dx, dy = np.meshgrid(d, d, indexing="ij")
    c, s = math.cos(yaw), math.sin(yaw)
    u, v = c * dx + s * dy, -s * dx + c * dy
    return (np.abs(u) <= half_x + grow) & (np.abs(v) <= half_y + grow)


def _disc(radius: float, cell: float) -> np.ndarray:
    """Footprint mask of the cells whose square may touch a disc of ``radius`` [m]."""
    reach = radius + cell / math.sqrt(2.0)
    n = int(math.ceil(reach / cell))
    d = np.arange(-n, n + 1) * cell
    return np.hypot(d[:, None], d[None, :]) <= reach


def nominal_knees(robot: RobotDescription = LITTLEDOG) -> np.ndarray:
    """Knee-axis positions [m] (4, 3) in the body frame with the feet in the nominal stance."""
    out = []
    for name in LEG_NAMES:
        leg = robot.leg(name)
        centre = np.array(robot.nominal_foot(name)) + np.array([0.0, 0.0, robot.foot_radius])
        q, ok = inverse_kinematics(leg, centre, robot)
        if not ok:
            raise FootfallError(f"the nominal stance of leg {name} is out of reach")
        out.append(knee_position(leg, q, robot))
    return np.array(out)


def evaluate_cells(hmap: HeightMap, reward_for: RewardFor, robot: RobotDescription = LITTLEDOG,
                   config: BodyPathConfig = BodyPathConfig(), yaw: float = 0.0,
                   grids: dict[str, ScoreGrid] | None = None) -> CellRewards:
    """The reward of every cell, assuming the body there at heading ``yaw`` in its default stance.

    For each leg the default foot position (``robot.nominal_foot``, rotated
    by ``yaw``) is snapped to the nearest lattice point of its reward grid;
    the ``best_k`` highest rewards among the lattice points within
    ``search_radius`` of it are summed (if fewer than ``best_k`` are valid, the
    missing ones count as the worst valid one; none valid: the cell is
    impassable, -inf). Only lattice points whose feature patches lie wholly
    on the map are used: at the map's border the patches are cut and their
    rewards are not comparable. Heuristics, in reward units:

    * body: the trunk box (``robot.trunk_size``) with its origin
      ``nominal_height`` above the mean terrain height at the default foot
      positions (those with data; none: height 0); its underside should clear the highest terrain beneath its
      footprint by ``body_margin``;
    * knees: the nominal knees (inverse kinematics of the nominal stance)
      should clear the highest terrain within ``knee_radius`` by
      ``knee_margin`` (knee surface: axis less ``robot.lower_leg_radius``).

    A shortfall ``d`` [m] costs ``weight * unit * d``. Terrain maxima are taken
    over path cells (each holds the highest map cell nearest to it) under a
    footprint grown by half a cell's diagonal: conservative by up to a cell.
    Map cells without data count as no obstacle.

    Parameters
    ----------
    reward_for : callable
        ``reward_for(leg_name) -> FootholdScorer`` (e.g. ``FootholdModel.reward_for``).
    yaw : float
        Body heading [rad] assumed in every cell.
    grids : dict, optional
        Precomputed :func:`terrain_grids` (same spacing and yaw) to reuse.
    """
    if not isinstance(hmap, HeightMap):
        raise FootfallError(f"the body path planner needs a HeightMap, got {type(hmap).__name__}")
    yaw = float(yaw)
    if not math.isfinite(yaw):
        raise FootfallError(f"heading must be finite, got {yaw}")
    if grids is None:
        grids = terrain_grids(hmap, reward_for, robot, config.spacing, yaw)
    cell = config.cell
    x0, x1, y0, y1 = hmap.bounds
    xs, ys = _cell_axis(x0, x1, cell), _cell_axis(y0, y1, cell)
    if xs.size < 2 or ys.size < 2:
        raise FootfallError("the map is smaller than two path cells along x or y")
    centres = np.stack(np.meshgrid(xs, ys, indexing="ij"), axis=-1)  # (nx, ny, 2)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    footholds, pooled_rewards = _foothold_sums(hmap, reward_for, grids, robot, config, yaw,
                                               centres, rot)
    unit = reward_unit(pooled_rewards)
    body_clear, knee_clear = _clearances(hmap, robot, config, yaw, xs, ys, centres, rot)
    body_short = np.maximum(config.body_margin - body_clear, 0.0)
    knee_short = np.maximum(config.knee_margin - knee_clear, 0.0).sum(axis=-1)
    heuristic = -unit * (config.body_weight * body_short + config.knee_weight * knee_short)
    reward = np.where(np.isfinite(footholds), footholds + heuristic, -np.inf)
    return CellRewards(xs, ys, footholds, body_clear, knee_clear, unit, reward)


def _foothold_sums(hmap: HeightMap, reward_for: RewardFor, grids: dict[str, ScoreGrid],
                   robot: RobotDescription, config: BodyPathConfig, yaw: float,
                   centres: np.ndarray, rot: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """Sum over the legs of each cell's best-k foothold rewards (nx, ny) (-inf: a leg has none),
    and every distinct reward grid with the points whose patches leave the map masked (-inf).

    ``centres`` (nx, ny, 2) [m] are the cell centres, ``rot`` (2, 2) the body's rotation by ``yaw``.
    """
    masked: dict[int, np.ndarray] = {}
    pooled_rewards = []
    footholds = np.zeros(centres.shape[:2])
    for name in LEG_NAMES:  # four legs
        grid = grids[name]
        if id(grid) not in masked:
            inner = _interior(grid, hmap, _patch_half_extent(reward_for(name), yaw))
            masked[id(grid)] = np.where(inner, grid.reward, -np.inf)
            pooled_rewards.append(masked[id(grid)])
        foot = centres + np.array(robot.nominal_foot(name)[:2]) @ rot.T
        footholds += _best_k_sum(grid, masked[id(grid)], foot, config)
    return footholds, pooled_rewards


def _best_k_sum(grid: ScoreGrid, values: np.ndarray, foot: np.ndarray, config: BodyPathConfig
                ) -> np.ndarray:
    """Sum of the ``best_k`` rewards ``values`` (na, nb) on ``grid``'s lattice within
    ``search_radius`` of each default foot position (nx, ny, 2) [m]; -inf where none is valid.

    Each cell's window of lattice points is gathered at once.
    """
    spacing = grid_spacing(grid)
    n = int(math.floor(config.search_radius / spacing + 1e-9))
    d = np.arange(-n, n + 1)
    di, dj = np.meshgrid(d, d, indexing="ij")
    keep = (di * di + dj * dj) * spacing * spacing <= config.search_radius ** 2 + 1e-12
    di, dj = di[keep], dj[keep]  # (m,) window offsets in lattice steps
    pad = 2 * n + 1
    padded = np.pad(values, pad, constant_values=-np.inf)
    i, j = grid_index(grid, foot, spacing)
    # Far off the grid: clipped to where the whole window is still off it (-inf).
    i = np.clip(i, -n - 1, values.shape[0] + n) + pad
    j = np.clip(j, -n - 1, values.shape[1] + n) + pad
    window = padded[i[..., None] + di, j[..., None] + dj]  # (nx, ny, m)
    k = min(config.best_k, window.shape[-1])
    best = -np.partition(-window, k - 1, axis=-1)[..., :k]
    # Missing footholds count as the worst valid one; none valid (worst = inf): impassable.
    worst = np.min(np.where(np.isfinite(best), best, np.inf), axis=-1, keepdims=True)
    total = np.where(np.isfinite(best), best, worst).sum(axis=-1)
    return np.where(np.isfinite(worst[..., 0]), total, -np.inf)


def _clearances(hmap: HeightMap, robot: RobotDescription, config: BodyPathConfig, yaw: float,
                xs: np.ndarray, ys: np.ndarray, centres: np.ndarray, rot: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Clearance [m] of the trunk's underside (nx, ny) and of the knees (nx, ny, 4) above the
    highest terrain under them, the body in its default stance in every cell (see
    :func:`evaluate_cells`)."""
    cell = config.cell
    # Terrain heights: at the default feet, and the highest under trunk and knees.
    nominal = np.array([robot.nominal_foot(n_)[:2] for n_ in LEG_NAMES]) @ rot.T  # (4, 2)
    feet_z = hmap.height_at(centres[:, :, None, :] + nominal)  # (nx, ny, 4)
    has = np.isfinite(feet_z)
    mean_z = np.where(has, feet_z, 0.0).sum(-1) / np.maximum(has.sum(-1), 1)
    body_z = mean_z + robot.nominal_height
    pooled = _pooled_max(hmap, xs, ys, cell)
    trunk = _offsets_in_rectangle(robot.trunk_size[0] / 2, robot.trunk_size[1] / 2, yaw, cell)
    under = ndimage.maximum_filter(pooled, footprint=trunk, mode="constant", cval=-np.inf)
    body_clear = body_z - robot.trunk_size[2] / 2 - under
    near = ndimage.maximum_filter(pooled, footprint=_disc(config.knee_radius, cell),
                                  mode="constant", cval=-np.inf)
    knees = nominal_knees(robot)
    knee_clear = np.empty(centres.shape[:2] + (4,))
    for k_, knee in enumerate(knees):  # four knees
        off = np.floor(knee[:2] @ rot.T / cell + 0.5).astype(np.int64)
        ki = np.arange(xs.size)[:, None] + off[0]
        kj = np.arange(ys.size)[None, :] + off[1]
        inside = (ki >= 0) & (ki < xs.size) & (kj >= 0) & (kj < ys.size)
        ground = np.where(inside, near[np.clip(ki, 0, xs.size - 1), np.clip(kj, 0, ys.size - 1)],
                          -np.inf)
        knee_clear[..., k_] = body_z + knee[2] - robot.lower_leg_radius - ground
    return body_clear, knee_clear


def cell_rewards(hmap: HeightMap, reward_for: RewardFor, robot: RobotDescription = LITTLEDOG,
                 config: BodyPathConfig = BodyPathConfig(), yaw: float = 0.0,
                 grids: dict[str, ScoreGrid] | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell centres x (nx,), y (ny,) [m] and cell rewards (nx, ny); see :func:`evaluate_cells`."""
    cells = evaluate_cells(hmap, reward_for, robot, config, yaw, grids)
    return cells.x, cells.y, cells.reward


# ---------------------------------------------------------------- the path
def _smooth(points: np.ndarray, spacing: float, length: float) -> np.ndarray:
    """Resample a polyline every ``spacing`` [m], then a moving average over ``length`` [m].

    The ends are extended by point reflection, so they stay where they are
    and a straight line stays exactly straight.
    """
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    n = max(int(math.ceil(s[-1] / spacing)), 1)
    t = np.linspace(0.0, s[-1], n + 1)
    p = np.column_stack([np.interp(t, s, points[:, 0]), np.interp(t, s, points[:, 1])])
    h = min(int(round(length / spacing / 2)), p.shape[0] - 1)
    if h < 1:
        return p
    head = 2 * p[0] - p[h:0:-1]
    tail = 2 * p[-1] - p[-2:-h - 2:-1]
    ext = np.concatenate([head, p, tail])
    return ndimage.uniform_filter1d(ext, size=2 * h + 1, axis=0, mode="nearest")[h:-h]


def plan_body_path(hmap: HeightMap, reward_for: RewardFor, start_xy, goal,
                   robot: RobotDescription = LITTLEDOG, config: BodyPathConfig = BodyPathConfig(),
                   *, yaw: float = 0.0, grids: dict[str, ScoreGrid] | None = None,
                   cells: CellRewards | None = None) -> BodyPath:
    """The cheapest body path from ``start_xy`` to ``goal`` over the cell grid (Dijkstra).

    Edge costs: a move between 8-connected neighbouring cells costs its
    length [m] times the mean of the two cells' costs

        c = 1 + cost_weight * (r_best - r) / (4 * best_k * unit),

    where ``r`` is the cell reward, ``r_best`` the best cell reward of the
    map and ``unit`` the reward unit: c = 1 on the best cells, and a cell
    whose footholds are on average one unit worse than the best cell's costs
    ``1 + cost_weight`` per metre. Impassable cells (-inf) have no edges. The
    start cell is the cell nearest ``start_xy``; the path ends at the cell
    nearest a goal point, or, for a goal line ``x = goal``, at the cheapest
    reachable cell of the column nearest it. The grid path runs from
    ``start_xy`` to the goal (the line's cell y) and is smoothed by a moving
    average over ``config.smoothing`` metres (ends held).

    Parameters
    ----------
    start_xy : array of shape (2,)
        Start of the body [m].
    goal : array of shape (2,), or float
        Goal point [m], or the x [m] of a goal line across the board.
    yaw : float
        Body heading [rad] the cell rewards assume (the walking direction).
    grids, cells : optional
        Precomputed :func:`terrain_grids` or :func:`evaluate_cells` to reuse.

    Raises
    ------
    FootfallError
        Start or goal off the grid or impassable, or no path between them.
    """
    if cells is None:
        cells = evaluate_cells(hmap, reward_for, robot, config, yaw, grids)
    start = np.asarray(start_xy, dtype=np.float64)
    if start.shape != (2,) or not np.isfinite(start).all():
        raise FootfallError(f"start must be a finite (x, y) [m], got {start_xy!r}")
    goal_arr = np.asarray(goal, dtype=np.float64)
    if goal_arr.shape not in ((), (2,)) or not np.isfinite(goal_arr).all():
        raise FootfallError(f"goal must be a finite (x, y) point or an x line [m], got {goal!r}")
    cell = config.cell
    si, sj = _cell_index(cells, start, "start", cell)
    dist, pred = _cheapest_paths(cells, config, si, sj)
    xs, ys = cells.x, cells.y
    if goal_arr.shape == (2,):
        gi, gj = _cell_index(cells, goal_arr, "goal", cell)
        end = goal_arr
    else:
        gi = int(np.floor((float(goal_arr) - xs[0]) / cell + 0.5))
        if not 0 <= gi < xs.size:
            raise FootfallError(f"goal line x = {float(goal_arr):.3f} m is off the map")
        gj = int(np.argmin(dist[gi]))
        end = np.array([float(goal_arr), ys[gj]])
    if not np.isfinite(dist[gi, gj]):
        raise FootfallError("no passable body path from the start to the goal")

    node, chain = gi * ys.size + gj, []
    while node >= 0:  # walk the predecessor tree back to the start (path length, not cells)
        chain.append(node)
        node = int(pred[node])
    chain = np.array(chain[::-1])
    pts = np.column_stack([xs[chain // ys.size], ys[chain % ys.size]])
    pts = np.concatenate([start[None], pts[1:-1], end[None]]) if pts.shape[0] > 2 else \
        np.array([start, end])
    if np.linalg.norm(pts[-1] - pts[0]) < 1e-12 and pts.shape[0] <= 2:
        raise FootfallError("start and goal coincide: no path to plan")
    return BodyPath(_smooth(pts, cell, config.smoothing))


def _cell_index(cells: CellRewards, xy: np.ndarray, what: str, cell: float) -> tuple[int, int]:
    """Index (i, j) of the path cell nearest ``xy`` (2,) [m]; raises FootfallError if it is off
    the grid or impassable (``what`` names the point in the message)."""
    i = int(np.floor((xy[0] - cells.x[0]) / cell + 0.5))
    j = int(np.floor((xy[1] - cells.y[0]) / cell + 0.5))
    if not (0 <= i < cells.x.size and 0 <= j < cells.y.size):
        raise FootfallError(f"{what} ({xy[0]:.3f}, {xy[1]:.3f}) m is off the map")
    if not np.isfinite(cells.reward[i, j]):
        raise FootfallError(f"{what} ({xy[0]:.3f}, {xy[1]:.3f}) m is impassable: some leg has "
                            f"no valid foothold near its default position")
    return i, j


def _cheapest_paths(cells: CellRewards, config: BodyPathConfig, si: int, sj: int
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Dijkstra from cell (si, sj) over the 8-connected grid of passable cells: the cost of the
    cheapest path to every cell (nx, ny) (inf: unreachable) and each node's predecessor (nx * ny,)
    (node ``i * ny + j``; negative at the start and at unreachable nodes)."""
    reward, cell = cells.reward, config.cell
    nx, ny = reward.shape
    passable = np.isfinite(reward)
    best = reward[passable].max()
    cost = np.where(passable,
                    1.0 + config.cost_weight * (best - np.where(passable, reward, best))
                    / (4 * config.best_k * cells.unit), np.inf)

    # 8-connected grid graph: four edge directions, each undirected.
    ids = np.arange(nx * ny).reshape(nx, ny)
    rows, cols, weights = [], [], []
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):  # four directions, not a loop over cells
        a = (slice(0, nx - di), slice(max(0, -dj), ny - max(0, dj)))
        b = (slice(di, nx), slice(max(0, dj), ny - max(0, -dj)))
        ok = passable[a] & passable[b]
        rows.append(ids[a][ok])
        cols.append(ids[b][ok])
        weights.append(math.hypot(di, dj) * cell * 0.5 * (cost[a][ok] + cost[b][ok]))
    graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(nx * ny, nx * ny)).tocsr()
    dist, pred = dijkstra(graph, directed=False, indices=ids[si, sj], return_predecessors=True)
    return dist.reshape(nx, ny), pred
