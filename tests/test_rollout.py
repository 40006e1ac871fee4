"""The rollout teacher (footfall.sim.rollout): candidates tried in branches of a run, what
followed each valued, the best taught -- on a run that falls where other footholds walk on."""

from dataclasses import replace

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
from footfall.features.reward import default_reward
from footfall.sim.branch import TapedWalk
from footfall.sim.episode import WalkConfig
from footfall.sim.rollout import RolloutConfig, RolloutWalk, branch_variations, rollout_verdict
from footfall.terrain import make_board, parse_board_spec


@pytest.fixture(scope="module")
def taped():
    """The hand-tuned reward on a rough board: its last decisions lead to a fall."""
    reward = default_reward()
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    walk = TapedWalk(hmap, lambda leg: reward, 1, WalkConfig())
    record = walk.run()
    assert record.result["reason"].startswith("fall")
    return walk


def test_where_the_base_choice_falls_the_teacher_teaches_one_that_walks_on(taped):
    config = RolloutConfig()
    verdict = rollout_verdict(taped, 13, config, SyntheticExpert(ExpertConfig()))
    assert verdict.base == taped.tape.decisions[13].plan.index == verdict.tried[0]
    m = verdict.tried.size
    assert config.candidates <= m <= config.candidates + 1  # the expert's best, if not tried
    assert len(verdict.outcomes) == m * config.branches
    assert [o.candidate for o in verdict.outcomes] == np.repeat(verdict.tried, 2).tolist()
    base = [o for o in verdict.outcomes if o.candidate == verdict.base]
    taught = [o for o in verdict.outcomes if o.candidate == verdict.best]
    assert any(o.fell for o in base) and not any(o.fell or o.failed for o in taught)
    assert verdict.best != verdict.base
    np.testing.assert_allclose(verdict.values[list(verdict.tried).index(verdict.best)],
                               np.mean([o.value for o in taught]))
    assert {o.describe() for o in base} & {"fell"}


def test_where_every_candidate_falls_the_base_choice_stands(taped):
    last = len(taped.tape.decisions) - 1
    verdict = rollout_verdict(taped, last, RolloutConfig(candidates=2, branches=1))
    assert all(o.fell for o in verdict.outcomes)
    assert verdict.best == verdict.base


def test_the_verdict_is_the_same_for_the_same_run_and_its_branches_share_their_luck(taped):
    config = RolloutConfig(candidates=2, branches=2, horizon=1)
    a, b = rollout_verdict(taped, 5, config), rollout_verdict(taped, 5, config)
    np.testing.assert_array_equal(a.values, b.values)
    assert a.outcomes == b.outcomes
    # the same variations for every candidate at a decision, new ones at the next
    assert branch_variations(config, 1, 5) == branch_variations(config, 1, 5)
    assert branch_variations(config, 1, 5) != branch_variations(config, 1, 6)
    assert len({v.noise_seed for v in branch_variations(config, 1, 5)}) == 2
    with pytest.raises(FootfallError, match="no decision"):
        rollout_verdict(taped, len(taped.tape.decisions), config)


def test_a_walk_the_rollout_teacher_chooses_takes_what_it_teaches():
    reward = default_reward()
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    config = RolloutConfig(candidates=2, branches=1, horizon=1, margin=0.0)
    walk = RolloutWalk(hmap, lambda leg: reward, 1, WalkConfig(max_steps=6), rollout=config)
    record = walk.run()
    assert len(walk.verdicts) == len(walk.tape.decisions) >= len(record.steps) == 6
    taught = [v.best for v in walk.verdicts]
    assert [s.chosen for s in record.steps] == taught[:len(record.steps)]
    assert [d.plan.index for d in walk.tape.decisions] == taught  # the tape keeps what was taken
    assert any(v.best != v.base for v in walk.verdicts)  # at margin 0 progress alone decides
    assert record.settings["teacher"]["rollout"]["candidates"] == 2


def test_the_rollout_teacher_walks_where_any_teacher_walks_and_refuses_to_label(tmp_path):
    from footfall.experiments.runs import RunJob, execute
    from footfall.expert.synthetic import walking_expert
    from footfall.expert.teachers import TEACHERS

    board = make_board([parse_board_spec("rocky:0.7")], seed=3)
    board.save(tmp_path / "board.npz")
    config = WalkConfig(max_steps=2)
    settings = walking_expert(config.footstep.lead)
    record, demos = execute(RunJob(None, str(tmp_path / "board.npz"), None, 0, config,
                                   expert=settings, judge=True, teacher="rollout"))
    assert len(record.steps) == 2 and demos == []
    assert record.settings["teacher"] == {"rollout": RolloutConfig().to_dict(),
                                          "expert_best": True}
    walker = TEACHERS.get("rollout").walker(settings, 60.0, 0.01)
    assert walker.rollout and walker.reward is not None  # over the accepted teacher
    with pytest.raises(FootfallError, match="not a state alone"):
        TEACHERS.get("rollout").expert(settings, 60.0, 0.01)


def test_branches_forked_at_the_decision_answer_as_the_replayed_ones():
    """The rollout walk tries its candidates in forked copies of the run at each decision;
    afterwards the same tries by replay (TapedWalk.branch) give the same outcomes, bit for bit."""
    reward = default_reward()
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    config = RolloutConfig(candidates=2, branches=2, horizon=2)
    walk = RolloutWalk(hmap, lambda leg: reward, 1, WalkConfig(max_steps=5), rollout=config)
    walk.branch_processes = 2
    walk.run()
    kept = [v for v in walk.verdicts if v.best == v.base]  # their tape keeps the base's plan
    assert kept
    for live in kept:
        again = rollout_verdict(walk, live.decision, config)
        assert again.outcomes == live.outcomes
        np.testing.assert_array_equal(again.values, live.values)


def test_the_rollout_teacher_labels_the_runs_own_states_as_it_goes(tmp_path):
    """A correcting run job with the rollout teacher: the run walks with its own choices, the
    teacher's verdict at every decision becomes a demonstration -- its choice the best tried,
    the tried candidates that went clearly worse refused."""
    from footfall.experiments.runs import RunJob, execute
    from footfall.expert.synthetic import walking_expert

    board = make_board([parse_board_spec("rocky:1.0")], seed=3)
    board.save(tmp_path / "board.npz")
    config = WalkConfig(max_steps=4)
    settings = walking_expert(config.footstep.lead)
    job = RunJob("r0", str(tmp_path / "board.npz"), None, 1, config, correct=True,
                 expert=settings, teacher="rollout", every_step=True)
    record, demos = execute(job)
    plain = execute(RunJob("r0", str(tmp_path / "board.npz"), None, 1, config))[0]
    assert [s.chosen for s in record.steps] == [s.chosen for s in plain.steps]  # its own choices
    assert [d.source for d in demos] == [f"run:r0:step:{k}" for k in range(4)]
    for d, step in zip(demos, record.steps):
        np.testing.assert_array_equal(d.candidates, step.candidates)
        assert d.values is None and not d.refused[d.chosen]
        assert d.expert["class"].endswith("RolloutVerdict")
    # policy iteration: the rollout over the walking function itself, its choice the base
    small = RolloutConfig(candidates=2, branches=1, horizon=1, base="walker")
    _, demos = execute(replace(job, rollout=small))
    assert [d.expert["verdict"]["base"] for d in demos] == [s.chosen for s in record.steps]
    assert all(d.refused[d.expert["verdict"]["tried"]].sum() == d.refused.sum() for d in demos)


def test_rollout_labels_refuse_what_went_worse_and_a_cap_keeps_the_largest_gains():
    from footfall.sim.rollout import refused_of, verdict_demonstrations

    reward = default_reward()
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    config = RolloutConfig(candidates=3, branches=1, horizon=1, margin=0.0, refuse=0.0)
    walk = RolloutWalk(hmap, lambda leg: reward, 1, WalkConfig(max_steps=6), rollout=config,
                       take=False)
    record = walk.run()
    every = verdict_demonstrations(walk, record, "r", every_step=True)
    changed = verdict_demonstrations(walk, record, "r", every_step=False)
    assert len(every) == 6 and 0 < len(changed) < 6  # at margin 0 progress alone decides
    for d, v in zip(every, walk.verdicts):
        assert d.chosen == v.best
        assert set(np.flatnonzero(d.refused)) == set(v.tried[refused_of(v, 0.0)])
    assert any(d.refused.any() for d in every)
    gains = {d.source: v.values.max() - v.values[0] for d, v in zip(every, walk.verdicts)}
    capped = verdict_demonstrations(walk, record, "r", every_step=False, cap=1)
    assert len(capped) == 1
    assert gains[capped[0].source] == max(gains[d.source] for d in changed)


def test_a_base_other_than_the_walk_ranks_the_tries_and_continues_the_branches():
    """Labelling a run another function walks (a student's), the teacher improves on its own
    base: the base's plan of each state gives the candidates tried and the tie, the base
    chooses in every branch (forked and replayed alike), and the run keeps its own choices.
    Untried candidates are refused as the base teacher's face refuses them; tried ones by
    their branches alone."""
    from footfall.control.footstep import FootstepPlanner
    from footfall.expert.protocol import kept_verdict, teacher_verdict
    from footfall.expert.synthetic import walking_expert
    from footfall.expert.teachers import TEACHERS, state_judge
    from footfall.sim.rollout import refused_of, verdict_demonstrations
    from test_bad_models import make_model

    student = make_model()  # a function of random weights walks; the accepted teacher labels
    hmap = make_board([parse_board_spec("rocky:1.0")], seed=3)
    walk_config = WalkConfig(max_steps=10)  # the first steps are on the flat approach
    lead = walk_config.footstep.lead
    settings = walking_expert(lead)
    base = TEACHERS.get("accepted").walker(settings, walk_config.footstep.bias_weight,
                                           lead).reward
    config = RolloutConfig(candidates=2, branches=1, horizon=1, margin=0.0, refuse=0.0)
    walk = RolloutWalk(hmap, student.reward_for, 1, walk_config, rollout=config,
                       expert=SyntheticExpert(settings), take=False, base=lambda leg: base)
    walk.branch_processes = 2
    record = walk.run()
    plain = TapedWalk(hmap, student.reward_for, 1, walk_config).run()
    assert [s.chosen for s in record.steps] == [s.chosen for s in plain.steps]
    own = walk.own_planner
    planner = FootstepPlanner(hmap, lambda leg: base, own.path, walk.robot, own.config)
    differs = 0
    for v in walk.verdicts:
        decision = walk.tape.decisions[v.decision]
        base_plan = planner.plan(decision.state)
        assert v.base == base_plan.index == v.tried[0]
        if base_plan.index != decision.plan.index:  # the base is another chooser here
            differs += 1
            again = rollout_verdict(walk, v.decision, config, SyntheticExpert(settings),
                                    base_plan=base_plan)  # replayed: the same answers
            assert again.outcomes == v.outcomes
    assert differs
    judge = state_judge("rollout", settings, walk_config.footstep.bias_weight, lead)
    assert type(judge) is type(TEACHERS.get("accepted").expert(
        settings, walk_config.footstep.bias_weight, lead))
    last = {len(walk.tape.decisions[v.decision].task.steps): v for v in walk.verdicts}
    demos = verdict_demonstrations(walk, record, "r", untried=judge)
    assert len(demos) == len(record.steps)
    for d in demos:
        step = record.steps[int(d.source.rsplit(":", 1)[1])]
        v = last[step.k]  # a step planned again is labelled at its last decision
        values, refused, judged = teacher_verdict(judge, hmap, step.state, step.candidates)
        expected = kept_verdict(values, refused, judged, v.best)[1].copy()
        expected[v.tried] = False
        expected[v.tried[refused_of(v, 0.0)]] = True
        np.testing.assert_array_equal(d.refused, expected)
        assert d.chosen == v.best and not d.refused[d.chosen]
