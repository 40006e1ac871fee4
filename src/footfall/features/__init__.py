"""Candidates and features: the candidate set F, foothold patches, terrain features, templates, pose features, the linear reward and dense scoring."""
