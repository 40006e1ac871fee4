"""The walking ablation: variants change one thing each, runs are paired, a stopped one resumes."""

import json
from dataclasses import replace

import numpy as np
import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.core.stats import mcnemar_exact
from footfall.data.store import DemoStore
from footfall.experiments.ablation import (
    VARIANTS,
    AblationConfig,
    ablation_markdown,
    register_variant,
    run_ablation,
    summarise_ablation,
)
from footfall.sim.episode import WalkConfig

TINY = AblationConfig(variants=("defaults", "no-tilt-reflex"), who=("hand",),
                      test_board=(("rocky", 0.3),), test_runs=2, calibration_difficulties=(),
                      hard_runs=0, suite_runs=0,
                      walk=replace(AblationConfig().walk, max_steps=6))  # six steps a run


def test_each_variant_changes_only_its_part():
    config = AblationConfig()
    base = config.variant_walk("defaults")
    assert base == config.walk and base.footstep.search_radius == 0.03
    for name, changed in (("no-lift-off-gate", "lift_off_gate"),
                          ("no-touchdown-check", "touchdown_check"),
                          ("no-tilt-reflex", "tilt_reflex")):
        walk = config.variant_walk(name)
        assert getattr(base.reflexes, changed) and not getattr(walk.reflexes, changed)
        assert walk == replace(base, reflexes=replace(base.reflexes, **{changed: False}))
    assert config.variant_walk("with-slip-reflex").reflexes.slip_reflex
    assert not base.reflexes.slip_reflex
    assert config.variant_walk("no-load-control").lowlevel.load_gain == 0 < base.lowlevel.load_gain
    assert config.variant_walk("no-cog-reach").cog.reach is None and base.cog.reach is not None
    anchored = config.variant_walk("with-re-anchoring")
    assert anchored == replace(base, lowlevel=replace(base.lowlevel, anchor_follow_time=0.3))
    assert base.lowlevel.anchor_follow_time is None
    handed = config.variant_walk("no-hand-over")
    assert handed == replace(base, lowlevel=replace(base.lowlevel, hand_over=False))
    assert base.lowlevel.hand_over
    horizontal = config.variant_walk("no-pose-hand-over")
    assert horizontal == replace(base, lowlevel=replace(base.lowlevel, hand_over_height=False,
                                                        hand_over_attitude=False))
    assert base.lowlevel.hand_over_height and base.lowlevel.hand_over_attitude
    shallow = config.variant_walk("no-deep-press")
    assert shallow == replace(base, lowlevel=replace(base.lowlevel, press_depth=0.004))
    assert base.lowlevel.press_depth == 0.015
    unsupported = config.variant_walk("no-support-feedforward")
    assert unsupported == replace(base, lowlevel=replace(base.lowlevel, support_feedforward=0.0))
    assert base.lowlevel.support_feedforward > 0
    rebased = config.variant_walk("with-rebase")
    assert rebased == replace(base, reflexes=replace(base.reflexes, rebase_distance=0.03))
    assert base.reflexes.rebase_distance is None
    checked = config.variant_walk("with-friction-check")
    assert checked == replace(base, footstep=replace(base.footstep, friction_safety=1.5))
    assert base.footstep.friction_safety is None
    margin = config.variant_walk("with-joint-margin")
    assert margin == replace(base, footstep=replace(base.footstep, joint_margin=0.1))
    assert base.footstep.joint_margin is None
    unpressed = config.variant_walk("no-press-to-load")
    assert unpressed == replace(base, lowlevel=replace(base.lowlevel, press_speed=0.0))
    assert base.lowlevel.press_speed == 0.1
    slow = config.variant_walk("with-slow-shift")
    assert slow == replace(base, cog=replace(base.cog, shift_duration=0.3))
    assert base.cog.shift_duration == 0.15
    unclear = config.variant_walk("no-leg-clearance")
    assert unclear == replace(base, footstep=replace(base.footstep, leg_clearance=None))
    assert base.footstep.leg_clearance == 0.005
    unheld = config.variant_walk("no-load-hold")
    assert unheld == replace(base, lowlevel=replace(base.lowlevel, load_hold=0.0))
    assert base.lowlevel.load_hold == 0.2
    none = config.variant_walk("none")
    assert not any(getattr(none.reflexes, r) for r in
                   ("lift_off_gate", "touchdown_check", "tilt_reflex", "slip_reflex"))
    assert none.reflexes.rebase_distance is None
    assert none.lowlevel.load_gain == 0 and none.cog.reach is None
    assert not none.lowlevel.hand_over and none.lowlevel.support_feedforward == 0


def test_an_expert_variant_changes_only_the_expert_of_the_expert_s_runs(tmp_path):
    from footfall.experiments.ablation import ablation_jobs
    from footfall.experiments.variants import ROLL_BACK, VARIANTS
    from footfall.expert.synthetic import walking_expert

    config = AblationConfig(variants=("with-roll-back",), test_runs=1, calibration_runs=0,
                            hard_runs=0, suite_runs=0)
    assert config.variant_walk("with-roll-back") == config.variant_walk("defaults")
    rolled = VARIANTS.get("with-roll-back")
    assert rolled.changes_expert and not VARIANTS.get("defaults").changes_expert
    plain = walking_expert(config.walk.footstep.lead)
    assert plain.roll_back is None
    assert rolled.expert(plain) == replace(plain, roll_back=ROLL_BACK)
    jobs = {j.key: j for j in ablation_jobs(config, {"test": tmp_path / "test.npz"})}
    assert jobs["with-roll-back/expert/test/s5000"].expert == replace(plain, roll_back=ROLL_BACK)
    assert jobs["defaults/expert/test/s5000"].expert == plain
    assert "with-roll-back/hand/test/s5000" not in jobs  # the hand-tuned reward's are the defaults'
    assert "defaults/hand/test/s5000" in jobs


def test_the_default_boards_are_the_issue_s():
    boards = AblationConfig().boards()
    assert boards["test"] == ((("rocky", 0.7), ("steps", 0.7)), 500, 21, 5000)
    hard = {k: v for k, v in boards.items() if k.startswith("hard")}
    assert len(hard) == 4 and sum(v[2] for v in hard.values()) == 64
    assert hard["hard0.85-902"] == ((("rocky", 0.85), ("steps", 0.85)), 902, 16, 0)
    cal = {k: v for k, v in boards.items() if k.startswith("cal")}
    assert len(cal) == 6 and sum(v[2] for v in cal.values()) == 48
    assert cal["cal0.6-801"] == ((("rocky", 0.6), ("steps", 0.6)), 801, 8, 0)
    suite = {k: v for k, v in boards.items() if k.startswith("suite")}
    assert len(suite) == 36 and sum(v[2] for v in suite.values()) == 288
    assert {v[0][0][0] for v in suite.values()} == {"steps", "barrier", "slope", "logs", "rocky",
                                                    "ridges", "pitted", "rockyscan", "pavers"}
    assert suite["suite-barrier-1102"] == ((("barrier", 0.7), ("barrier", 0.7)), 1102, 8, 0)


def test_a_variant_name_is_new_and_has_no_slash():
    for bad in ("defaults", "a/b", ""):
        with pytest.raises(FootfallError):
            register_variant(bad, "x", lambda w: w)
    with pytest.raises(FootfallError, match="variant"):
        AblationConfig(variants=("no-such-thing",))


def _result(ok, cause="stance foot slipped"):
    return ({"success": True, "speed_cm_s": 5.0} if ok else
            {"success": False, "reason": "fall: trunk tilted", "explanation": {"cause": cause}})


def test_the_summary_pairs_runs_by_board_and_seed():
    config = AblationConfig(variants=("defaults", "no-tilt-reflex"), who=("expert",),
                            test_runs=3, calibration_difficulties=(0.5,),
                            calibration_board_seeds=(800,), calibration_runs=2,
                            hard_board_seeds=(900,), hard_runs=3, suite_runs=0)
    base = {"test": [True, True, False], "cal0.5-800": [True, False],
            "hard0.85-900": [False, False, True]}
    other = {"test": [False, True, True], "cal0.5-800": [False, False],
             "hard0.85-900": [True, True, True]}
    results = {}
    for v, outcome in (("defaults", base), ("no-tilt-reflex", other)):
        for board, oks in outcome.items():
            first = 5000 if board == "test" else 0
            for i, ok in enumerate(oks):
                results[f"{v}/expert/{board}/s{first + i}"] = _result(ok)
    summary = summarise_ablation(config, results)
    row = summary["no-tilt-reflex"]["expert"]
    assert row["test"] == {"successes": 2, "runs": 3}
    assert row["calibration"] == {"successes": 0, "runs": 2}
    assert (row["won"], row["lost"]) == (1, 2)  # seed 5002 won; 5000 and cal seed 0 lost
    assert row["p_value"] == pytest.approx(mcnemar_exact(1, 2))
    assert row["causes"] == {"stance foot slipped": 3}
    # the hard boards are counted and paired apart (seeds 0 and 1 won there, none lost)
    assert row["hard"] == {"successes": 3, "runs": 3}
    assert (row["hard_won"], row["hard_lost"]) == (2, 0)
    assert row["hard_p_value"] == pytest.approx(mcnemar_exact(2, 0))
    assert summary["defaults"]["expert"]["won"] == summary["defaults"]["expert"]["lost"] == 0
    table = ablation_markdown(config, summary)
    assert ("| no-tilt-reflex: without the tilt reflex | 2 / 3 | 0 / 2 | +1 / -2 (1) | 3 / 3 "
            "| +2 / -0 (0.5) |") in table


@pytest.fixture(scope="module")
def walked(tmp_path_factory):
    out = tmp_path_factory.mktemp("ablation")
    return out, run_ablation(out, TINY, processes=1, log=lambda s: None)


def test_an_ablation_walks_every_variant_on_the_same_seeds(walked):
    out, summary = walked
    with DemoStore(out / "ablation.sqlite") as store:
        runs = {r["key"]: r for r in store.runs()}
    assert sorted(runs) == [f"{v}/hand/test/s{s}" for v in ("defaults", "no-tilt-reflex")
                            for s in (5000, 5001)]
    for v in ("defaults", "no-tilt-reflex"):  # each walked with its own settings
        settings = runs[f"{v}/hand/test/s5000"]["settings"]
        assert settings["walk"]["reflexes"]["tilt_reflex"] == (v == "defaults")
    assert json.loads((out / "ablation.json").read_text())["variants"] == summary
    assert (out / "ablation.md").read_text().count("| no-tilt-reflex") == 1


def test_an_ablation_resumes_without_walking_again(walked):
    out, summary = walked
    lines = []
    again = run_ablation(out, TINY, processes=1, log=lines.append)
    assert again == summary
    assert lines == ["ablation runs: 4 of 4 runs already stored"]
    with pytest.raises(FootfallError, match="other settings"):
        run_ablation(out, replace(TINY, test_runs=3), processes=1, log=lambda s: None)
    # fewer variants in the same folder: their runs are all stored, nothing is walked
    lines.clear()
    fewer = run_ablation(out, replace(TINY, variants=("defaults",)), processes=1,
                         log=lines.append)
    assert fewer == {"defaults": summary["defaults"]}
    assert lines == ["ablation runs: 2 of 2 runs already stored"]


def test_the_command_refuses_an_unknown_variant(tmp_path, capsys):
    code, _, err = run(capsys, "ablation", "--variant", "no-such", "--out", tmp_path / "a")
    assert_user_error(code, err, "no-such")
    assert not (tmp_path / "a").exists()


def test_the_registry_lists_the_default_variants_first():
    assert list(VARIANTS)[0] == "defaults"
    assert isinstance(AblationConfig().variant_walk("none"), WalkConfig)


def test_no_hard_walks_issue_18_s_boards_only(tmp_path, capsys, monkeypatch):
    import footfall.cli.experiments as commands  # what `footfall ablation` calls

    seen = []

    def fake(out, config, processes=None, log=print, executor=None):
        seen.append(config)
        return {}

    monkeypatch.setattr(commands, "run_ablation", fake)
    monkeypatch.setattr(commands, "ablation_markdown", lambda config, summary: "")
    for flag, hard_runs in (("--no-hard", 0), ("--hard", AblationConfig().hard_runs)):
        code, _, _ = run(capsys, "ablation", flag, "--no-training-suite", "--out", tmp_path / "a")
        assert code == 0
        assert seen[-1].hard_runs == hard_runs and seen[-1].suite_runs == 0
    boards = seen[0].boards()
    assert not any(b.startswith(("hard", "suite")) for b in boards) and len(boards) == 7
    code, _, _ = run(capsys, "ablation", "--out", tmp_path / "a")
    assert code == 0 and seen[-1].suite_runs == AblationConfig().suite_runs > 0


def test_a_seeds_round_moves_every_board_s_first_run_seed_and_nothing_else(tmp_path, capsys,
                                                                          monkeypatch):
    base = AblationConfig()
    assert base.seeds_round(0) is base
    fresh = base.seeds_round(2)
    for name, (spec, board_seed, runs, first) in base.boards().items():
        assert fresh.boards()[name] == (spec, board_seed, runs, first + 2000)
    assert replace(fresh, test_seed=base.test_seed, calibration_seed=base.calibration_seed,
                   hard_seed=base.hard_seed, suite_seed=base.suite_seed) == base
    import footfall.cli.experiments as commands

    seen = []
    monkeypatch.setattr(commands, "run_ablation",
                        lambda out, config, processes=None, log=print, executor=None:
                        seen.append(config) or {})
    monkeypatch.setattr(commands, "ablation_markdown", lambda config, summary: "")
    code, _, _ = run(capsys, "ablation", "--seeds-round", "1", "--out", tmp_path / "a")
    assert code == 0 and seen[-1] == base.seeds_round(1)
    code, _, err = run(capsys, "ablation", "--seeds-round", "-1", "--out", tmp_path / "b")
    assert code == 2 and len(err.strip().splitlines()) == 1


def _rows(hard, suite, cal=(0, 0)):
    """Rows of both choosers with the given (won, lost) on the hard boards, the suite and the
    test and calibration boards."""
    row = {"hard": {"successes": 1, "runs": 1}, "suite": {"successes": 1, "runs": 1}}
    for prefix, (won, lost) in (("hard_", hard), ("suite_", suite), ("", cal)):
        row.update({prefix + "won": won, prefix + "lost": lost,
                    prefix + "p_value": mcnemar_exact(won, lost)})
    return row


def test_the_training_suite_rule_counts_hard_and_suite_runs_and_guards_every_group():
    from footfall.experiments.ablation import training_rule

    even = _rows((3, 5), (6, 4))  # 9 won, 9 lost over both: adopted
    assert training_rule({"expert": even, "hand": even}) is True
    behind = _rows((3, 6), (6, 4))  # 9 won, 10 lost
    assert training_rule({"expert": even, "hand": behind}) is False
    # a large gain on the suite does not buy a significant loss on the hard boards
    sunk = _rows((0, 8), (20, 2))
    assert mcnemar_exact(0, 8) < 0.05
    assert training_rule({"expert": sunk, "hand": even}) is False
    # nor on the test and calibration boards
    assert training_rule({"expert": _rows((4, 0), (4, 0), cal=(0, 7)), "hand": even}) is False
    assert training_rule({"expert": _rows((4, 0), (4, 0), cal=(1, 5)), "hand": even}) is True
    # a chooser or a group not walked: no verdict
    assert training_rule({"expert": even}) is None
    assert training_rule({"expert": even, "hand": {**even, "suite": None}}) is None


def test_the_table_says_what_the_rule_decided():
    config = AblationConfig(variants=("defaults", "no-tilt-reflex"), test_runs=1,
                            calibration_difficulties=(), hard_board_seeds=(900,), hard_runs=2,
                            suite_kinds=("barrier",), suite_board_seeds=(1100,), suite_runs=2)
    results = {}
    for who in ("expert", "hand"):
        for v, oks in (("defaults", (True, False, False, True, False)),
                       ("no-tilt-reflex", (True, True, False, True, True))):
            keys = ["test/s5000", "hard0.85-900/s0", "hard0.85-900/s1", "suite-barrier-1100/s0",
                    "suite-barrier-1100/s1"]
            for key, ok in zip(keys, oks):
                results[f"{v}/{who}/{key}"] = _result(ok)
    summary = summarise_ablation(config, results)
    assert summary["no-tilt-reflex"]["training_rule"] is True
    assert summary["defaults"]["training_rule"] is None
    row = summary["no-tilt-reflex"]["expert"]
    assert row["suite"] == {"successes": 2, "runs": 2}
    assert (row["suite_won"], row["suite_lost"], row["hard_won"]) == (1, 0, 1)
    table = ablation_markdown(config, summary)
    assert "training suite: won / lost (p)" in table and table.count("| adopted |") == 1


def test_the_walking_expert_s_riser_term_costs_a_foot_at_a_riser_s_foot_and_nothing_farther_back():
    """1 value unit a mm of weighted riser above 2 cm; no-riser-ahead walks without it."""
    from footfall.core.heightmap import HeightMap
    from footfall.core.robot import LITTLEDOG
    from footfall.core.state import nominal_state
    from footfall.experiments.variants import VARIANTS
    from footfall.expert.synthetic import (
        WALKER_RISER_FREE,
        WALKER_RISER_WEIGHT,
        SyntheticExpert,
        walking_expert,
    )

    cautious = walking_expert(AblationConfig().walk.footstep.lead)
    assert (cautious.w_riser, cautious.riser_free) == (WALKER_RISER_WEIGHT, WALKER_RISER_FREE)
    without = VARIANTS.get("no-riser-ahead")
    assert without.changes_expert
    assert AblationConfig().variant_walk("no-riser-ahead") == AblationConfig().variant_walk("defaults")
    plain = without.expert(cautious)
    assert plain == replace(cautious, w_riser=0.0)
    # A 71 mm riser across the path at x = 0.4 m; one foothold with its ball centre 20 mm
    # before the face (where the expert without the term stood before a riser), one 45 mm before.
    x = np.arange(0.0, 0.8, 0.001) + 0.0005
    z = np.where(x > 0.4, 0.071, 0.0)[:, None] * np.ones((1, 400))
    board = HeightMap(z, 0.001, (0.0, -0.2))
    state = nominal_state(board, (0.25, 0.0), 0.0, "LH")
    cand = np.array([[0.4 - 0.02, 0.081, 0.0], [0.4 - 0.045, 0.081, 0.0]])
    a, b = SyntheticExpert(plain), SyntheticExpert(cautious)
    rise = b.terms(board, state, cand)["riser_ahead"]
    # the riser's full height lies within 20 mm ahead of the ball centre, weighted at least 1/2
    assert 0.5 * 0.071 <= rise[0] <= 0.071 + LITTLEDOG.foot_radius
    assert rise[1] < WALKER_RISER_FREE  # 35 mm on, weighted 1/8: the lift clears it
    cost = a.values(board, state, cand) - b.values(board, state, cand)
    assert cost[0] == pytest.approx(WALKER_RISER_WEIGHT * (rise[0] - WALKER_RISER_FREE), rel=1e-9)
    assert cost[1] == 0.0
