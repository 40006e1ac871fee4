"""Scenes on the robot: a controller whose ``step_phases`` stages one situation, walked once."""

from footfall.control.controller import Controller
from footfall.features.reward import default_reward
from footfall.sim.episode import Walk, WalkConfig
from maps import short_flat_board


def staged(controller_class: type[Controller], **settings) -> Walk:
    """Walk ``controller_class`` once on the short flat board (hand-tuned reward, seed 1),
    standing 0.2 m into the board, for one step (its ``step_phases``: the scene); ``settings``
    are further :class:`WalkConfig` fields. Returns the walk: its controller in
    ``.controller``, its run log in ``.record``, its simulation (as the scene left it) in
    ``.sim``."""
    config = WalkConfig(start_setback=0.2, max_steps=1, **settings)
    scene = type(f"Staged{controller_class.__name__}", (Walk,),
                 {"controller_class": controller_class})
    run = scene(short_flat_board(), lambda leg: default_reward(), 1, config)
    run.record = run.run()
    return run
