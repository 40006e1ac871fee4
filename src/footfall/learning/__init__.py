"""Learning a foothold ranking function: the pairwise data set, the rank learners, training with cross-validation, the model file and ranking evaluation."""
