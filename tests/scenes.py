"""Scenes on the robot: a controller whose ``step_phases`` stages one situation, walked once."""

from footfall.control.body_path import BodyPath, terrain_grids
from footfall.control.controller import Controller
from footfall.control.footstep import FootstepConfig, FootstepPlanner
from footfall.core.heightmap import HeightMap
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


def centre_line_planner(hmap: HeightMap, **config) -> FootstepPlanner:
    """The hand-tuned reward's footstep planner along the map's centre line from x = 0.1 to
    0.8 m, F within 3 cm; ``config`` are further :class:`FootstepConfig` fields."""
    reward = default_reward()
    return FootstepPlanner(hmap, lambda leg: reward, BodyPath.straight((0.1, 0.0), (0.8, 0.0)),
                           grids=terrain_grids(hmap, lambda leg: reward),
                           config=FootstepConfig(search_radius=0.03, **config))
