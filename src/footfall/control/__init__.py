"""The control architecture of the paper (§IV-B): planners, trajectories, low-level control."""
