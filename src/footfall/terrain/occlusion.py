"""A module's heights as a scanner sees them: no data (NaN) behind rises, and dropouts.

A real elevation map has holes: cells a scanner looking from behind and above
could not see because something nearer stands in the way (the shadow), and
cells it missed for no visible reason (dropouts). :func:`as_scanned` turns a
generated module into such a map, by one rule shared by every kind that has
holes (the held-out ``scan``, the training ``rockyscan``). The planner has no
data in those cells; the simulator fills them down to the map's lowest height
(:func:`footfall.sim.hfield.terrain_surface`).

The rule, fixed before any run on a kind that uses it:

* the scanner stands :data:`SCANNER_BEHIND` behind the module's start at
  :data:`SCANNER_HEIGHT`; a cell is hidden when the ray from the scanner to it
  passes under a nearer cell's height (the ray's slope against the running
  maximum of the slopes in x); only cells farther than :data:`SEEN_EDGE` from
  both ends can be hidden, so a module always meets its neighbours with data;
* ``2 + round(8 d)`` dropouts, discs of radius U(0.008, 0.02) m, centres at
  least :data:`SEEN_EDGE` + :data:`DROPOUT_RAMP` from both ends and within
  0.28 m of the centre line.
"""

from __future__ import annotations

import numpy as np

from footfall.terrain.geometry import MODULE_SIZE, cell_centres

SCANNER_BEHIND = 0.3  # [m] the scanner's distance behind the module's start (x = 0)
SCANNER_HEIGHT = 0.6  # [m] the scanner's height above the ground plane
SEEN_EDGE = 0.05  # [m] cells within this of either end in x are always seen
DROPOUT_RAMP = 0.03  # [m] dropout centres keep this much farther from the ends again
DROPOUT_REACH = 0.28  # [m] dropout centres lie within this of the centre line (|y|)


def shadow(z: np.ndarray) -> np.ndarray:
    """Cells the scanner cannot see behind nearer, higher ones: bool (610, 610).

    ``z`` (610, 610) [m] are a module's heights, indexed [x, y]; the scanner
    looks along +x from (-:data:`SCANNER_BEHIND`, :data:`SCANNER_HEIGHT`).
    """
    x, _ = cell_centres()
    slope = (z - SCANNER_HEIGHT) / (x + SCANNER_BEHIND)  # [-] of the ray to each cell
    inside = (x >= SEEN_EDGE) & (x <= MODULE_SIZE - SEEN_EDGE)
    return (slope < np.maximum.accumulate(slope, axis=0) - 1e-9) & inside


def as_scanned(z: np.ndarray, difficulty: float, rng: np.random.Generator) -> np.ndarray:
    """A module's heights ``z`` (610, 610) [m] with the shadow and the dropouts set to NaN.

    ``difficulty`` in [0, 1] sets the number of dropouts (``2 + round(8 d)``);
    their places and sizes are drawn from ``rng``, after whatever the kind's
    generator drew. Returns a new array; ``z`` is not changed.
    """
    x, y = cell_centres()
    out = np.where(shadow(z), np.nan, z)
    n = 2 + int(round(8 * difficulty))
    bx = rng.uniform(SEEN_EDGE + DROPOUT_RAMP, MODULE_SIZE - SEEN_EDGE - DROPOUT_RAMP, n)
    by = rng.uniform(-DROPOUT_REACH, DROPOUT_REACH, n)
    br = rng.uniform(0.008, 0.02, n)  # [m]
    for k in range(n):  # a handful of discs, each vectorised over the module
        out = np.where((x - bx[k]) ** 2 + (y - by[k]) ** 2 <= br[k] ** 2, np.nan, out)
    return out
