"""Learning a foothold ranking function: the pairwise data set, the rank learners, training with cross-validation, the model file and ranking evaluation."""

# The built-in learners register themselves when their module is imported; importing it here
# makes every registry lookup (footfall.learning.learner.get_learner) see them.
from footfall.learning import boosted as _boosted  # noqa: F401
from footfall.learning import kernel as _kernel  # noqa: F401
from footfall.learning import ranker as _builtin_learners  # noqa: F401
