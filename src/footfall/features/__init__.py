"""Candidates and features: the candidate set F, foothold patches, terrain features, templates, pose features, the scorer interface, the linear reward and dense scoring."""

# The built-in feature families and the hand-tuned reward register themselves when their modules
# are imported: importing any part of footfall.features makes them known to their registries
# (footfall.features.family, footfall.features.scorer).
from footfall.features import pose_features, reward, templates, terrain_features  # noqa: F401
