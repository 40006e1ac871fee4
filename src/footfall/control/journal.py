"""What the controller tells whoever records its run, as it happens.

The controller plans and takes steps and its reflexes act; a recorder (the
walking task, :mod:`footfall.sim.task`) keeps the run log from these notes,
reading the positions it logs from its own source of truth. Every note
carries the time [s] of the control period in which it happened.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from footfall.control.footstep import FootstepPlan


@dataclass(frozen=True)
class Settled:
    """The robot has stood still its settle time; its first step is planned next."""

    time: float  # [s]


@dataclass(frozen=True, eq=False)
class StepPlanned:
    """Step ``k`` is planned: its foothold, candidates and the COG plan's least margin."""

    time: float  # [s]
    k: int  # step number, from 0
    plan: FootstepPlan
    margin: float  # [m] the planned centre of mass's least margin inside the swing triangle
    seconds: float  # [s] of wall-clock time the planning took (not simulated time)


@dataclass(frozen=True)
class StepCalledOff:
    """Step ``k`` was called off before its foot lifted: it will be planned anew."""

    time: float  # [s]
    k: int


@dataclass(frozen=True)
class LiftOff:
    """The foot of leg ``leg`` (a LEG_NAMES index) lifts for step ``k``."""

    time: float  # [s]
    k: int
    leg: int


@dataclass(frozen=True)
class TouchDown:
    """The foot of leg ``leg`` stands for step ``k`` (after any re-placement) and takes load."""

    time: float  # [s]
    k: int
    leg: int


@dataclass(frozen=True)
class ReflexEvent:
    """A reflex acted: ``kind`` (e.g. "tilt", "touch-down re-placed"), on ``leg`` or the body."""

    time: float  # [s]
    kind: str
    leg: int | None  # a LEG_NAMES index, None: the whole body
    details: dict = field(default_factory=dict)  # numbers in the units their names give


Note = Settled | StepPlanned | StepCalledOff | LiftOff | TouchDown | ReflexEvent
