"""footfall: learning where a legged robot should put its feet, with terrain templates.

The packages follow the pipeline, lowest layer first: ``core`` (height map,
robot, state, kinematics, files, seeds), ``terrain``, ``features``, ``data``,
``learning``, ``expert``, ``control``, ``sim``, ``plots``, ``experiments`` and
``cli``; a layer imports only from the layers below it
(``docs/architecture.md``).
"""

import os

__version__ = "0.1.0"

# MuJoCo picks its OpenGL backend when it is first imported, and footfall renders offscreen:
# EGL unless the caller chose otherwise. Set here, the one place every footfall import passes,
# so that no module has to import the simulator first just for this.
os.environ.setdefault("MUJOCO_GL", "egl")
