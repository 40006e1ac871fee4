"""A physics variant under measurement: MuJoCo options, a height-field spacing, a foot contact.

The walking runs of every experiment use the documented model
(:mod:`footfall.sim.mjcf`); ``footfall bench sim --physics`` compiles models with
other physics while :func:`physics_variant` lasts, to measure what it costs in
fidelity and gives in speed. :data:`VARIANT` is the variant in force, read by
the model's writers (:mod:`footfall.sim.mjcf`, :mod:`footfall.sim.hfield`) and
changed only by :func:`physics_variant`.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Mapping

import mujoco

from footfall.core.errors import FootfallError

PHYSICS_OPTIONS = ("cone", "impratio", "tolerance", "iterations", "ls_iterations", "jacobian",
                   "solver", "noslip_iterations", "timestep")  # <option> attributes a variant may set
VARIANT: dict = {}  # the physics variant in force (physics_variant); empty: the documented model

FOOT_CONTACTS = ("terrain", "pads")  # the ball feet meet the height field, or their pads


@contextlib.contextmanager
def physics_variant(options: Mapping[str, str] | None = None,
                    max_spacing: float | None = None,
                    foot_contact: str = "terrain") -> Iterator[None]:
    """Compile models with other physics while the context lasts: to measure what it costs.

    ``options``: MuJoCo ``<option>`` attributes (of :data:`PHYSICS_OPTIONS`) as
    MJCF text, e.g. ``{"cone": "pyramidal", "impratio": "10"}``;
    ``max_spacing`` [m]: the height field's coarsest vertex spacing in place of
    :data:`~footfall.sim.hfield.MAX_HFIELD_SPACING`; ``foot_contact`` "pads": each
    ball foot meets only its own pad (:mod:`footfall.sim.foot_pads`). For
    ``footfall bench sim --physics``: the walking runs of every experiment use
    the documented model.

    Raises
    ------
    FootfallError
        For an option not in :data:`PHYSICS_OPTIONS`, or a bad spacing.
    """
    options = dict(options or {})
    unknown = sorted(set(options) - set(PHYSICS_OPTIONS))
    if unknown:
        raise FootfallError(f"unknown physics option(s) {', '.join(unknown)}; known: "
                            f"{', '.join(PHYSICS_OPTIONS)}")
    if foot_contact not in FOOT_CONTACTS:
        raise FootfallError(f"unknown foot contact {foot_contact!r}; known: "
                            f"{', '.join(FOOT_CONTACTS)}")
    if max_spacing is not None and not (isinstance(max_spacing, (int, float))
                                        and math.isfinite(max_spacing) and max_spacing > 0):
        raise FootfallError(f"max_spacing must be a number > 0 [m], got {max_spacing!r}")
    attributes = " ".join(f'{k}="{v}"' for k, v in options.items())
    try:  # a value MuJoCo refuses is refused here, in one line
        mujoco.MjModel.from_xml_string(f"<mujoco><option {attributes}/></mujoco>")
    except ValueError as exc:
        raise FootfallError(f"physics options {attributes}: "
                            f"{str(exc).strip().splitlines()[0]}") from None
    saved = dict(VARIANT)
    VARIANT.clear()
    VARIANT.update({"options": {k: str(v) for k, v in options.items()},
                     "max_spacing": max_spacing, "foot_contact": foot_contact})
    try:
        yield
    finally:
        VARIANT.clear()
        VARIANT.update(saved)


def pads_on() -> bool:
    """Whether the physics variant in force gives each ball foot its own pad."""
    return VARIANT.get("foot_contact") == "pads"
