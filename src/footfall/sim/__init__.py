"""The simulated robot: the MuJoCo model of the robot on the terrain, its physics, and a
walking episode that runs the control stack on it."""
