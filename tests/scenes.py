"""Scenes on the robot: a Walk subclass whose ``_step`` stages one situation, run once."""

from footfall.features.reward import default_reward
from footfall.sim.episode import Walk, WalkConfig
from maps import short_flat_board


def staged(walk_class: type[Walk], **settings) -> Walk:
    """Run ``walk_class`` once on the short flat board (hand-tuned reward, seed 1), standing 0.2 m
    into the board, for one step (its ``_step``: the scene); ``settings`` are further
    :class:`WalkConfig` fields. Returns the walk, its run log in ``.record``."""
    config = WalkConfig(start_setback=0.2, max_steps=1, **settings)
    run = walk_class(short_flat_board(), lambda leg: default_reward(), 1, config)
    run.record = run.run()
    return run
