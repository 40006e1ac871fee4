"""The simulated robot: the MuJoCo model of the robot on the terrain, its physics and senses,
the walking task that referees a run and keeps its log, and the episode that steps the
simulator, the controller and the task together."""
