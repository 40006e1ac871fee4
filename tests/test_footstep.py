"""The footstep planner: path-biased foothold choice with a five-step look-ahead."""


import numpy as np
import pytest

from footfall.control.body_path import BodyPath, terrain_grids
from footfall.control.footstep import FootstepConfig, FootstepPlan, FootstepPlanner, NoFootholdError
from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LEG_NAMES, LITTLEDOG
from footfall.core.state import RobotState, feet_pitch, nominal_state
from footfall.features.candidates import reachable_footholds
from footfall.features.pose_features import POSE_FEATURE_NAMES, PoseFeatures
from footfall.features.reward import LinearReward, default_reward, weights_from_names
from footfall.features.scoring import score_footholds
from footfall.features.spread import reward_spread
from footfall.terrain.modules import make_module

REWARD = default_reward()
POSED = REWARD.with_weights(PoseFeatures(), weights_from_names(
    {"next_cog_margin": 20.0, "knee_clearance": 10.0, "fore_aft_height_diff": -20.0,
     "swing_obstacle": -20.0}, POSE_FEATURE_NAMES))


def grid_map(heights, res=0.001, y0=-0.3):
    """Heights on a 1 mm grid whose cell (0, 0) is at (0, y0): lattice points at 5 mm multiples."""
    return HeightMap(heights, res, (0.0, y0))


def flat_map(length=0.9, width=0.6):
    return grid_map(np.zeros((int(length / 0.001) + 1, int(width / 0.001) + 1)), y0=-width / 2)


@pytest.fixture(scope="module")
def flat():
    hmap = flat_map()
    return hmap, terrain_grids(hmap, lambda leg: REWARD)


@pytest.fixture(scope="module")
def rocky():
    hmap = make_module("rocky", 0.6, seed=5)
    return hmap, terrain_grids(hmap, lambda leg: REWARD)


def walk(planner, start_s, steps):
    """A kinematic walk: plan, put the swing foot down, move the body one advance along the path."""
    path, adv = planner.path, planner.config.step_advance
    state = nominal_state(planner.hmap, path.point_at(start_s), 0.0, LITTLEDOG.gait_order[0])
    feet = state.feet.copy()
    plans = []
    for k in range(steps):
        xy = path.point_at(start_s + k * adv)
        leg = LITTLEDOG.gait_order[k % 4]
        state = RobotState(feet, np.array([*xy, feet[:, 2].mean() + LITTLEDOG.nominal_height]),
                           np.zeros(3), leg)
        plan = planner.plan(state)
        feet[LEG_NAMES.index(leg)] = plan.foothold
        plans.append(plan)
    return plans


def test_on_flat_ground_the_feet_advance_along_the_path_near_the_nominal_stance(flat):
    hmap, grids = flat
    path = BodyPath.straight((0.2, 0.0), (0.8, 0.0))
    planner = FootstepPlanner(hmap, lambda leg: REWARD, path, grids=grids)
    plans = walk(planner, 0.1, 12)
    cfg = planner.config
    stride = 4 * cfg.step_advance
    for k, plan in enumerate(plans):
        assert isinstance(plan, FootstepPlan)
        assert plan.leg == LITTLEDOG.gait_order[k % 4]
        assert plan.legs == tuple(LITTLEDOG.gait_order[(k + i) % 4] for i in range(5))
        np.testing.assert_array_equal(plan.footholds[0], plan.foothold)
        np.testing.assert_array_equal(plan.candidates[plan.index], plan.foothold)
        assert plan.total[plan.index] == plan.total.max()  # no pose weights: greedy is optimal
        # The nominal stance around the body half a stride after touch-down.
        body_x = 0.2 + 0.1 + (k + 1) * cfg.step_advance + cfg.lead
        nominal = np.array([body_x, 0.0]) + np.array(LITTLEDOG.nominal_foot(plan.leg)[:2])
        np.testing.assert_allclose(plan.targets[0], nominal, atol=1e-12)
        assert np.linalg.norm(plan.foothold[:2] - nominal) <= cfg.spacing / np.sqrt(2) + 1e-12
        assert plan.foothold[2] == 0.0
        np.testing.assert_allclose(plan.body_xy[:, 1], 0.0)
        np.testing.assert_allclose(plan.body_yaw, 0.0)
    for leg_plans in (plans[i::4] for i in range(4)):  # each leg strides forward
        x = np.array([p.foothold[0] for p in leg_plans])
        np.testing.assert_allclose(np.diff(x), stride, atol=cfg.spacing)
        y = np.array([p.foothold[1] for p in leg_plans])
        assert np.ptp(y) <= cfg.spacing


def test_on_rough_ground_the_planner_trades_terrain_against_the_path(rocky):
    hmap, grids = rocky
    path = BodyPath.straight((0.15, 0.0), (0.5, 0.0))
    planner = FootstepPlanner(hmap, lambda leg: REWARD, path, grids=grids)
    plans = walk(planner, 0.05, 8)
    for plan in plans:
        # The reward of every candidate is the reward function's (float32 grids vs exact patches).
        state = RobotState(np.zeros((4, 3)), np.array([*plan.body_xy[0], 0.2]), np.zeros(3),
                           plan.leg)
        sample = np.linspace(0, plan.candidates.shape[0] - 1, 25).astype(int)
        exact = score_footholds(hmap, state, plan.candidates[sample], REWARD)
        np.testing.assert_allclose(plan.reward[sample], exact, rtol=1e-4, atol=1e-4)
        # Better terrain than the footholds nearest the target, at most a few cm away from it.
        nearest = np.argmin(np.linalg.norm(plan.candidates[:, :2] - plan.targets[0], axis=1))
        assert plan.reward[plan.index] >= plan.reward[nearest]
        assert np.linalg.norm(plan.foothold[:2] - plan.targets[0]) < 0.1
    assert any(p.reward[p.index] > p.reward[np.argmin(
        np.linalg.norm(p.candidates[:, :2] - p.targets[0], axis=1))] for p in plans)


def test_candidate_set_is_the_reachable_set_with_feature_coverage(rocky):
    hmap, grids = rocky
    path = BodyPath.straight((0.15, 0.0), (0.5, 0.0))
    planner = FootstepPlanner(hmap, lambda leg: REWARD, path, grids=grids)
    for leg in LEG_NAMES:
        state = nominal_state(hmap, (0.3, 0.0), 0.0, leg)
        plan = planner.plan(state)
        touchdown = RobotState(state.feet, np.array([*plan.body_xy[0], state.feet[:, 2].mean()
                                                     + LITTLEDOG.nominal_height]),
                               np.array([0.0, feet_pitch(state.feet), 0.0]), leg)
        expected = reachable_footholds(hmap, touchdown, LITTLEDOG, 0.005, REWARD.config)
        np.testing.assert_array_equal(plan.candidates, expected)
        # The look-ahead's small windows follow the same rule.
        near = planner._near(touchdown, plan.targets[0])
        inside = np.linalg.norm(expected[:, :2] - plan.targets[0], axis=1) \
            <= planner.config.lookahead_radius
        assert inside.sum() > 100
        np.testing.assert_array_equal(near, expected[inside])


def test_look_ahead_avoids_a_hole_that_leaves_the_next_steps_badly_off():
    # The left front foot stands in a pit and is about to step out of it onto
    # the floor; beside the left hind foot's target is a foot-sized hole as
    # deep as the pit. A reward that wants the feet of one side level makes
    # the hole the greedy choice for the hind foot (level with the front foot
    # now), but the front foot's next step back onto the floor then pays for it.
    x = np.arange(0.0, 0.9, 0.001)
    y = np.arange(-0.3, 0.3 + 1e-9, 0.001)
    X, Y = np.meshgrid(x, y, indexing="ij")
    h = np.zeros(X.shape)
    h[(X >= 0.48) & (X <= 0.52) & (Y >= 0.05) & (Y <= 0.11)] = -0.03  # pit under LF
    h[(X >= 0.368) & (X <= 0.387) & (Y >= 0.068) & (Y <= 0.092)] = -0.03  # hole by LH's target
    hmap = grid_map(h)
    level = LinearReward((PoseFeatures(),), (weights_from_names({"fore_aft_height_diff": -100.0},
                                                                POSE_FEATURE_NAMES),))
    path = BodyPath.straight((0.2, 0.0), (0.8, 0.0))
    feet = np.array([[0.50, 0.08, -0.03], [0.50, -0.08, 0.0], [0.30, 0.08, 0.0], [0.30, -0.08, 0.0]])
    state = RobotState(feet, np.array([0.4, 0.0, 0.14]), np.zeros(3), "LH")
    grids = terrain_grids(hmap, lambda leg: level)

    greedy = FootstepPlanner(hmap, lambda leg: level, path, config=FootstepConfig(lookahead=1),
                             grids=grids).plan(state)
    assert greedy.foothold[2] == pytest.approx(-0.03)  # into the hole
    assert greedy.legs == ("LH",)

    ahead = FootstepPlanner(hmap, lambda leg: level, path, grids=grids).plan(state)
    assert ahead.foothold[2] == pytest.approx(0.0)  # beside it, on the floor
    assert ahead.legs == ("LH", "LF", "RH", "RF", "LH")
    assert np.all(ahead.footholds[:, 2] == 0.0)
    # The hole is the better single step, the floor the better five steps.
    hole = int(np.nanargmax(ahead.total))
    assert ahead.candidates[hole, 2] == pytest.approx(-0.03)
    assert ahead.total[hole] > ahead.total[ahead.index]
    assert ahead.value[ahead.index] > ahead.value[hole] > -np.inf
    np.testing.assert_array_equal(ahead.value[np.isfinite(ahead.value)].size, 2)


def test_pose_weighted_rewards_are_the_reward_function_s(rocky):
    hmap, grids = rocky
    path = BodyPath.straight((0.15, 0.0), (0.5, 0.0))
    config = FootstepConfig(pose_candidates=None)
    planner = FootstepPlanner(hmap, lambda leg: POSED, path, config=config, grids=grids)
    state = nominal_state(hmap, (0.3, 0.0), 0.0, "RF")
    plan = planner.plan(state)
    touchdown = RobotState(state.feet, np.array([*plan.body_xy[0], state.feet[:, 2].mean()
                                                 + LITTLEDOG.nominal_height]),
                           np.array([0.0, feet_pitch(state.feet), 0.0]), "RF")
    exact = score_footholds(hmap, touchdown, plan.candidates, POSED)
    np.testing.assert_allclose(plan.reward, exact, rtol=1e-4, atol=1e-4)
    assert np.isfinite(plan.value[plan.index])

    short = FootstepPlanner(hmap, lambda leg: POSED, path, grids=grids).plan(state)
    evaluated = np.isfinite(short.reward)
    assert evaluated.sum() == FootstepConfig().pose_candidates
    np.testing.assert_allclose(short.reward[evaluated], plan.reward[evaluated], rtol=1e-12)
    assert short.index == plan.index


def test_off_grid_headings_score_exact_patches():
    hmap = flat_map(0.8, 0.8)
    path = BodyPath.straight((0.2, -0.1), (0.6, 0.2))  # heading 0.64 rad
    config = FootstepConfig(spacing=0.01, lookahead=2)
    grids = terrain_grids(hmap, lambda leg: REWARD, spacing=0.01)
    planner = FootstepPlanner(hmap, lambda leg: REWARD, path, config=config, grids=grids)
    state = nominal_state(hmap, (0.3, -0.025), 0.0, "LF")
    plan = planner.plan(state)
    yaw = np.arctan2(0.3, 0.4)
    np.testing.assert_allclose(plan.body_yaw, yaw)
    touchdown = RobotState(state.feet, np.array([*plan.body_xy[0], 0.14]),
                           np.array([0.0, 0.0, yaw]), "LF")
    np.testing.assert_allclose(plan.reward, score_footholds(hmap, touchdown, plan.candidates,
                                                            REWARD), rtol=1e-9)
    assert np.linalg.norm(plan.foothold[:2] - plan.targets[0]) <= 0.01


def test_no_candidates_raises_no_foothold_error(flat):
    hmap, _ = flat
    h = hmap.heights.copy()
    h[:, hmap.y > -0.06] = np.nan  # no data left of the body: no foothold for a left leg
    holed = HeightMap(h, hmap.resolution, hmap.origin)
    path = BodyPath.straight((0.2, -0.02), (0.8, -0.02))
    planner = FootstepPlanner(holed, lambda leg: REWARD, path)
    feet = np.array([[0.4, -0.01, 0.0], [0.4, -0.1, 0.0], [0.2, -0.01, 0.0], [0.2, -0.1, 0.0]])
    with pytest.raises(NoFootholdError, match="LH has no candidate"):
        planner.plan(RobotState(feet, np.array([0.3, -0.02, 0.14]), np.zeros(3), "LH"))
    assert issubclass(NoFootholdError, FootfallError)
    plan = planner.plan(RobotState(feet, np.array([0.3, -0.02, 0.14]), np.zeros(3), "RH"))
    assert plan.legs == ("RH", "RF")  # the look-ahead stops at the left hind leg: no footholds


def test_planning_is_deterministic(rocky):
    hmap, grids = rocky
    path = BodyPath.straight((0.15, 0.0), (0.5, 0.0))
    plans = [walk(FootstepPlanner(hmap, lambda leg: POSED, path, grids=g), 0.05, 4)
             for g in (grids, None)]
    for a, b in zip(*plans):
        for name in ("candidates", "reward", "total", "value", "footholds", "body_xy"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert a.index == b.index and a.legs == b.legs


def test_bad_input_raises(flat):
    hmap, grids = flat
    path = BodyPath.straight((0.2, 0.0), (0.8, 0.0))
    with pytest.raises(FootfallError, match="BodyPath"):
        FootstepPlanner(hmap, lambda leg: REWARD, [(0, 0), (1, 0)], grids=grids)
    with pytest.raises(FootfallError, match="HeightMap"):
        FootstepPlanner(np.zeros((5, 5)), lambda leg: REWARD, path, grids=grids)
    with pytest.raises(FootfallError, match="spacing"):
        FootstepPlanner(hmap, lambda leg: REWARD, path, config=FootstepConfig(spacing=0.01),
                        grids=grids)
    with pytest.raises(FootfallError, match="RobotState"):
        FootstepPlanner(hmap, lambda leg: REWARD, path, grids=grids).plan(np.zeros(20))
    for bad in ({"lookahead": 0}, {"beam_width": 1.5}, {"step_advance": 0.0},
                {"bias_weight": -1.0}, {"foot_lead": np.inf}, {"pose_candidates": 0},
                {"heading_tolerance": np.nan}, {"root_separation": -0.1}):
        with pytest.raises(FootfallError, match="footstep config"):
            FootstepConfig(**bad)


def test_path_bias_follows_the_rewards_scale():
    """A reward in other units (a learned one: logits) trades terrain against the path alike."""
    doubled = REWARD.scaled(2.0, name="doubled")
    assert reward_spread(doubled) == pytest.approx(2 * reward_spread(REWARD), rel=1e-4)
    hmap = flat_map()
    path = BodyPath.straight((0.3, 0.0), (0.8, 0.0))
    config = FootstepConfig(bias_weight=60.0)
    default = FootstepPlanner(hmap, lambda leg: default_reward(), path, config=config)
    assert default.bias_ == {leg: 60.0 for leg in LEG_NAMES}  # the default's own units, exactly
    scaled = FootstepPlanner(hmap, lambda leg: doubled, path, config=config)
    assert scaled.bias_ == pytest.approx({leg: 120.0 for leg in LEG_NAMES}, rel=1e-4)


def test_search_radius_keeps_f_near_the_gait_nominal_position_or_falls_back(flat):
    hmap, grids = flat
    path = BodyPath.straight((0.2, 0.0), (0.8, 0.0))
    radius = 0.02
    near = FootstepPlanner(hmap, lambda leg: REWARD, path, grids=grids,
                           config=FootstepConfig(search_radius=radius))
    every = FootstepPlanner(hmap, lambda leg: REWARD, path, grids=grids)
    (a,), (b,) = walk(near, 0.1, 1), walk(every, 0.1, 1)
    dist = np.linalg.norm(a.candidates[:, :2] - a.targets[0], axis=1)
    assert np.all(dist <= radius + 1e-9)
    assert a.candidates.shape[0] >= 0.9 * np.pi * (radius / 0.005) ** 2  # the whole disc is there
    assert b.candidates.shape[0] > 3 * a.candidates.shape[0]
    # No data within the radius of the target: F is every reachable foothold again.
    h = hmap.heights.copy()
    tx, ty = a.targets[0]
    h[np.ix_(np.abs(hmap.x - tx) < 0.03, np.abs(hmap.y - ty) < 0.03)] = np.nan
    holed = HeightMap(h, hmap.resolution, hmap.origin)
    (c,) = walk(FootstepPlanner(holed, lambda leg: REWARD, path,
                                config=FootstepConfig(search_radius=radius)), 0.1, 1)
    assert np.min(np.linalg.norm(c.candidates[:, :2] - a.targets[0], axis=1)) > radius
    assert c.candidates.shape[0] > a.candidates.shape[0]
    with pytest.raises(FootfallError, match="search_radius"):
        FootstepConfig(search_radius=0.0)


def test_the_path_bias_holds_against_a_rewards_pose_part_too():
    strong = POSED.scaled(10.0, state=True, name="strong")
    assert reward_spread(strong) > reward_spread(POSED) > reward_spread(
        POSED.scaled(0.0, state=True, name="no pose"))
    hmap = flat_map()
    path = BodyPath.straight((0.3, 0.0), (0.8, 0.0))
    config = FootstepConfig(bias_weight=60.0)
    a = FootstepPlanner(hmap, lambda leg: POSED, path, config=config).bias_
    b = FootstepPlanner(hmap, lambda leg: strong, path, config=config).bias_
    assert all(b[leg] > a[leg] for leg in LEG_NAMES)


def test_the_predicted_body_pitches_with_the_feet_so_a_front_foot_reaches_down_a_step():
    # Two steps down (60 -> 30 -> 0 mm): hind feet on top, front feet on the middle step.
    x = np.arange(0, 901) * 0.001
    heights = np.repeat(np.where(x < 0.40, 0.06, np.where(x < 0.47, 0.03, 0.0))[:, None], 601,
                        axis=1)
    hmap = grid_map(heights)
    state = nominal_state(hmap, (0.34, 0.0), 0.0, "LF")
    assert state.feet[0, 2] == pytest.approx(0.03) and state.feet[2, 2] == pytest.approx(0.06)
    pitch = feet_pitch(state.feet)
    assert pitch == pytest.approx(np.arctan2(0.03, 2 * LITTLEDOG.leg("LF").hip[0]))
    assert feet_pitch(np.zeros((4, 3))) == 0.0  # level feet: no pitch
    planner = FootstepPlanner(hmap, lambda leg: REWARD, BodyPath.straight((0.34, 0.0), (0.8, 0.0)))
    plan = planner.plan(state)
    # LF reaches its path-nominal foothold from there: the body is posed over the feet as they stand.
    assert plan.state.body_rpy[1] == pytest.approx(feet_pitch(state.feet))
    level = RobotState(plan.state.feet, plan.state.body_position, np.zeros(3), "LF")
    lower = [np.sum(f[:, 2] == 0.0) for f in (
        reachable_footholds(hmap, level), reachable_footholds(hmap, plan.state))]
    assert lower[1] > 2 * lower[0]  # the pitched body reaches much more of the lower level


def test_the_body_is_predicted_for_the_stance_after_the_step_so_a_front_foot_reaches_down_a_riser():
    # One 64 mm riser down at x = 0.40 m, every foot still on top: posed over the feet as they
    # stand, the body would hold LF's hip so high that nothing below the edge is in reach, and the
    # robot would shuffle at the edge for ever (it did, on steps modules with a single riser).
    x = np.arange(0, 901) * 0.001
    hmap = grid_map(np.repeat(np.where(x < 0.40, 0.064, 0.0)[:, None], 601, axis=1))
    state = nominal_state(hmap, (0.28, 0.0), 0.0, "LF")
    assert np.all(state.feet[:, 2] == pytest.approx(0.064))
    config = FootstepConfig(search_radius=0.03)
    plan = FootstepPlanner(hmap, lambda leg: REWARD, BodyPath.straight((0.28, 0.0), (0.8, 0.0)),
                           config=config).plan(state)
    assert hmap.height_at(plan.targets[:1])[0] == 0.0  # LF's path-nominal foothold is below
    assert plan.foothold[2] == 0.0 and plan.foothold[0] > 0.40  # and it steps down
    assert np.hypot(*(plan.foothold[:2] - plan.targets[0])) <= 0.03
    after = state.feet.copy()  # posed for the stance after the step: LF at its nominal foothold
    after[0] = (*plan.targets[0], 0.0)
    assert plan.state.body_rpy[1] == pytest.approx(feet_pitch(after))
    assert plan.state.body_position[2] == pytest.approx(after[:, 2].mean()
                                                        + LITTLEDOG.nominal_height)
    before = RobotState(state.feet, (*plan.state.body_position[:2],
                                     state.feet[:, 2].mean() + LITTLEDOG.nominal_height),
                        np.array([0.0, feet_pitch(state.feet), 0.0]), "LF")
    assert not np.any(reachable_footholds(hmap, before)[:, 2] == 0.0)
    assert np.sum(reachable_footholds(hmap, plan.state)[:, 2] == 0.0) > 100


def test_the_compiled_reach_test_is_the_inverse_kinematics_within_limits():
    from footfall.core.kinematics import (
        body_to_world,
        inverse_kinematics,
        reaches_points,
        world_to_body,
    )
    from footfall.core.robot import LITTLEDOG

    rng = np.random.default_rng(9)
    for leg in LITTLEDOG.legs:
        body, rpy = rng.normal(0.0, 0.05, 3) + [0.5, 0.0, 0.15], rng.normal(0.0, 0.2, 3)
        points = body + rng.uniform(-0.25, 0.25, (2000, 3)) - [0.0, 0.0, 0.1]
        _, expect = inverse_kinematics(leg, world_to_body(points, body, rpy), LITTLEDOG)
        got = reaches_points(leg, points, body, rpy, LITTLEDOG)
        assert (got == expect).all() and 0 < got.sum() < got.size
        # The kernel skips the trigonometry beyond the farthest reach, sqrt(d^2 + (l1 + l2)^2)
        # from the hip: on shells just inside and outside it, the answers are the IK's too.
        far = np.sqrt(LITTLEDOG.hip_offset ** 2 + (LITTLEDOG.upper_leg + LITTLEDOG.lower_leg) ** 2)
        u = rng.normal(size=(3000, 3))
        u[:, 2] = -np.abs(u[:, 2])  # below the hip, where the leg hangs
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        scale = far * (1.0 + rng.choice([-1e-3, -1e-9, -1e-12, 0.0, 1e-12, 1e-10, 1e-3], 3000))
        local = np.asarray(leg.hip) + u * scale[:, None]
        points = body_to_world(local, body, rpy)
        _, expect = inverse_kinematics(leg, world_to_body(points, body, rpy), LITTLEDOG)
        assert (reaches_points(leg, points, body, rpy, LITTLEDOG) == expect).all()
