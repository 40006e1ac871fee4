"""The control architecture of the paper (§IV-B) -- planners, trajectories, low-level control --
and the walking controller that runs it on the robot: measurements in, joint targets out."""
