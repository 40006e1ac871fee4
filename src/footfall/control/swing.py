"""Swing-foot trajectories over the convex hull of the terrain (paper §IV-B 5).

The foot lifts nearly vertically, passes over the upper convex hull of the
terrain between lift-off and touch-down raised by a minimum clearance, and
sets down nearly vertically. The knots are joined by piecewise cubics that
are monotone between knots (PCHIP), and the path is run through in time with
zero velocity at both ends.

Convention: ``start``, ``end`` and every position of a :class:`SwingTrajectory`
are *contact-point* positions -- the lowest point of the ball foot, as in
:attr:`footfall.core.state.RobotState.feet` and the footstep plan. The ball's
centre, the inverse-kinematics target, is ``robot.foot_radius`` above it.

Why the path clears the terrain: the terrain profile bounds the terrain
within ``band`` of the straight xy segment from above (see
:func:`terrain_profile`), so a foot whose lowest point is above the profile
clears every terrain point under the ball when ``band`` is the foot radius.
The knots are the vertices of the upper convex hull of the raised profile
and the two lift points, a concave chain; on such a chain PCHIP's knot
tangents lie between the neighbouring chords (they are weighted harmonic
means, with the same weights for every coordinate), so every cubic piece
lies on or above its chord, and every chord on or above the raised profile.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.ndimage import maximum_filter1d
from scipy.spatial import ConvexHull, QhullError

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.params import Params, above, at_least, param
from footfall.core.robot import LITTLEDOG, RobotDescription

TIMINGS = ("cubic", "quintic")  # names of the time scalings SwingConfig.timing accepts
_MAX_PROFILE_SAMPLES = 200_000  # [-] guard against a path of kilometres at 1 mm
_ZERO_LENGTH = 1e-6  # [m] a horizontal move shorter than this is a move on the spot


@dataclass(frozen=True)
class SwingConfig(Params):
    """Every knob of the swing-foot trajectory (docs/configuration.md)."""

    clearance: float = param(0.02, unit="m", range=at_least(0),
                             doc="least height of the foot's lowest point above the terrain's "
                                 "hull")
    lift_height: float = param(0.02, unit="m", range=above(0),
                               doc="height of the knots straight above lift-off and touch-down")
    resolution: float | None = param(None, unit="m", range=above(0),
                                     doc="spacing of terrain profile samples; None: map "
                                         "resolution")
    band: float | None = param(None, unit="m", range=at_least(0),
                               doc="half-width of the terrain band the ball must clear; None: "
                                   "robot.foot_radius (the ball's footprint)")
    timing: str = param("quintic", choices=TIMINGS,
                        doc="time scaling of the path: 'cubic' (3u^2 - 2u^3, zero end velocity) "
                            "or 'quintic' (10u^3 - 15u^4 + 6u^5, zero end velocity and "
                            "acceleration)")


def _scaling(u: np.ndarray, timing: str) -> tuple[np.ndarray, np.ndarray]:
    """Time scaling and its derivative, u in [0, 1] -> (tau, dtau/du), both (...)."""
    if timing == "cubic":
        return u * u * (3 - 2 * u), 6 * u * (1 - u)
    return u ** 3 * (10 + u * (-15 + 6 * u)), 30 * u * u * (1 - u) ** 2


@dataclass(frozen=True, eq=False)
class SwingTrajectory:
    """A swing-foot path in time; positions are contact points (lowest point of the ball).

    Before 0 the foot rests at ``start`` and after ``duration`` at ``end``.
    """

    start: np.ndarray  # (3,) [m] world contact point at lift-off
    end: np.ndarray  # (3,) [m] world contact point at touch-down
    duration: float  # [s] time from lift-off to touch-down
    knots: np.ndarray  # (n, 3) [m] world positions of the knots, lift-off first
    knot_params: np.ndarray  # (n,) [m] path parameter of each knot: cumulative chord length
    profile: np.ndarray  # (m, 2) [m] (distance along the xy segment, terrain height to clear)
    clearance: float  # [m] the clearance the path keeps above ``profile``
    timing: str  # time scaling, one of TIMINGS
    _path: PchipInterpolator  # (distance along the xy segment, height) [m] of the path parameter
    _rate: PchipInterpolator = field(init=False, repr=False)  # derivative of _path

    def __post_init__(self) -> None:
        object.__setattr__(self, "_rate", self._path.derivative())

    @property
    def direction(self) -> np.ndarray:
        """Unit xy direction (2,) from lift-off to touch-down (x axis if they coincide)."""
        d = self.end[:2] - self.start[:2]
        n = np.linalg.norm(d)
        return d / n if n > _ZERO_LENGTH else np.array([1.0, 0.0])

    def _param(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = np.clip(np.asarray(t, dtype=np.float64) / self.duration, 0.0, 1.0)
        tau, dtau = _scaling(u, self.timing)
        total = self.knot_params[-1]
        return total * tau, total * dtau / self.duration

    def at_param(self, sigma: np.ndarray) -> np.ndarray:
        """Positions [m] (..., 3) at path parameters ``sigma`` [m] (0 .. knot_params[-1])."""
        sz = self._path(np.asarray(sigma, dtype=np.float64))
        xy = self.start[:2] + sz[..., :1] * self.direction
        return np.concatenate([xy, sz[..., 1:]], axis=-1)

    def position(self, t: np.ndarray) -> np.ndarray:
        """Contact-point positions [m] (..., 3) at times ``t`` [s] (...) after lift-off."""
        sigma, _ = self._param(t)
        return self.at_param(sigma)

    def velocity(self, t: np.ndarray) -> np.ndarray:
        """Velocities [m/s] (..., 3) at times ``t`` [s] (...); zero at 0 and ``duration``."""
        sigma, rate = self._param(t)
        dsz = self._rate(sigma) * np.asarray(rate)[..., None]
        return np.concatenate([dsz[..., :1] * self.direction, dsz[..., 1:]], axis=-1)

    @property
    def knot_times(self) -> np.ndarray:
        """Time [s] (n,) at which the foot passes each knot (bisection of the time scaling)."""
        target = self.knot_params / self.knot_params[-1]
        lo, hi = np.zeros_like(target), np.ones_like(target)
        for _ in range(60):  # 60 halvings: exact to double precision
            mid = 0.5 * (lo + hi)
            below = _scaling(mid, self.timing)[0] < target
            lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
        u = 0.5 * (lo + hi)
        u[[0, -1]] = 0.0, 1.0  # the scaling is flat at the ends: pin them exactly
        return u * self.duration


def terrain_profile(hmap: HeightMap, start_xy: np.ndarray, end_xy: np.ndarray, band: float,
                    resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """An upper bound of the terrain within ``band`` of each sample of a straight xy segment.

    Samples ``s`` are spaced at most ``resolution`` [m] along the segment.
    The map's terrain between cell centres is their bilinear interpolation,
    never higher than the four cell centres around it, which lie within one
    cell diagonal of the point. So the profile at ``s`` is the highest cell
    centre whose offsets along and across the segment are within ``band +
    cell diagonal`` of (s, 0): at least as high as every terrain point in
    the square ``[s - band, s + band] x [-band, band]`` (the ball foot's
    footprint when ``band`` is its radius). Cells without data, and windows
    reaching off the map, count as the highest data near the segment; with
    no data at all the profile is NaN, for the caller to replace.

    Returns
    -------
    s : ndarray of shape (m,)
        Distance [m] along the segment from ``start_xy``, 0 .. length.
    height : ndarray of shape (m,)
        Terrain height bound [m] around each sample.
    """
    start_xy = np.asarray(start_xy, dtype=np.float64)
    delta = np.asarray(end_xy, dtype=np.float64) - start_xy
    length = float(np.linalg.norm(delta))
    along = delta / length if length > _ZERO_LENGTH else np.array([1.0, 0.0])
    side = np.array([-along[1], along[0]])
    n_along = max(int(np.ceil(length / resolution)), 1)
    if n_along > _MAX_PROFILE_SAMPLES:
        raise FootfallError(f"swing of {length:.3g} m is too long to sample at {resolution:.3g} m")
    ds = length / n_along if length > _ZERO_LENGTH else resolution
    s = np.minimum(np.arange(n_along + 1) * ds, length)
    reach = band + hmap.resolution * np.sqrt(2.0)

    # Window corners of every sample; those reaching off the map see "no data".
    ends = np.array([-reach, length + reach])
    box = start_xy + ends[:, None, None] * along + np.array([-reach, reach])[None, :, None] * side
    box = box.reshape(-1, 2)
    corner = (start_xy + s[:, None, None, None] * along
              + np.array([-reach, reach])[None, :, None, None] * along
              + np.array([-reach, reach])[None, None, :, None] * side)
    off_map = ~hmap.is_inside(corner).all(axis=(1, 2))

    # Cell centres near the segment, binned to their nearest sample.
    nx, ny = hmap.shape
    lo = np.maximum(np.floor(hmap.continuous_index(box.min(axis=0))).astype(int), 0)
    hi = np.minimum(np.ceil(hmap.continuous_index(box.max(axis=0))).astype(int), [nx - 1, ny - 1])
    if np.any(hi < lo):
        return s, np.full(s.shape, np.nan)
    sub = hmap.heights[lo[0]:hi[0] + 1, lo[1]:hi[1] + 1]
    cx = hmap.origin[0] + np.arange(lo[0], hi[0] + 1) * hmap.resolution - start_xy[0]
    cy = hmap.origin[1] + np.arange(lo[1], hi[1] + 1) * hmap.resolution - start_xy[1]
    a = cx[:, None] * along[0] + cy[None, :] * along[1]
    c = cx[:, None] * side[0] + cy[None, :] * side[1]
    near = (np.abs(c) <= reach) & (a >= -reach) & (a <= length + reach)
    values, a = sub[near], a[near]
    holes = np.isnan(values)
    if holes.all():
        return s, np.full(s.shape, np.nan)
    top = np.nanmax(values)
    values = np.where(holes, top, values)
    m = int(np.ceil((reach + ds / 2) / ds))  # window half-width in samples, rounding included
    bins = np.clip(np.rint(a / ds).astype(int), -m, n_along + m) + m
    acc = np.full(n_along + 1 + 2 * m, -np.inf)
    np.maximum.at(acc, bins, values)
    height = maximum_filter1d(acc, size=2 * m + 1, mode="nearest")[m:m + n_along + 1]
    height = np.where(off_map | ~np.isfinite(height), top, height)
    return s, height


def _upper_hull(s: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Indices of the vertices of the upper convex hull of points (s, z), strictly inside (s0, s1).

    ``s`` must be sorted and span a positive length; two floor points far
    below close the hull, so the vertices with 0 < s < length all lie on the
    upper chain.
    """
    floor = z.min() - 1.0 - (z.max() - z.min())
    pts = np.column_stack([np.concatenate([s, s[[0, -1]]]),
                           np.concatenate([z, [floor, floor]])])
    vertices = ConvexHull(pts).vertices
    vertices = vertices[vertices < s.size]
    vertices = vertices[(s[vertices] > s[0]) & (s[vertices] < s[-1])]
    return np.sort(vertices)


def swing_trajectory(hmap: HeightMap, start: np.ndarray, end: np.ndarray, duration: float,
                     robot: RobotDescription = LITTLEDOG, config: SwingConfig | None = None
                     ) -> SwingTrajectory:
    """Plan a swing from contact point ``start`` (3,) to contact point ``end`` (3,) [m].

    Parameters
    ----------
    hmap : HeightMap
        The terrain.
    start, end : array of shape (3,)
        World contact points [m] (lowest point of the ball foot) at lift-off
        and touch-down.
    duration : float
        Swing time [s], > 0.
    robot : RobotDescription
        Supplies the foot radius (the default band half-width).
    config : SwingConfig, optional

    Returns
    -------
    SwingTrajectory
        Knots: lift-off, the point ``lift_height`` above it (or higher if the
        raised terrain is), the interior vertices of the upper convex hull of
        the terrain profile raised by ``clearance``, the point above
        touch-down, touch-down. Every position whose xy lies strictly between
        lift-off and touch-down is at least ``clearance`` above the terrain
        within ``band`` of it. Cells without data count as the highest data
        near the segment (no data at all: the higher of the two footholds).
    """
    config = config or SwingConfig()
    start = np.asarray(start, dtype=np.float64)
    end = np.asarray(end, dtype=np.float64)
    if start.shape != (3,) or end.shape != (3,):
        raise FootfallError(f"swing start and end must be (3,) points, got {start.shape} and {end.shape}")
    if not (np.isfinite(start).all() and np.isfinite(end).all()):
        raise FootfallError("swing start and end must be finite")
    if not (np.isfinite(duration) and duration > 0):
        raise FootfallError(f"swing duration must be > 0 s, got {duration}")
    band = robot.foot_radius if config.band is None else config.band
    resolution = hmap.resolution if config.resolution is None else config.resolution

    s, ground = terrain_profile(hmap, start[:2], end[:2], band, resolution)
    ground = np.where(np.isnan(ground), max(start[2], end[2]), ground)
    raised = ground + config.clearance
    length = s[-1]
    top0 = max(start[2] + config.lift_height, raised[0])
    top1 = max(end[2] + config.lift_height, raised[-1])
    if length > _ZERO_LENGTH:
        hull_s = np.concatenate([[0.0], s, [length]])
        hull_z = np.concatenate([[top0], raised, [top1]])
        try:
            inner = _upper_hull(hull_s, hull_z)
        except QhullError:  # numerically degenerate: a flat chain over everything is safe
            top0 = top1 = hull_z.max()
            inner = np.zeros(0, dtype=int)
        knots_sz = np.vstack([[0.0, start[2]], [0.0, top0],
                              np.column_stack([hull_s[inner], hull_z[inner]]),
                              [length, top1], [length, end[2]]])
    else:  # a move on the spot: straight up and down again
        top = max(top0, top1)
        knots_sz = np.array([[0.0, start[2]], [0.0, top], [length, end[2]]])
    params = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(knots_sz, axis=0).T))])
    # One interpolant for both coordinates: the same knots, each coordinate monotone between them.
    path = PchipInterpolator(params, knots_sz, axis=0)
    along = (end[:2] - start[:2]) / length if length > _ZERO_LENGTH else np.array([1.0, 0.0])
    knots = np.column_stack([start[:2] + knots_sz[:, :1] * along, knots_sz[:, 1]])
    knots[-1] = end  # exact, whatever the rounding of the segment's length
    return SwingTrajectory(start=start.copy(), end=end.copy(), duration=float(duration),
                           knots=knots, knot_params=params,
                           profile=np.column_stack([s, ground]), clearance=config.clearance,
                           timing=config.timing, _path=path)
