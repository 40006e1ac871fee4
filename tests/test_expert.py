"""The synthetic expert: Fig. 2's ordering, physical terrain judgement, and its choices."""

import math

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.kinematics import body_to_world, inverse_kinematics, knee_position, world_to_body
from footfall.core.robot import LITTLEDOG
from footfall.core.sphere_surface import sphere_surface
from footfall.core.state import RobotState, nominal_state
from footfall.expert.synthetic import ExpertConfig, SyntheticExpert, walking_expert
from footfall.expert.terms import EXPERT_TERM_NAMES, EXPERT_TERMS
from footfall.features.candidates import reachable_footholds
from footfall.terrain.modules import make_board

RES = 0.001  # [m] the scan resolution
SHAPE = (600, 600)
ORIGIN = (-0.3, -0.3)  # cell (300, 300) is at (0, 0)
EXPERT = SyntheticExpert()
TERRAIN_TERMS = ("slip_margin", "pinch", "trap_depth", "drop_off", "riser_ahead", "leg_clearance",
                 "unknown")


def grid():
    x = ORIGIN[0] + np.arange(SHAPE[0]) * RES
    y = ORIGIN[1] + np.arange(SHAPE[1]) * RES
    return x[:, None], y[None, :]


def hmap(z):
    return HeightMap(np.broadcast_to(z, SHAPE).copy(), RES, ORIGIN)


FLAT = hmap(0.0)
STATE = nominal_state(FLAT, (0.0, 0.0), 0.0, "LF")  # the same state on every test terrain
P = STATE.feet[STATE.swing_index, :2]  # the LF nominal foothold (0.101, 0.080), a cell centre


def judge(terrain, xy=P):
    """Value and terms of one candidate at xy on a terrain (height taken from the map)."""
    cand = np.array([[xy[0], xy[1], float(terrain.height_at(np.asarray(xy)))]])
    terms = EXPERT.terms(terrain, STATE, cand)
    return float(EXPERT.values(terrain, STATE, cand)[0]), {k: float(v[0]) for k, v in terms.items()}


def radius_from(xy=P):
    x, y = grid()
    return np.hypot(x - xy[0], y - xy[1])


def bowl(depth, across):
    """A spherical dent ``depth`` [m] deep and ``across`` [m] wide, centred on P."""
    a = across / 2
    big = (a * a + depth * depth) / (2 * depth)  # [m] radius of the sphere
    rho = radius_from()
    return hmap(np.minimum(big - depth - np.sqrt(np.clip(big * big - rho * rho, 0, None)), 0.0))


def hole(width, depth):
    """A steep-walled cylindrical hole, flat bottom, centred on P."""
    return hmap(np.where(radius_from() <= width / 2, -depth, 0.0))


# ------------------------------------------------------------------ geometry
def test_ball_surface_is_the_lowered_ball():
    """B(x, y) = max over cells within r of h + sqrt(r^2 - d^2), holes giving no support."""
    rng = np.random.default_rng(0)
    h = 0.004 * rng.standard_normal((60, 60))
    h[20:30, 25:40] = np.nan
    m = HeightMap(h, RES, (0.0, 0.0))
    r = LITTLEDOG.foot_radius
    surf = sphere_surface(m, np.array([0.015, 0.015]), np.array([0.045, 0.045]), r)
    for i, j in [(30, 30), (22, 30), (15, 45), (40, 18)]:
        d2 = ((np.arange(60)[:, None] - i) ** 2 + (np.arange(60)[None, :] - j) ** 2) * RES ** 2
        lift = np.where((d2 <= r * r) & ~np.isnan(h), h + np.sqrt(np.clip(r * r - d2, 0, None)),
                        -np.inf)
        assert surf.at(np.array([i * RES, j * RES])) == pytest.approx(lift.max(), abs=1e-12)
    # On a 45 deg plane the ball sits r / cos(45 deg) above the point under its centre.
    x, _ = grid()
    plane = hmap(x - P[0] + 0 * x)
    _, t = judge(plane)
    cand = np.array([[*P, 0.0]])
    seat = sphere_surface(plane, P, P, r).at(cand[:, :2])[0]
    assert seat == pytest.approx(r * math.sqrt(2), abs=2e-5)
    assert t["slip_margin"] == pytest.approx(math.atan(LITTLEDOG.foot_friction) - math.pi / 4,
                                             abs=0.02)


def test_terms_are_named_documented_and_finite():
    assert set(EXPERT_TERMS) == set(EXPERT_TERM_NAMES)
    assert all(doc.startswith("[") for doc in EXPERT_TERMS.values())  # unit first
    cand = reachable_footholds(FLAT, STATE)
    terms = EXPERT.terms(FLAT, STATE, cand)
    assert tuple(terms) == EXPERT_TERM_NAMES
    assert all(v.shape == (cand.shape[0],) and np.isfinite(v).all() for v in terms.values())
    # On flat open ground the ball is neither held, pinched, trapped nor near a drop.
    phi = math.atan(LITTLEDOG.foot_friction)
    np.testing.assert_allclose(terms["slip_margin"], phi)
    for name in ("pinch", "trap_depth", "drop_off", "unknown"):
        np.testing.assert_allclose(terms[name], 0.0, atol=1e-12, err_msg=name)


# ------------------------------------------------------------- Fig. 2 order
def test_fig2_mild_hollow_beats_flat_beats_deep_narrow_hole():
    v_flat, t_flat = judge(FLAT)
    v_bowl, t_bowl = judge(bowl(depth=0.003, across=0.04))
    v_hole, t_hole = judge(hole(width=0.015, depth=0.03))
    assert v_bowl > v_flat + 0.5 > v_hole + 2.0
    # Why: the hollow holds the ball from every side; the hole pinches it on its rim.
    assert t_bowl["slip_margin"] > t_flat["slip_margin"]
    assert t_bowl["pinch"] < 0.05 and t_hole["pinch"] > 0.6
    # The ball (2 cm) rests on the rim of the 1.5 cm hole, 3.4 mm down, not at its bottom.
    r, a = LITTLEDOG.foot_radius, 0.0075
    assert t_hole["trap_depth"] == pytest.approx(r - math.sqrt(r * r - a * a), abs=3e-4)


@pytest.mark.parametrize("depth, across", [(0.002, 0.03), (0.004, 0.05), (0.005, 0.04)])
def test_mild_hollows_of_several_sizes_beat_flat(depth, across):
    assert judge(bowl(depth, across))[0] > judge(FLAT)[0]


def test_a_hole_the_ball_falls_into_traps_it():
    v_flat, _ = judge(FLAT)
    v_hole, t_hole = judge(hole(width=0.024, depth=0.03))
    assert t_hole["trap_depth"] == pytest.approx(0.03, abs=1e-3)
    assert v_hole < v_flat - 5.0


def test_steep_face_beyond_the_friction_cone_is_worse_than_flat():
    _, y = grid()
    v_flat, _ = judge(FLAT)
    slopes = {deg: judge(hmap(math.tan(math.radians(deg)) * (y - P[1])))
              for deg in (15, 30, 45, 60)}  # faces rising outward, away from the leg
    values = [slopes[deg][0] for deg in (15, 30, 45, 60)]
    assert v_flat > values[0] > values[1] > values[2] > values[3]
    assert slopes[30][1]["slip_margin"] > 0 > slopes[45][1]["slip_margin"]  # cone: 38.7 deg
    assert v_flat - slopes[45][0] > 10.0


def test_drop_off_edge_near_the_foot_is_worse_than_far_from_it():
    _, y = grid()
    near = hmap(np.where(y > P[1] + 0.005, -0.04, 0.0))  # ground falls 4 cm, 5 mm from the foot
    far = hmap(np.where(y > P[1] + 0.08, -0.04, 0.0))  # the same edge 8 cm away
    v_near, t_near = judge(near)
    v_far, t_far = judge(far)
    assert t_far["drop_off"] == 0 and t_near["drop_off"] > 0.015
    assert v_near < v_far - 5.0
    assert v_far == pytest.approx(judge(FLAT)[0])


def test_shin_or_knee_hitting_a_wall_is_worse_than_without():
    leg = LITTLEDOG.leg("LF")
    centre = np.array([*P, LITTLEDOG.foot_radius])
    q, ok = inverse_kinematics(leg, world_to_body(centre, STATE.body_position, STATE.body_rpy),
                               LITTLEDOG)
    knee = body_to_world(knee_position(leg, q, LITTLEDOG), STATE.body_position, STATE.body_rpy)
    assert ok and knee[0] > P[0] + 0.03  # the front knee points forward, over the terrain ahead
    x, y = grid()
    # A block under the lower leg, starting 2.4 cm ahead of the foot: the ball never touches it.
    wall = hmap(np.where((x >= P[0] + 0.024) & (np.abs(y - knee[1]) < 0.03), 0.045, 0.0))
    v_flat, t_flat = judge(FLAT)
    v_wall, t_wall = judge(wall)
    assert t_flat["leg_clearance"] > LITTLEDOG.lower_leg_radius and t_wall["leg_clearance"] < 0
    for name in ("slip_margin", "pinch", "trap_depth", "drop_off", "unknown"):
        assert t_wall[name] == pytest.approx(t_flat[name]), name  # the foot itself is unchanged
    assert v_wall < v_flat - 5.0


def test_more_progress_is_preferred_on_flat_ground():
    xs = P[0] + np.arange(-0.02, 0.031, 0.005)
    cand = np.column_stack([xs, np.full_like(xs, P[1]), np.zeros_like(xs)])
    v = EXPERT.values(FLAT, STATE, cand)
    assert np.all(np.diff(v) > 0)
    # Over the whole candidate set, the pose terms alone decide on flat ground.
    cand = reachable_footholds(FLAT, STATE)
    parts = EXPERT.contributions(FLAT, STATE, cand)
    terrain = sum(parts[k] for k in ("slip_margin", "pinch", "trap_depth", "drop_off", "unknown"))
    np.testing.assert_allclose(terrain, 0.0, atol=1e-9)
    best = cand[np.argmax(EXPERT.values(FLAT, STATE, cand))]
    assert best[0] > P[0] + 0.02  # a real step forward


# ------------------------------------------------------------------- choice
def test_choose_without_imperfection_is_argmax_and_second_best_when_asked():
    cand = reachable_footholds(FLAT, STATE)
    v = EXPERT.values(FLAT, STATE, cand)
    rng = np.random.default_rng(5)
    assert EXPERT.choose(FLAT, STATE, cand, rng) == int(np.argmax(v))
    second = SyntheticExpert(ExpertConfig(second_best_prob=1.0))
    assert second.choose(FLAT, STATE, cand, rng) == int(np.argsort(-v, kind="stable")[1])


def test_choose_is_deterministic_for_a_seed_and_noise_varies_it():
    cand = reachable_footholds(FLAT, STATE)[::8]
    noisy = SyntheticExpert(ExpertConfig(noise=2.0, second_best_prob=0.3))
    first = [noisy.choose(FLAT, STATE, cand, np.random.default_rng(s)) for s in range(12)]
    again = [noisy.choose(FLAT, STATE, cand, np.random.default_rng(s)) for s in range(12)]
    assert first == again
    assert len(set(first)) > 3  # the imperfection does change the choice
    with pytest.raises(FootfallError, match="empty"):
        EXPERT.choose(FLAT, STATE, np.zeros((0, 3)), np.random.default_rng(0))


def test_bad_settings_and_candidates_are_refused():
    with pytest.raises(FootfallError, match="second_best_prob"):
        ExpertConfig(second_best_prob=1.5)
    with pytest.raises(FootfallError, match="noise"):
        ExpertConfig(noise=-1.0)
    with pytest.raises(FootfallError, match="directions"):
        ExpertConfig(directions=7)
    with pytest.raises(FootfallError, match="placement_error"):
        ExpertConfig(placement_error=-0.001)
    with pytest.raises(FootfallError, match="placement error"):
        walking_expert(0.05, placement_error=float("nan"))
    with pytest.raises(FootfallError, match=r"\(n, 3\)"):
        EXPERT.values(FLAT, STATE, np.zeros((4, 2)))
    with pytest.raises(FootfallError, match="finite"):
        EXPERT.values(FLAT, STATE, np.array([[np.nan, 0.0, 0.0]]))


# -------------------------------------------------------------- missing data
def test_values_are_finite_with_holes_in_the_map():
    x, y = grid()
    h = np.zeros(SHAPE)
    h[(np.abs(x - P[0] - 0.01) < 0.006) & (np.abs(y - P[1]) < 0.02)] = np.nan  # no scan here
    h[(np.abs(x - P[0] + 0.04) < 0.01)[:, 0], :] = np.nan  # and a strip across the map
    holey = HeightMap(h, RES, ORIGIN)
    cand = reachable_footholds(FLAT, STATE)  # including points in the holes, with NaN height
    cand[:, 2] = holey.height_at(cand[:, :2])
    assert np.isnan(cand[:, 2]).any()
    terms = EXPERT.terms(holey, STATE, cand)
    v = EXPERT.values(holey, STATE, cand)
    assert np.isfinite(v).all() and all(np.isfinite(t).all() for t in terms.values())
    # Missing data is seen and penalised near the holes, not far from them.
    far = np.hypot(cand[:, 0] - P[0] - 0.01, cand[:, 1] - P[1]) > 0.06
    far &= np.abs(cand[:, 0] - P[0] + 0.04) > 0.04
    assert terms["unknown"][np.isnan(cand[:, 2])].min() > 0.1
    np.testing.assert_allclose(terms["unknown"][far], 0.0)
    np.testing.assert_allclose(v[far], EXPERT.values(FLAT, STATE, cand)[far])


# ------------------------------------------------------------- real terrain
def test_a_right_leg_is_judged_like_a_left_leg_on_the_mirrored_terrain():
    board = make_board([("rocky", 0.7)], 5)
    state = nominal_state(board, (0.95, 0.02), 0.05, "LF")
    cand = reachable_footholds(board, state)
    flip = np.array([1.0, -1.0, 1.0])
    swap = [1, 0, 3, 2]  # LF <-> RF, LH <-> RH
    mirrored = RobotState(state.feet[swap] * flip, state.body_position * flip,
                          state.body_rpy * np.array([-1.0, 1.0, -1.0]), "RF",
                          state.goal * flip[:2])
    np.testing.assert_allclose(EXPERT.values(board.mirrored_y(), mirrored, cand * flip),
                               EXPERT.values(board, state, cand), rtol=1e-9, atol=1e-9)


# --------------------------------------------------------- placement error
def test_placement_error_reads_the_terrain_where_the_foot_fares_worst():
    """Terrain terms from the worst of f, f + d and f - d along the heading; the rest from f."""
    d = 0.007
    board = make_board([("rocky", 0.7)], 3)
    robust = SyntheticExpert(ExpertConfig(placement_error=d))
    moved = 0
    for bx, yaw, leg in [(0.85, 0.0, "LF"), (1.0, 0.4, "RH"), (0.95, -0.3, "RF")]:
        state = nominal_state(board, (bx, 0.0), yaw, leg)
        cand = reachable_footholds(board, state)
        shift = d * np.array([math.cos(yaw), math.sin(yaw), 0.0])
        at = [EXPERT.terms(board, state, cand + s) for s in (0 * shift, shift, -shift)]
        score = np.stack([sum(p for k, p in EXPERT.utilities(t).items() if k in TERRAIN_TERMS
                              and k != "leg_clearance") for t in at])
        worst = np.argmin(score, axis=0)
        moved += np.count_nonzero(worst)
        got = robust.terms(board, state, cand)
        for name in EXPERT_TERM_NAMES:
            if name in TERRAIN_TERMS and name != "leg_clearance":
                want = np.choose(worst, [t[name] for t in at])
            else:  # the leg and the pose are judged at the foothold itself
                want = at[0][name]
            np.testing.assert_allclose(got[name], want, rtol=0, atol=1e-12, err_msg=name)
        assert np.all(robust.values(board, state, cand) <= EXPERT.values(board, state, cand) + 1e-9)
    assert moved > 0  # on rocky ground the shifted placements do matter


def test_placement_error_is_along_the_heading():
    """An edge across the heading 5 mm ahead counts more; one along the heading no more."""
    x, y = grid()
    robust = SyntheticExpert(ExpertConfig(placement_error=0.007))
    ahead = hmap(np.where(x > P[0] + 0.005, -0.04, 0.0))  # the heading (yaw 0) is +x
    beside = hmap(np.where(y > P[1] + 0.005, -0.04, 0.0))
    cand = lambda m: np.array([[P[0], P[1], float(m.height_at(np.asarray(P)))]])  # noqa: E731
    t_ahead, r_ahead = EXPERT.terms(ahead, STATE, cand(ahead)), robust.terms(ahead, STATE, cand(ahead))
    assert r_ahead["drop_off"][0] > t_ahead["drop_off"][0] + 0.003
    assert robust.values(ahead, STATE, cand(ahead))[0] < EXPERT.values(ahead, STATE, cand(ahead))[0] - 3
    t_beside, r_beside = EXPERT.terms(beside, STATE, cand(beside)), robust.terms(beside, STATE, cand(beside))
    for name in EXPERT_TERM_NAMES:
        assert r_beside[name][0] == t_beside[name][0], name


def test_roll_back_judges_a_trough_by_itself_and_a_crest_still_by_its_flank():
    """A ball set on a trough's flank slides back into it; one set off a crest slides away."""
    x, y = grid()
    u = x - P[0]  # [m] along the heading (yaw 0 is +x), 0 at the foothold
    bend = u * u / (2 * 0.015)  # [m] a round profile of 1.5 cm radius: the ball touches it once
    trough = hmap(np.minimum(bend, 0.03))  # a trough across the heading, f at its bottom
    crest = hmap(np.maximum(0.03 - bend, 0.0))  # a ridge, f on its top
    cand = lambda m: np.array([[P[0], P[1], float(m.height_at(np.asarray(P)))]])  # noqa: E731
    plain = SyntheticExpert(ExpertConfig(placement_error=0.007))
    back = SyntheticExpert(ExpertConfig(placement_error=0.007, roll_back=0.001))
    here = EXPERT.terms(trough, STATE, cand(trough))
    worst, rolled = plain.terms(trough, STATE, cand(trough)), back.terms(trough, STATE, cand(trough))
    assert worst["slip_margin"][0] < here["slip_margin"][0] - 0.2  # judged on the flank
    for name in EXPERT_TERM_NAMES:  # judged where the ball ends: the trough itself
        assert rolled[name][0] == here[name][0], name
    on_top = EXPERT.terms(crest, STATE, cand(crest))
    worst, rolled = plain.terms(crest, STATE, cand(crest)), back.terms(crest, STATE, cand(crest))
    assert rolled["slip_margin"][0] == worst["slip_margin"][0] < on_top["slip_margin"][0] - 0.2
    # So a trough now beats a crest for the rolled-back expert, and did not before.
    assert back.values(trough, STATE, cand(trough))[0] > back.values(crest, STATE, cand(crest))[0]
    assert plain.values(trough, STATE, cand(trough))[0] < plain.values(crest, STATE, cand(crest))[0]


def test_a_wall_is_not_a_flank_the_ball_slides_back_down():
    """A foothold at a bar's foot: the placement on the bar counts again with roll_back_wall."""
    x, y = grid()
    bar = hmap(np.where(x > P[0] + 0.012, 0.04, 0.0))  # a 4 cm wall 12 mm ahead of the foothold
    cand = np.array([[P[0], P[1], 0.0]])
    plain = SyntheticExpert(ExpertConfig(placement_error=0.007))
    back = SyntheticExpert(ExpertConfig(placement_error=0.007, roll_back=0.001))
    wall = SyntheticExpert(ExpertConfig(placement_error=0.007, roll_back=0.001, roll_back_wall=1.0))
    here = EXPERT.terms(bar, STATE, cand)
    a, b, c = (e.terms(bar, STATE, cand) for e in (plain, back, wall))
    assert a["slip_margin"][0] != here["slip_margin"][0]  # judged on the wall's edge
    assert all(b[k][0] == here[k][0] for k in EXPERT_TERM_NAMES)  # rolled back: as if no wall
    assert all(c[k][0] == a[k][0] for k in EXPERT_TERM_NAMES)  # a wall: judged on its edge again
    x0 = P[0]  # and a gentle trough is still judged by itself with the wall rule
    trough = hmap(np.minimum((x - x0) ** 2 / (2 * 0.015), 0.03))
    cand = np.array([[P[0], P[1], 0.0]])
    here, c = EXPERT.terms(trough, STATE, cand), wall.terms(trough, STATE, cand)
    assert all(c[k][0] == here[k][0] for k in EXPERT_TERM_NAMES)


def test_the_crown_reads_a_crest_above_its_ring_and_a_trough_below_it():
    """The crown: the seated ball centre against the ball-centre surface 2 cm around the aim."""
    x, y = grid()
    u = x - P[0]  # [m] along the heading, 0 at the foothold
    bend = u * u / (2 * 0.015)  # a round profile of 1.5 cm radius
    trough = hmap(np.minimum(bend, 0.03))
    crest = hmap(np.maximum(0.03 - bend, 0.0))
    cand = lambda m: np.array([[P[0], P[1], float(m.height_at(np.asarray(P)))]])  # noqa: E731
    config = ExpertConfig(crown_radius=0.02)
    judge_ = SyntheticExpert(config)
    # The ring: 16 directions; along the heading the profile is 0.02^2 / 0.03 = 13.3 mm off, across
    # it 0. The ball's centre follows the profile's offset curve: lower over the crest's convex
    # flanks, higher on the trough's concave ones (it rests on a 53 deg flank 17 mm above it).
    on_crest = judge_.terms(crest, STATE, cand(crest))["crown"][0]
    in_trough = judge_.terms(trough, STATE, cand(trough))["crown"][0]
    flat = judge_.terms(FLAT, STATE, cand(FLAT))["crown"][0]
    assert 0.004 < on_crest < 0.008
    assert -0.016 < in_trough < -0.008
    assert abs(flat) < 1e-12
    # Off by default: the value is the one without the term, to the last bit.
    weighted = SyntheticExpert(ExpertConfig(crown_radius=0.02, w_crown=8000.0))
    assert judge_.values(crest, STATE, cand(crest))[0] == EXPERT.values(crest, STATE, cand(crest))[0]
    # Weighted: 8 value units a mm above 2 mm, on the crest only.
    drop = (judge_.values(crest, STATE, cand(crest))[0]
            - weighted.values(crest, STATE, cand(crest))[0])
    assert drop == pytest.approx(8000.0 * (on_crest - 0.002), rel=1e-9)
    assert weighted.values(trough, STATE, cand(trough))[0] == judge_.values(
        trough, STATE, cand(trough))[0]


def test_the_crown_is_read_at_the_aim_not_at_a_placement_error():
    """A foothold 12 mm before a 4 cm bar: a placement 7 mm on stands at the bar's edge, whose
    crown is large; the crown stays the aim's, and it does not pick the worst placement."""
    x, y = grid()
    bar = hmap(np.where(x > P[0] + 0.012, 0.04, 0.0))
    cand = np.array([[P[0], P[1], 0.0]])
    at_aim = SyntheticExpert(ExpertConfig(crown_radius=0.02, w_crown=8000.0))
    placed = SyntheticExpert(ExpertConfig(crown_radius=0.02, w_crown=8000.0, placement_error=0.007))
    plain = SyntheticExpert(ExpertConfig(placement_error=0.007))
    a, b, c = (e.terms(bar, STATE, cand) for e in (at_aim, placed, plain))
    assert b["crown"][0] == a["crown"][0] < 0.0  # the bar beside it: the aim stands low
    for name in EXPERT_TERM_NAMES:  # every other term from the same placement as without it
        if name != "crown":
            assert b[name][0] == c[name][0], name


def test_roll_back_keeps_an_edge_ahead_and_changes_nothing_on_flat_ground():
    x, y = grid()
    back = SyntheticExpert(ExpertConfig(placement_error=0.007, roll_back=0.001))
    plain = SyntheticExpert(ExpertConfig(placement_error=0.007))
    for terrain in (hmap(np.where(x > P[0] + 0.005, -0.04, 0.0)), FLAT):  # a drop ahead; flat
        cand = np.array([[P[0], P[1], float(terrain.height_at(np.asarray(P)))]])
        a, b = plain.terms(terrain, STATE, cand), back.terms(terrain, STATE, cand)
        for name in EXPERT_TERM_NAMES:
            assert a[name][0] == b[name][0], name


def test_on_rocky_terrain_the_terrain_changes_the_choice():
    board = make_board([("rocky", 0.7)], 3)  # flat, rocky (x in [0.61, 1.22] m), flat
    phi = math.atan(LITTLEDOG.foot_friction)
    differs_from_progress = differs_from_pose = 0
    cases = [(bx, leg) for bx in (0.85, 1.0) for leg in ("LF", "RF", "LH", "RH")]
    for bx, leg in cases:
        state = nominal_state(board, (bx, 0.0), 0.0, leg)
        cand = reachable_footholds(board, state)
        terms = EXPERT.terms(board, state, cand)
        parts = EXPERT.utilities(terms)
        v = sum(parts.values())
        pose_only = sum(p for k, p in parts.items() if k not in TERRAIN_TERMS)
        i, i_progress, i_pose = np.argmax(v), np.argmax(terms["progress"]), np.argmax(pose_only)
        differs_from_progress += i != i_progress
        differs_from_pose += i != i_pose
        # The chosen foothold is physically sound, which the pose-only pick often is not.
        assert terms["slip_margin"][i] > 0.5 * phi
        assert terms["pinch"][i] < 1.0 and terms["leg_clearance"][i] > 0
        assert terms["trap_depth"][i] < 0.01 and terms["drop_off"][i] < 0.01
        terrain = sum(parts[k] for k in TERRAIN_TERMS)
        assert terrain[i] > terrain[i_pose] or i == i_pose
    assert differs_from_progress == len(cases)
    assert differs_from_pose >= len(cases) // 2


def test_walking_expert_wants_the_foot_at_the_gait_nominal_position_on_flat_ground():
    """With w_stance the expert's best on flat ground is the leg's default stance, stance_lead ahead."""
    lead = 0.05
    walking = SyntheticExpert(walking_expert(lead))
    assert walking.config.w_stance == 100.0 and walking.config.w_progress == 0.0
    cand = reachable_footholds(FLAT, STATE)
    terms = walking.terms(FLAT, STATE, cand)
    c, s = math.cos(STATE.yaw), math.sin(STATE.yaw)
    nominal = np.asarray(LITTLEDOG.nominal_foot(STATE.swing_leg)[:2]) + (lead, 0.0)
    target = STATE.body_position[:2] + np.array([c * nominal[0] - s * nominal[1],
                                                 s * nominal[0] + c * nominal[1]])
    np.testing.assert_allclose(terms["stance_offset"],
                               np.linalg.norm(cand[:, :2] - target, axis=1), atol=1e-12)
    parts = walking.contributions(FLAT, STATE, cand)
    np.testing.assert_allclose(parts["stance_offset"], -100.0 * terms["stance_offset"])
    np.testing.assert_allclose(parts["progress"], 0.0)
    best = cand[np.argmax(walking.values(FLAT, STATE, cand))]
    assert np.linalg.norm(best[:2] - target) < 0.011  # within two lattice steps of the target
    # The default expert (w_stance 0) is unchanged by the term: it still reaches forward.
    assert np.all(EXPERT.contributions(FLAT, STATE, cand)["stance_offset"] == 0.0)


def _window_surface(hmap, lo, hi, radius):
    """The sphere surface dilated on the window alone: the computation before per-map caching."""
    from footfall.core.ball import ball_centre_surface

    res = hmap.resolution
    reach = int(math.ceil(radius / res))
    lo_idx = np.floor((np.asarray(lo) - hmap.origin) / res).astype(int) - reach - 1
    hi_idx = np.ceil((np.asarray(hi) - hmap.origin) / res).astype(int) + reach + 2
    i0, j0 = max(lo_idx[0], 0), max(lo_idx[1], 0)
    i1, j1 = min(hi_idx[0], hmap.shape[0]), min(hi_idx[1], hmap.shape[1])
    return ball_centre_surface(hmap.heights[i0:i1, j0:j1], res, radius), (i0, j0)


def test_the_per_map_sphere_surface_equals_the_window_dilation_where_it_is_sampled():
    board = make_board([("rocky", 0.7)], seed=3)
    rng = np.random.default_rng(1)
    h = np.array(board.heights)
    h[rng.random(h.shape) < 0.03] = np.nan  # scattered holes
    h[700:760, 200:260] = np.nan  # a large one
    holes = HeightMap(h, board.resolution, board.origin)
    r = LITTLEDOG.foot_radius
    for lo, hi in (((0.70, -0.20), (0.80, -0.10)), ((0.60, 0.20), (0.90, 0.31)),
                   ((0.0, -0.31), (0.05, -0.25))):  # ... and at the map's border
        lo, hi = np.array(lo), np.array(hi)
        cached = sphere_surface(holes, lo, hi, r)
        direct, (i0, j0) = _window_surface(holes, lo, hi, r)
        # every cell a sample inside [lo, hi] reads (with its bilinear neighbours)
        a = np.floor((lo - holes.origin) / holes.resolution).astype(int) - (i0, j0)
        b = np.ceil((hi - holes.origin) / holes.resolution).astype(int) + 2 - (i0, j0)
        a = np.maximum(a, 0)
        inner = direct[a[0]:b[0], a[1]:b[1]]
        known = np.isfinite(inner)
        assert np.array_equal(cached.known[a[0]:b[0], a[1]:b[1]] > 0, known)
        assert np.array_equal(cached.filled[a[0]:b[0], a[1]:b[1]][known], inner[known])


def test_the_expert_judges_a_candidate_set_again_exactly_as_the_first_time():
    from footfall.expert.synthetic import walking_expert

    board = make_board([("rocky", 0.7), ("steps", 0.7)], seed=500)
    expert = SyntheticExpert(walking_expert(0.02))
    state = nominal_state(board, (0.9, 0.0), 0.1, "LF")
    cand = reachable_footholds(board, state)
    first = expert.values(board, state, cand)
    first[:] = 0.0  # a caller changing its result changes nothing kept
    again = expert.values(board, state, cand)
    fresh = SyntheticExpert(walking_expert(0.02)).values(board, state, cand)
    assert np.array_equal(again, fresh)
    other = nominal_state(board, (0.9, 0.0), 0.3, "LF")  # another heading: judged anew
    assert not np.array_equal(expert.values(board, other, cand), fresh)


def test_a_riser_ahead_counts_nearer_more_and_behind_or_beside_not_at_all():
    """riser_ahead: the ball-centre surface's rise along the heading, weighted (1 - s / D)."""
    x, y = grid()
    r = LITTLEDOG.foot_radius
    rise = {}
    for name, wall in [("near", x > P[0] + r + 0.005), ("far", x > P[0] + 0.03),
                       ("beyond", x > P[0] + 0.04 + r), ("behind", x < P[0] - 0.01),
                       ("beside", y > P[1] + 0.01)]:
        rise[name] = judge(hmap(np.where(wall, 0.05, 0.0)))[1]["riser_ahead"]
    assert rise["near"] > rise["far"] > 0  # the ball centre meets the riser at s = face - r
    assert max(rise["beyond"], rise["behind"], rise["beside"]) < 1e-12
    # the ball centre meets the face 5 mm ahead and has risen 5 cm by s = 5 mm + r: weight >= 0.6
    assert 0.6 * 0.05 <= rise["near"] <= 0.05
    # weighted at 0 by default: the value does not change until w_riser is set
    steep = hmap(np.where(x > P[0] + r + 0.005, 0.05, 0.0))
    cand = np.array([[P[0], P[1], 0.0]])
    cautious = SyntheticExpert(ExpertConfig(w_riser=100.0))
    assert (EXPERT.values(steep, STATE, cand)[0] - cautious.values(steep, STATE, cand)[0]
            == pytest.approx(100.0 * rise["near"]))
