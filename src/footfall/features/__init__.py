"""Candidates and features: the candidate set F, foothold patches, terrain features, templates, pose features, the linear reward and dense scoring."""

# The built-in feature families register themselves when their modules are imported: importing
# any part of footfall.features makes them known to the registry (footfall.features.family).
from footfall.features import pose_features, templates, terrain_features  # noqa: F401
