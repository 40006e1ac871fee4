"""Controller variants: the default walk with one change, by name.

A variant is the default :class:`~footfall.sim.episode.WalkConfig` with one
part switched off, or a part that is off by default switched on -- or the
walking expert (:func:`footfall.expert.synthetic.walking_expert`) that chooses
the expert's runs with one change of its judgement. The
ablation (:mod:`footfall.experiments.ablation`) walks them paired against
the defaults on the training boards; a terrain suite
(:mod:`footfall.experiments.terrain_suite`) walks one on its kinds.
:data:`VARIANTS` is a registry: a new part of the controller adds its variant
with :func:`register_variant`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from footfall.core.errors import FootfallError
from footfall.core.registry import Registry
from footfall.expert.synthetic import ExpertConfig
from footfall.sim.episode import WalkConfig


def _same_expert(config: ExpertConfig) -> ExpertConfig:
    return config


@dataclass(frozen=True)
class Variant:
    """A controller variant: the default walk with one change, or the walking expert with one."""

    name: str  # the key in VARIANTS and in run keys (no "/")
    description: str  # one line, for the table
    change: Callable[[WalkConfig], WalkConfig]  # the default walk -> this variant's walk
    expert: Callable[[ExpertConfig], ExpertConfig] = _same_expert
    # the walking expert of the walk -> the expert choosing this variant's expert runs

    @property
    def changes_expert(self) -> bool:
        """Whether the variant changes the expert's judgement (not only the walk)."""
        return self.expert is not _same_expert


VARIANTS: Registry[Variant] = Registry("controller variant")
"""The controller variants by name: the defaults, each part switched off, the parts off by default
switched on."""


def register_variant(name: str, description: str,
                     change: Callable[[WalkConfig], WalkConfig],
                     expert: Callable[[ExpertConfig], ExpertConfig] | None = None) -> Variant:
    """Add a controller variant to :data:`VARIANTS` (a new part of the controller adds its own);
    ``expert`` changes the walking expert that chooses the expert's runs [default: none]."""
    if not name or "/" in name:
        raise FootfallError(f"a variant needs a new name without '/', got {name!r}")
    try:
        return VARIANTS.register(name, Variant(name, description, change,
                                               expert or _same_expert))
    except ValueError:  # the name is taken
        raise FootfallError(f"a variant needs a new name without '/', got {name!r}") from None


ROLL_BACK = 0.001  # [m] with-roll-back: a placement error seated higher than this above the
# aim slides back to it (texture on flat ground moves a seat by a few tenths of a mm; 1 mm over
# the walking expert's 7 mm placement error is ground falling back at 8 deg on average)


ROLL_BACK_WALL = 1.0  # [-] with-flank-roll-back: ground rising faster than 1 : 1 (45 deg on
# average) from the aim to a placement is a wall (a riser, a bar, a rock's side): the ball lands
# on its edge or top, it does not slide back (round 4: every choice the roll-back changed on the
# steps and barrier boards stood at a wall's foot, 19-63 mm below the placement 7 mm ahead)


def _reflexes(walk: WalkConfig, **switches) -> WalkConfig:
    return replace(walk, reflexes=replace(walk.reflexes, **switches))


def _lowlevel(walk: WalkConfig, **settings) -> WalkConfig:
    return replace(walk, lowlevel=replace(walk.lowlevel, **settings))


def _no_reach(walk: WalkConfig) -> WalkConfig:
    return replace(walk, cog=replace(walk.cog, reach=None))


BUILTIN_VARIANTS = tuple(variant.name for variant in (
    register_variant("defaults", "the default controller", lambda w: w),
    register_variant("no-lift-off-gate", "without the lift-off gate",
                     lambda w: _reflexes(w, lift_off_gate=False)),
    register_variant("no-touchdown-check", "without the touch-down check",
                     lambda w: _reflexes(w, touchdown_check=False)),
    register_variant("no-tilt-reflex", "without the tilt reflex",
                     lambda w: _reflexes(w, tilt_reflex=False)),
    register_variant("no-load-control", "without the stance load control",
                     lambda w: _lowlevel(w, load_gain=0.0)),
    register_variant("no-load-hold", "without the load control's offsets held while a foot "
                     "set down less than 0.2 s ago settles", lambda w: _lowlevel(w, load_hold=0.0)),
    register_variant("no-press-to-load", "without a foot just set down pressed down while it "
                     "reads under half its part of the weight", lambda w: _lowlevel(w, press_speed=0.0)),
    register_variant("no-deep-press", "with a new foot pressed down to at most 4 mm below "
                     "where it touched down instead of 15 mm", lambda w: _lowlevel(w, press_depth=0.004)),
    register_variant("no-leg-clearance", "without footholds dropped from F where the swing "
                     "leg's knee or shin comes within 5 mm of the terrain at touch-down or a "
                     "stride on", lambda w: replace(w, footstep=replace(w.footstep,
                                                                        leg_clearance=None))),
    register_variant("no-seen-footing", "without footholds dropped within 17 mm (the ball's "
                     "radius and the expert's placement error) of a place where the ball has no "
                     "map data under it, a hole in a scan wider than the ball",
                     lambda w: replace(w, footstep=replace(w.footstep, seen_footing=None))),
    register_variant("no-cog-reach", "without the COG plan within the legs' reach", _no_reach),
    register_variant("no-hand-over", "without the body correction handed to the stance anchors "
                     "at each touch-down", lambda w: _lowlevel(w, hand_over=False)),
    register_variant("no-pose-hand-over", "with only the horizontal body correction handed to "
                     "the stance anchors at each touch-down, not its height, roll and pitch",
                     lambda w: _lowlevel(w, hand_over_height=False, hand_over_attitude=False)),
    register_variant("no-support-feedforward", "without the support torques fed forward",
                     lambda w: _lowlevel(w, support_feedforward=0.0)),
    register_variant("none", "no reflexes, no load control, no reach, no hand-over, no support "
                     "torques (the controller before the reflexes)",
                     lambda w: _no_reach(_lowlevel(_reflexes(
                         w, lift_off_gate=False, touchdown_check=False, tilt_reflex=False,
                         slip_reflex=False, rebase_distance=None),
                         load_gain=0.0, hand_over=False, support_feedforward=0.0))),
    register_variant("with-slip-reflex", "with the stance slip reflex (off by default)",
                     lambda w: _reflexes(w, slip_reflex=True)),
    register_variant("with-re-anchoring", "with slipped stance feet re-anchored where they "
                     "stand (0.3 s; off by default)",
                     lambda w: _lowlevel(w, anchor_follow_time=0.3)),
    register_variant("with-rebase", "with the stance re-based after a recovery that leaves the "
                     "body more than 30 mm off (off by default)",
                     lambda w: _reflexes(w, rebase_distance=0.03)),
    register_variant("with-friction-check", "with footholds dropped where a ball foot's "
                     "contact tilts past atan(friction / 1.5) within 5 mm (off by default)",
                     lambda w: replace(w, footstep=replace(w.footstep, friction_safety=1.5))),
    register_variant("with-joint-margin", "with footholds dropped where the swing leg comes "
                     "within 0.1 rad of a joint limit at touch-down or a stride on (off by "
                     "default)",
                     lambda w: replace(w, footstep=replace(w.footstep, joint_margin=0.1))),
    register_variant("with-slow-shift", "with the body's shift between swings taking 0.3 s "
                     "instead of 0.15 s (off by default)",
                     lambda w: replace(w, cog=replace(w.cog, shift_duration=0.3))),
    register_variant("with-roll-back", "with the expert counting no placement error that seats "
                     "the ball more than 1 mm above its aim: the ball slides back (off by "
                     "default)", lambda w: w, lambda e: replace(e, roll_back=ROLL_BACK)),
    register_variant("no-riser-ahead", "without the expert's riser term (a foothold whose "
                     "swing must climb a riser within 4 cm ahead losing 1 value unit a mm of "
                     "nearer-weighted rise above 2 cm)", lambda w: w,
                     lambda e: replace(e, w_riser=0.0)),
    register_variant("no-crown", "without the expert's crown term (a foothold standing more "
                     "than 2 mm above the ball-centre surface 2 cm around it losing 8 value units "
                     "a mm)", lambda w: w, lambda e: replace(e, w_crown=0.0)),
    register_variant("with-flank-roll-back", "with-roll-back, but a placement seated higher "
                     "above the aim than the placement error itself (45 deg on average: a wall) "
                     "counts (off by default)", lambda w: w,
                     lambda e: replace(e, roll_back=ROLL_BACK, roll_back_wall=ROLL_BACK_WALL)),
))  # the controller's own variants, in table order: an ablation walks them all by default
