"""The physics' fidelity measures, and the caches that make batches of runs cheaper."""

import os

import numpy as np
import pytest

from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.sim.fidelity import ball_rest_errors, ball_rest_height, slope_creep
from footfall.terrain.modules import make_board

R = LITTLEDOG.foot_radius


def test_a_ball_rests_one_radius_above_flat_ground_and_on_the_top_of_a_step():
    flat = HeightMap(np.zeros((200, 200)), 0.001, (0.0, 0.0))
    assert ball_rest_height(flat, [[0.1, 0.1]], R) == pytest.approx([R])
    h = np.zeros((200, 200))
    h[100:, :] = 0.02  # a 2 cm step up at x = 0.1 m
    step = HeightMap(h, 0.001, (0.0, 0.0))
    # on top, on the lower floor well away, and touching the edge from below (rests on the edge)
    z = ball_rest_height(step, [[0.15, 0.1], [0.05, 0.1], [0.1 - 0.006, 0.1]], R)
    assert z[0] == pytest.approx(0.02 + R) and z[1] == pytest.approx(R)
    assert z[2] == pytest.approx(0.02 + np.sqrt(R ** 2 - 0.006 ** 2), abs=2e-4)


def test_loaded_ball_feet_rest_where_the_map_says_within_a_fraction_of_a_millimetre():
    board = make_board([("rocky", 0.3)], seed=2)
    rng = np.random.default_rng(0)
    xy = np.column_stack([rng.uniform(0.7, 1.1, 40), rng.uniform(-0.2, 0.2, 40)])
    errors = ball_rest_errors(board, xy)
    assert errors.shape == (40,) and np.isfinite(errors).all()
    assert np.median(np.abs(errors)) < 0.5e-3  # [m] (0.1-0.3 mm: the soft contact sinks)
    flat = make_board([("flat", 0.0)] * 3, seed=0)
    sink = ball_rest_errors(flat, xy[:8])
    assert np.all(sink < 0) and np.all(sink > -0.3e-3)  # a loaded ball sinks in a little


def test_a_foot_standing_on_a_slope_does_not_creep():
    travel = slope_creep()
    assert travel.shape == (4,) and np.all(travel < 0.5e-3)  # [m] in 4 s (Coulomb: none)

    def slippery(model):  # MuJoCo's default friction impedance: the feet creep
        model.opt.impratio = 1.0

    assert slope_creep(tune=slippery).max() > 3 * travel.max()


def test_a_boards_reward_grids_are_scored_once_and_kept_read_only():
    from footfall.control.body_path import terrain_grids
    from footfall.features.reward import default_reward

    board = make_board([("rocky", 0.5)], seed=4)
    reward = default_reward()
    first = terrain_grids(board, lambda leg: reward)
    again = terrain_grids(board, lambda leg: reward)
    assert all(first[leg] is again[leg] for leg in first)
    assert not first["LF"].reward.flags.writeable
    twin = HeightMap(board.heights.copy(), board.resolution, board.origin)  # another map object
    other = terrain_grids(twin, lambda leg: reward)
    assert other["LF"] is not first["LF"]
    assert np.array_equal(other["LF"].reward, first["LF"].reward)


def test_a_worker_loads_a_board_file_once_while_it_is_unchanged(tmp_path):
    from footfall.experiments.runs import _board

    path = tmp_path / "b.npz"
    make_board([("flat", 0.0)], seed=0).save(path)
    assert _board(str(path)) is _board(str(path))
    held = _board(str(path))
    make_board([("rocky", 0.5)], seed=0).save(path)
    os.utime(path, ns=(1, 1))  # a changed file (size and time) is read again
    assert _board(str(path)) is not held
    assert _board(str(path)).metadata["modules"][1]["kind"] == "rocky"


def test_a_physics_variant_changes_the_models_compiled_inside_it_only():
    from footfall.core.errors import FootfallError
    from footfall.sim.mjcf import compile_model
    from footfall.sim.variants import physics_variant

    flat = make_board([("flat", 0.0)], seed=0)
    with physics_variant({"cone": "pyramidal", "impratio": "10"}, max_spacing=0.004):
        model = compile_model(LITTLEDOG, flat)
        assert model.opt.cone == 0 and model.opt.impratio == 10.0  # mjCONE_PYRAMIDAL
    documented = compile_model(LITTLEDOG, flat)
    assert documented.opt.cone == 1 and documented.opt.impratio == 100.0
    with pytest.raises(FootfallError, match="unknown physics option"):
        with physics_variant({"gravity": "0 0 0"}):
            pass
    with pytest.raises(FootfallError, match="invalid keyword"):
        with physics_variant({"cone": "banana"}):
            pass


def test_bench_sim_refuses_a_bad_physics_option_in_one_line(capsys):
    from cli_helpers import assert_user_error, run

    code, _, err = run(capsys, "bench", "sim", "--physics", "cone")
    assert_user_error(code, err, "--physics takes OPTION=VALUE")
    code, _, err = run(capsys, "bench", "sim", "--physics", "cone=banana")
    assert_user_error(code, err, "invalid keyword")


def test_foot_pads_touch_where_a_ball_rests_on_the_registered_terrain():
    from footfall.sim.foot_pads import BallSurface
    from footfall.sim.hfield import registration_centre, terrain_surface

    res, grade = 0.001, 0.3
    x = np.arange(600) * res
    slope = HeightMap(np.repeat((grade * x)[:, None], 400, axis=1), res, (0.0, -0.2))
    centre = registration_centre(slope)
    plain = BallSurface(terrain_surface(slope), slope, R, centre, 0.0, np.zeros(3))
    contact, normal = plain.contact(np.array([[0.3, 0.0, 0.2]]))
    expected = np.array([-grade, 0.0, 1.0]) / np.hypot(grade, 1.0)
    np.testing.assert_allclose(normal[0], expected, atol=1e-9)
    assert contact[0, 2] == pytest.approx(grade * contact[0, 0], abs=3e-5)  # on the slope
    # registered: the terrain turned 0.1 rad about its centre and lifted 2 mm
    yaw, offset = 0.1, np.array([0.003, -0.002, 0.002])
    moved = BallSurface(terrain_surface(slope), slope, R, centre, yaw, offset)
    world = np.array([[0.31, 0.02, 0.3]])
    contact, normal = moved.contact(world)
    c, s = np.cos(yaw), np.sin(yaw)
    back = np.array([[c, s], [-s, c]]) @ (contact[0, :2] - centre - offset[:2]) + centre
    assert contact[0, 2] - offset[2] == pytest.approx(grade * back[0], abs=3e-5)
    np.testing.assert_allclose(normal[0, :2], [-grade * c, -grade * s] / np.hypot(grade, 1.0),
                               atol=1e-9)


def test_the_pads_variant_gives_each_foot_one_contact_and_leaves_the_documented_model():
    import mujoco

    from footfall.core.state import nominal_state
    from footfall.sim.simulation import Simulation
    from footfall.sim.variants import physics_variant

    board = make_board([("rocky", 0.5)], seed=0)
    with physics_variant(foot_contact="pads"):
        sim = Simulation(hmap=board)
    st = nominal_state(board, (0.9, 0.0), 0.0, "LF")
    sim.stand(st.body_position, st.body_rpy, st.feet)
    sim.advance(0.5)
    foot_geoms = {mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, f"{leg}_foot")
                  for leg in ("LF", "RF", "LH", "RH")}
    touching = [g for pair in sim.data.contact.geom[:sim.data.ncon] for g in pair
                if g in foot_geoms]
    assert sorted(touching) == sorted(foot_geoms)  # four feet down, one contact each
    sim.close()
    plain = Simulation(hmap=board)
    assert mujoco.mj_name2id(plain.model, mujoco.mjtObj.mjOBJ_BODY, "LF_pad") < 0
    plain.close()
    with physics_variant(foot_contact="pads"):
        errors = ball_rest_errors(board, np.array([[0.8, 0.0], [0.9, 0.1], [1.0, -0.1]]))
    assert np.all(np.abs(errors) < 0.5e-3)  # each probe on its own pad: where the map says
