"""The rollout teacher's first runs (docs/learning/teacher.md, "Trying the footholds it
avoids"): the hand-tuned reward and the rollout teacher over it (RolloutConfig's starting
values, the synthetic expert's best tried too) on one rocky board, the same run seeds.
A lab script, not part of footfall's interface.

python rollout_first_runs.py [SEEDS...]
"""
import sys
import time

from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.features.reward import default_reward
from footfall.sim.episode import WalkConfig, walk
from footfall.sim.rollout import RolloutConfig, RolloutWalk
from footfall.terrain import make_board, parse_board_spec


def main():
    seeds = [int(s) for s in sys.argv[1:]] or [1, 2]
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    reward = default_reward()
    for seed in seeds:
        hand = walk(hmap, lambda leg: reward, seed, WalkConfig())
        t0 = time.perf_counter()
        taught = RolloutWalk(hmap, lambda leg: reward, seed, WalkConfig(), rollout=RolloutConfig(),
                             expert=SyntheticExpert(ExpertConfig()))
        rec = taught.run()
        changed = sum(v.best != v.base for v in taught.verdicts)
        print(f"seed {seed}: hand-tuned {hand.result['reason']} ({len(hand.steps)} steps, slip "
              f"{hand.result['slip_mean_mm']:.1f} mm) | rollout {rec.result['reason']} "
              f"({len(rec.steps)} steps, slip {rec.result['slip_mean_mm']:.1f} mm), "
              f"{changed} of {len(taught.verdicts)} decisions changed, "
              f"{time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
