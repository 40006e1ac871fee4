"""The simulated robot: MuJoCo model, terrain and physics (issue 4)."""
