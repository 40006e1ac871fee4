"""Walking runs: the low-level control pieces, the slip measure, a short seeded walk, the CLI."""

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cli_helpers import assert_user_error, run
from footfall.control.lowlevel import (
    BodyCorrection,
    LowLevelConfig,
    body_rotation,
    joint_targets,
    rolled,
    shin_rotations,
    transfer_weight,
)
from footfall.core.errors import FootfallError
from footfall.core.kinematics import (
    body_to_world,
    forward_kinematics,
    inverse_kinematics,
    knee_position,
    rotation_matrix,
)
from footfall.core.robot import LITTLEDOG, RobotDescription
from footfall.features.config import FeatureConfig
from footfall.features.reward import default_reward
from footfall.features.terrain_features import TerrainFeatures
from footfall.learning.function import LinearFunction
from footfall.learning.model import FootholdModel
from footfall.sim.episode import WALL_CLOCK_FIELDS, WalkConfig, foot_slip, walk
from maps import short_flat_board

R = LITTLEDOG


# ------------------------------------------------------------------ slip
def test_foot_slip_is_the_centre_travel_from_touchdown_to_liftoff():
    down = np.array([[0.30, 0.08, 0.010], [0.50, -0.08, 0.010]])
    up = np.array([[0.303, 0.084, 0.010], [0.50, -0.08, 0.022]])  # 3-4-5 slide; 12 mm lift
    np.testing.assert_allclose(foot_slip(down, up), [0.005, 0.012])
    assert foot_slip(down[0], down[0]) == 0.0
    with pytest.raises(FootfallError, match=r"positions \(\.\.\., 3\)"):
        foot_slip(np.zeros(2), np.zeros(2))


# ------------------------------------------------------------- low level
def test_transfer_weight_rises_smoothly_from_zero_to_one():
    w = transfer_weight(np.array([-1.0, 0.0, 0.025, 0.05, 1.0, np.inf]), 0.05)
    np.testing.assert_allclose(w, [0.0, 0.0, 0.5, 1.0, 1.0, 1.0])
    assert np.all(transfer_weight(np.array([0.0, 3.0]), 0.0) == 1.0)  # no transfer time: at once


def test_joint_targets_blend_the_commanded_and_measured_body_frames():
    q0 = np.array([[0.0, -0.6, 1.2], [0.0, -0.6, 1.2], [0.0, 0.6, -1.2], [0.0, 0.6, -1.2]])
    rpy = np.array([0.02, -0.03, 0.4])
    measured = (np.array([0.1, 0.0, 0.14]), body_rotation(rpy))
    feet = np.array([body_to_world(forward_kinematics(leg, q0[k], R), measured[0], rpy)
                     for k, leg in enumerate(R.legs)])
    up = measured[1] @ [0.0, 0.0, 0.01]  # 1 cm along the body's z axis
    commanded = (measured[0] + up, measured[1])
    # Weight 0: the measured frame, in which the feet are exactly where q0 puts them.
    q, ok = joint_targets(R, feet, commanded, measured, np.zeros(4), np.zeros((4, 3)))
    np.testing.assert_allclose(q, q0, atol=1e-9)
    assert ok.all()
    # Weight 1: solved for the body 1 cm higher -- every foot 1 cm lower in the body frame.
    q1, _ = joint_targets(R, feet, commanded, measured, np.ones(4), np.zeros((4, 3)))
    for k, leg in enumerate(R.legs):
        np.testing.assert_allclose(forward_kinematics(leg, q1[k], R),
                                   forward_kinematics(leg, q0[k], R) - [0, 0, 0.01], atol=1e-9)
    # Half way: half way in between.
    qh, _ = joint_targets(R, feet, commanded, measured, np.full(4, 0.5), np.zeros((4, 3)))
    for k, leg in enumerate(R.legs):
        np.testing.assert_allclose(forward_kinematics(leg, qh[k], R),
                                   forward_kinematics(leg, q0[k], R) - [0, 0, 0.005], atol=1e-9)


def test_joint_targets_agree_with_each_legs_own_inverse_kinematics():
    rng = np.random.default_rng(3)
    pose = (np.zeros(3), np.eye(3))
    for _ in range(50):  # random reachable and unreachable targets around every hip
        local = np.array([np.array(leg.hip) + [rng.uniform(-0.1, 0.1),
                                               leg.side * rng.uniform(-0.02, 0.12),
                                               -rng.uniform(0.0, 0.2)] for leg in R.legs])
        q, ok = joint_targets(R, local, pose, pose, np.ones(4), np.full((4, 3), 9.0))
        for k, leg in enumerate(R.legs):
            qk, okk = inverse_kinematics(leg, local[k], R)
            assert ok[k] == okk
            expect = np.clip(qk, *np.array(leg.limits).T) if np.isfinite(qk).all() else 9.0
            np.testing.assert_allclose(q[k], expect, atol=1e-12)


def test_body_rotation_is_the_kinematics_rotation():
    for rpy in ([0.0, 0.0, 0.0], [0.3, -0.2, 2.5], [-1.0, 1.2, -3.0]):
        np.testing.assert_allclose(body_rotation(np.array(rpy)), rotation_matrix(np.array(rpy)),
                                   atol=1e-14)


def test_body_rotation_is_mujocos_to_the_last_bit():
    # the controller turns attitudes into matrices without the simulator, by MuJoCo's own
    # operations: the same matrices, so a run is the same run whichever computes them
    import mujoco

    rng = np.random.default_rng(5)
    scales = rng.choice([1e-3, 0.1, 1.0, 3.1], (2000, 1))
    for rpy in np.vstack([rng.uniform(-1.0, 1.0, (2000, 3)) * scales, np.zeros((1, 3))]):
        quat, mat = np.empty(4), np.empty(9)
        mujoco.mju_euler2Quat(quat, rpy[::-1].copy(), "zyx")
        mujoco.mju_quat2Mat(mat, quat)
        np.testing.assert_array_equal(body_rotation(rpy), mat.reshape(3, 3))


def test_body_correction_integrates_height_roll_pitch_and_horizontal_error():
    cfg = LowLevelConfig(position_gain=0.1, horizontal_gain=0.2, attitude_gain=0.5,
                         max_position_correction=0.03, max_attitude_correction=0.2)
    corr = BodyCorrection(cfg)
    desired = (np.array([0.5, 0.0, 0.14]), np.array([0.0, 0.0, 0.3]))
    measured = (np.array([0.49, 0.01, 0.13]), np.array([0.02, -0.01, 0.0]))
    pos, rpy = corr.update(*desired, *measured)
    np.testing.assert_allclose(pos, [0.5 + 0.002, -0.002, 0.14 + 0.001])
    np.testing.assert_allclose(rpy, [-0.01, 0.005, 0.3])  # yaw follows the plan as it is
    for _ in range(1000):  # a lasting error saturates at the bounds
        pos, rpy = corr.update(*desired, *measured)
    np.testing.assert_allclose(pos, [0.53, -0.03, 0.17])
    np.testing.assert_allclose(rpy[:2], [-0.2, 0.2])


def test_rolling_ball_moves_its_centre_by_radius_times_the_tilt():
    start = Rotation.from_euler("z", np.array([0.0, 0.4, -1.0, 2.0])[:, None]).as_matrix()
    turn = Rotation.from_rotvec([[0.0, 0.3, 0.0], [0.0, 0.0, 0.7], [-0.2, 0.0, 0.0],
                                 [0.1, 0.2, 0.3]]).as_matrix()
    moved = rolled(start, turn @ start, 0.01)
    # About +y (toe forward): rolls 3 mm forward; about z: spins in place; about -x: 2 mm left.
    np.testing.assert_allclose(moved[:3], [[0.003, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.002, 0.0]],
                               atol=1e-12)
    np.testing.assert_allclose(moved[3], [0.002, -0.001, 0.0], atol=1e-12)


def test_shin_rotations_turn_the_lower_legs_as_the_kinematics_do():
    q = np.array([[0.2, -0.5, 1.1], [-0.1, -0.3, 0.9], [0.1, 0.4, -1.0], [-0.2, 0.6, -1.2]])
    rpy = np.array([0.05, -0.1, 0.7])
    body = Rotation.from_euler("ZYX", rpy[::-1]).as_matrix()
    rot = shin_rotations(q, body)
    for k, leg in enumerate(R.legs):  # the shin runs from the knee down its own -z axis
        shin = forward_kinematics(leg, q[k], R) - knee_position(leg, q[k], R)
        np.testing.assert_allclose(rot[k] @ [0.0, 0.0, -R.lower_leg], body @ shin, atol=1e-12)
        np.testing.assert_allclose(rot[k].T @ rot[k], np.eye(3), atol=1e-12)


# ------------------------------------------------------------- a short walk


SHORT = WalkConfig(start_setback=0.2, time_limit=30.0)


@pytest.fixture(scope="module")
def short_walks():
    board = short_flat_board()
    reward = default_reward()
    return [walk(board, lambda leg: reward, 7, SHORT) for _ in range(2)]


def test_short_seeded_walk_reaches_the_goal_and_keeps_its_balance(short_walks):
    result = short_walks[0].result
    assert result["success"] and result["reason"] == "goal"
    assert result["distance"] > 0.3 and result["steps"] >= 8
    # The measured centre of mass stayed inside the measured support triangle in every swing.
    assert result["min_stability_margin_mm"] > 0.0
    # Slip on flat ground: millimetres (mostly the ball feet rolling), not centimetres.
    assert 0.0 < result["slip_mean_mm"] < 13.0


def test_same_seed_same_run_bit_for_bit(short_walks):
    a, b = short_walks
    strip = lambda r: {k: v for k, v in r.result.items() if k not in WALL_CLOCK_FIELDS}
    assert strip(a) == strip(b)
    assert a.settings == b.settings and len(a.steps) == len(b.steps)
    for sa, sb in zip(a.steps, b.steps):
        assert sa.state.swing_leg == sb.state.swing_leg and sa.chosen == sb.chosen
        np.testing.assert_array_equal(sa.state.to_vector(), sb.state.to_vector())
        np.testing.assert_array_equal(sa.touchdown, sb.touchdown)
        assert sa.t_liftoff == sb.t_liftoff and (sa.slip == sb.slip or
                                                 (math.isnan(sa.slip) and math.isnan(sb.slip)))


def test_step_limit_ends_a_run_without_success():
    reward = default_reward()
    rec = walk(short_flat_board(), lambda leg: reward, 1, WalkConfig(start_setback=0.2,
                                                                      max_steps=2))
    assert rec.result["reason"] == "step limit" and not rec.result["success"]
    assert len(rec.steps) == 2 and [s.swing_leg for s in rec.steps] == list(R.gait_order[:2])


def test_walk_config_refuses_bad_settings():
    with pytest.raises(FootfallError, match="max_steps"):
        WalkConfig(max_steps=0)
    with pytest.raises(FootfallError, match="touchdown_early"):
        WalkConfig(touchdown_early=1.5)


# --------------------------------------------------------------------- CLI
def test_cli_walk_missing_terrain_is_one_line_and_exit_2(tmp_path, capsys):
    code, _, err = run(capsys, "walk", "--terrain", tmp_path / "none.npz", "--seed", "0")
    assert_user_error(code, err, "no such terrain file")
    code, _, err = run(capsys, "walk-many", "--terrain", tmp_path / "none.npz", "--seed", "0",
                       "--runs", "2")
    assert_user_error(code, err, "no such terrain file")


def test_cli_walk_refuses_a_model_for_another_robot(tmp_path, capsys):
    board = tmp_path / "board.npz"
    short_flat_board().save(board)
    config = FeatureConfig()
    terrain = TerrainFeatures(config)
    n = len(terrain.columns())
    f = LinearFunction(families=(terrain,), coef=(np.eye(n)[0],), scale=(np.ones(n),))
    other = RobotDescription(upper_leg=0.09)
    FootholdModel("terrain", "l1", {"front": f, "hind": f}, config, robot=other).save(
        tmp_path / "model.npz")
    code, _, err = run(capsys, "walk", "--terrain", board, "--model", tmp_path / "model.npz",
                       "--seed", "0")
    assert_user_error(code, err, "trained for robot")


def test_the_expert_can_choose_every_foothold_itself():
    """A judge in place of the reward: every logged candidate value is the expert's own."""
    from footfall.expert.scorer import ExpertScorer
    from footfall.expert.synthetic import SyntheticExpert, walking_expert

    board = short_flat_board()
    config = WalkConfig(start_setback=0.2, max_steps=3)
    expert = SyntheticExpert(walking_expert(config.footstep.lead))
    rec = walk(board, lambda leg: default_reward(), 1, config, judge=ExpertScorer(expert))
    assert rec.settings["judge"] == "synthetic expert"
    assert len(rec.steps) == 3
    for step in rec.steps:
        np.testing.assert_allclose(step.rewards, expert.values(board, step.state, step.candidates))
        # Flat ground: the expert wants the foot at its gait-nominal position (within 1 cm).
        assert step.rewards[step.chosen] > np.max(step.rewards) - 1.0


def test_cli_walk_expert_and_model_together_is_one_line_and_exit_2(tmp_path, capsys):
    board = tmp_path / "board.npz"
    short_flat_board().save(board)
    code, _, err = run(capsys, "walk", "--terrain", board, "--expert", "--model",
                       tmp_path / "model.npz", "--seed", "0")
    assert_user_error(code, err, "--expert chooses the footholds itself")
    code, _, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "2",
                       "--search-radius", "0")
    assert_user_error(code, err, "search_radius must be > 0")
    code, _, err = run(capsys, "walk", "--terrain", board, "--seed", "0",
                       "--friction-safety", "0.5")
    assert_user_error(code, err, "friction_safety must be >= 1")


def test_cli_walk_many_in_a_log_prints_progress_lines_on_stderr(tmp_path, capsys):
    # standard error is not a terminal here (as in `make run > log`): lines, not a bar
    board = tmp_path / "board.npz"
    assert run(capsys, "terrain", "board", "flat", "flat", "flat", "--seed", "1",
               "-o", board)[0] == 0
    code, out, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "2",
                         "--json")
    assert code == 0
    lines = err.splitlines()
    assert [line.split(",")[0] for line in lines] == ["runs: 1 / 2 runs done",
                                                      "runs: 2 / 2 runs done"]
    failed = 2 - json.loads(out)["successes"]
    assert lines[-1].startswith(f"runs: 2 / 2 runs done, {failed} failed, ")


def test_cli_walk_many_with_a_log_walks_only_the_runs_it_does_not_hold(tmp_path, capsys):
    board = tmp_path / "board.npz"
    assert run(capsys, "terrain", "board", "flat", "flat", "flat", "--seed", "1",
               "-o", board)[0] == 0
    log = tmp_path / "runs.sqlite"
    common = ["walk-many", "--terrain", board, "--seed", "4", "--log", log, "--json"]
    code, first, _ = run(capsys, *common, "--runs", "2")
    assert code == 0
    code, again, err = run(capsys, *common, "--runs", "3")  # seeds 4, 5 held; 6 walked
    assert code == 0
    lines = err.splitlines()
    assert lines[0] == f"runs: 2 of 3 already in {log}"
    assert [line.split(",")[0] for line in lines[1:]] == ["runs: 1 / 1 runs done"]
    strip = lambda out: [{k: v for k, v in r.items() if k not in WALL_CLOCK_FIELDS}
                         for r in json.loads(out)["runs_detail"]]
    assert strip(again)[:2] == strip(first)  # read back from the store, as walked
    from footfall.data.store import DemoStore

    with DemoStore(log) as store:
        keys = [r["key"] for r in store.runs()]
    assert len(keys) == len(set(keys)) == 3  # in the order the runs finished
    assert sorted(k.rsplit("/", 1)[1] for k in keys) == ["s4", "s5", "s6"]
    code, _, err = run(capsys, *common, "--runs", "1", "--search-radius", "0.03")
    assert code == 0 and "already" not in err  # other settings: another run
    with DemoStore(log) as store:
        assert len(store.runs()) == 4
    code, _, err = run(capsys, *common, "--runs", "1", "--friction-safety", "1.5")
    assert code == 0 and "already" not in err  # the friction check: another run
    with DemoStore(log) as store:
        runs = store.runs()
        assert len(runs) == 5 and runs[-1]["settings"]["walk"]["footstep"]["friction_safety"] == 1.5
    code, _, err = run(capsys, *common, "--runs", "1", "--variant", "no-press-to-load")
    assert code == 0 and "already" not in err  # another controller: another run
    with DemoStore(log) as store:
        runs = store.runs()
        assert len(runs) == 6 and runs[-1]["settings"]["walk"]["lowlevel"]["press_speed"] == 0
    code, _, err = run(capsys, *common, "--runs", "1", "--variant", "no-such-controller")
    assert_user_error(code, err, "no-such-controller")


def test_cli_walk_many_with_a_teacher_logs_it_and_refuses_an_unknown_one(tmp_path, capsys):
    from footfall.data.store import DemoStore

    board, log = tmp_path / "board.npz", tmp_path / "runs.sqlite"
    assert run(capsys, "terrain", "board", "flat", "flat", "flat", "--seed", "1",
               "-o", board)[0] == 0
    code, out, _ = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "1",
                       "--teacher", "guarded", "--log", log, "--json")
    assert code == 0 and json.loads(out)["teacher"] == "guarded"
    with DemoStore(log) as store:
        (row,) = store.runs()
        settings = store.run(row["id"]).settings
    assert row["key"].split("/")[2] == "guarded"  # not the expert's nor the hand-tuned runs
    assert set(settings["reward"]) == {"hand-tuned default, expert veto 10"}
    code, _, err = run(capsys, "walk-many", "--terrain", board, "--seed", "0", "--runs", "1",
                       "--teacher", "nobody")
    assert_user_error(code, err, "nobody")
    code, _, err = run(capsys, "walk", "--terrain", board, "--seed", "0", "--teacher",
                       "accepted", "--model", tmp_path / "model.npz")
    assert_user_error(code, err, "chooses the footholds itself")
