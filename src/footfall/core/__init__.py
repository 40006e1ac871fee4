"""Core types every layer shares: the height map, the robot description, its state and kinematics, errors, files, seeds and small statistics."""
