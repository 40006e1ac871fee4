"""footfall: learning where a legged robot should put its feet, with terrain templates."""

__version__ = "0.1.0"
