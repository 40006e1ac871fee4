"""What a learning curve measures (:class:`CurveConfig`), written next to its results: the sizes,
draws, feature sets and learners, the boards, the held-out decisions and how they are ranked."""

from __future__ import annotations

from dataclasses import dataclass

from footfall.core.limits import current_limits
from footfall.core.params import Params, above, at_least, param
from footfall.core.seeds import SeedStreams
from footfall.features.family import PAPER_FEATURE_SETS
from footfall.learning.learner import LEARNERS
from footfall.learning.ranker import SELECTIONS
from footfall.learning.train import FOLDS

from .offline import _difficulties, _feature_sets, _kinds

EXTENSIBLE = ("sizes", "draws", "feature_sets", "learners")  # settings a resumed curve may
# change: they say which points to measure, not what a point means (its draw's demonstrations
# are those its store holds)


MIN_SIZE = 10  # [demonstrations] the smallest point: each leg group's learner needs 5 folds,
# and the walker's demonstrations alternate front and hind legs


def _sizes(value: object) -> bool:
    return isinstance(value, tuple) and len(value) > 0 and all(
        isinstance(n, int) and not isinstance(n, bool) and MIN_SIZE <= n <= current_limits().max_count
        for n in value) and list(value) == sorted(set(value))


@dataclass(frozen=True)
class CurveConfig(Params):
    """What a learning curve measures; written next to its results (docs/configuration.md)."""

    sizes: tuple[int, ...] = param((25, 50, 100, 200, 400, 800, 1600), check=_sizes,
                                   must=f"increasing whole numbers from {MIN_SIZE} (5 "
                                        f"cross-validation folds of each leg group) up to "
                                        f"the max_count limit",
                                   doc="demonstrations learned from at each point")
    draws: int = param(3, range=at_least(1), doc="independent draws of training boards and "
                                                 "demonstrations per point")
    feature_sets: tuple[str, ...] = param(
        PAPER_FEATURE_SETS, check=_feature_sets, must="a tuple of feature sets",
        doc="the feature sets learned")
    learners: tuple[str, ...] = param(
        ("l1", "kernel", "lambdarank"), check=lambda v: isinstance(v, tuple) and len(v) > 0
        and all(learner in LEARNERS for learner in v), must="a tuple of registered learners",
        doc="the learners compared")
    train_kinds: tuple[str, ...] = param(("steps", "barrier", "slope", "rocky"), check=_kinds,
                                         must="a non-empty tuple of terrain kinds",
                                         doc="the kinds of every draw's training boards")
    train_difficulties: tuple[float, ...] = param(
        (0.3, 0.6, 0.9), unit="-", check=_difficulties, must="a tuple of numbers in [0, 1]",
        doc="difficulties of the training boards (one board per kind and difficulty)")
    test_difficulties: tuple[float, ...] = param(
        (0.45, 0.75), unit="-", check=_difficulties, must="a tuple of numbers in [0, 1]",
        doc="difficulties of the held-out test boards (the training kinds)")
    test_decisions: int = param(1000, range=at_least(1),
                                doc="held-out decisions every point is measured on")
    library_size: int = param(1000, range=at_least(3),
                              doc="templates in the library before selection")
    library_capped: bool = param(
        False, doc="the library never holds more than library_size templates (more "
                   "demonstrations than a third of it: a uniform random sample of their "
                   "footholds); False: every demonstrated foothold is a template (paper §III-A)")
    bandwidth_rms: float | None = param(
        0.004, unit="m", range=above(0), doc="RBF bandwidth of every scale, as an RMS height "
        "difference, for every point (the reproduction's rounds' value); None: each learner "
        "chooses them by cross-validation at each point (much slower)")
    folds: str = param("demonstration", check=lambda v: v in FOLDS,
                       must=f"one of {', '.join(FOLDS)}",
                       doc="what a cross-validation fold never splits")
    selection: str = param("min", choices=SELECTIONS,
                           doc="where on its path a learner stops: at the smallest CV error "
                               "(the reproduction's, paper §V) or the simplest within one "
                               "standard error of it")
    template_budget: float | None = param(
        None, unit="-", range=above(0),
        doc="a leg group's function reads at most this share of its demonstrations' number "
            "of templates; None: no budget")
    search_radius: float | None = param(
        None, unit="m", range=above(0),
        doc="the decisions' F, trained on and held out: the reachable footholds within this of "
            "the gait-nominal foothold, as the walking planner's F (the reproduction's walk: "
            "0.03); None: every reachable foothold")
    path_bias: float | None = param(
        None, unit="reward/m", range=at_least(0),
        doc="rank every scorer as the footstep planner picks: its values less this path bias "
            "per metre from the gait-nominal foothold, scaled to its spread (the reproduction's "
            "walk: 60; the expert carries its own); None: each scorer alone")
    seed: int = param(0, range=at_least(0), doc="the curve's seed: boards, demonstrations and "
                                                "learning draw from its named streams")

    @classmethod
    def quick(cls, seed: int = 0) -> CurveConfig:
        """A small curve for a smoke test: two sizes, two draws, small boards' worth."""
        return cls(sizes=(16, 32), draws=2, feature_sets=("terrain", "templates"),
                   learners=("l1", "lambdarank"), train_kinds=("rocky", "steps"),
                   train_difficulties=(0.6,), test_difficulties=(0.6,), test_decisions=30,
                   library_size=60, seed=seed)

    @property
    def streams(self) -> SeedStreams:
        """The curve's named seed streams."""
        return SeedStreams("learning curve", self.seed)

    def training_boards(self, draw: int) -> list[tuple[str, float, int]]:
        """(kind, difficulty, seed) of draw ``draw``'s training boards: a stream of their own."""
        return [(k, d, self.streams.seed_for("boards", 0, draw, i, j))
                for i, k in enumerate(self.train_kinds)
                for j, d in enumerate(self.train_difficulties)]

    def test_boards(self) -> list[tuple[str, float, int]]:
        """(kind, difficulty, seed) of the held-out test boards, the same for every draw."""
        return [(k, d, self.streams.seed_for("boards", 1, i, j))
                for i, k in enumerate(self.train_kinds)
                for j, d in enumerate(self.test_difficulties)]
