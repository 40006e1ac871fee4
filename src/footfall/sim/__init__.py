"""The simulated robot: MuJoCo model, terrain and physics (issue 4).

MuJoCo picks its OpenGL backend when it is first imported; footfall renders
offscreen, so EGL is the default here (``MUJOCO_GL`` in the environment wins).
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
