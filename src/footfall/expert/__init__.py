"""The synthetic expert: its judgement of footholds, its corrections of run logs and the kinematic walker that collects its demonstrations."""

# The expert's value registers itself as the scorer "expert" (footfall.features.scorer.SCORERS)
# when its module is imported: importing any part of footfall.expert makes it known.
from footfall.expert import scorer  # noqa: F401
