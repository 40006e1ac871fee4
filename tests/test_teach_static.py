"""The teaching page's files: everything it loads is in the package (no internet needed), the
vendored three.js is the release its notes name, and the pure functions behind the page."""

import hashlib
import re
from importlib import resources

import numpy as np
import pytest

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.robot import LITTLEDOG
from footfall.core.state import nominal_state
from footfall.teach.review import (
    FALL_LOOKBACK,
    nearest_candidate,
    review_order,
    robot_pose,
    steps_to_fall,
    terrain_window,
)

STATIC = resources.files("footfall.teach") / "static"


def test_the_page_loads_nothing_from_outside_the_package():
    scripts = sorted(p.name for p in STATIC.iterdir() if p.name.endswith(".js"))
    assert "teach.js" in scripts
    for name in ["index.html", "teach.css", *scripts]:
        text = (STATIC / name).read_text()
        assert not re.search(r"(https?:)?//[a-z0-9.-]+\.[a-z]{2,}/", text), name
    imports = {i for name in scripts for i in re.findall(r'from "([^"]+)"',
                                                         (STATIC / name).read_text())}
    local = {i for i in imports if i.startswith("./")}
    assert imports - local == {"three", "three/addons/OrbitControls.js"}
    assert {i.removeprefix("./") for i in local} <= set(scripts)
    html = (STATIC / "index.html").read_text()
    for target in re.findall(r'"(/static/[^"]+)"', html):  # the import map and the page's files
        if target.endswith("/"):
            continue
        assert (STATIC / target.removeprefix("/static/")).is_file(), target


def test_the_vendored_three_js_matches_its_notes():
    vendor = STATIC / "vendor" / "three"
    notes = (vendor / "VENDORED.md").read_text()
    rows = re.findall(r"\| `([^`]+)` \| `[^`]+` \| `([0-9a-f]{64})` \|", notes)
    assert {name for name, _ in rows} == {"three.module.js", "three.core.js",
                                          "OrbitControls.js", "LICENSE"}
    for name, digest in rows:
        assert hashlib.sha256((vendor / name).read_bytes()).hexdigest() == digest, name
    assert "MIT License" in (vendor / "LICENSE").read_text()


def test_a_click_labels_the_nearest_candidate_only_within_the_radius():
    f = np.array([[0.0, 0.0, 0.0], [0.02, 0.0, 0.01], [0.0, 0.03, 0.0]])
    assert nearest_candidate(f, [0.012, 0.001]) == 1
    assert nearest_candidate(f, [0.0, 0.02]) == 2
    assert nearest_candidate(f, [0.5, 0.5]) is None
    assert nearest_candidate(f, [0.5, 0.0], radius=1.0) == 1
    with pytest.raises(FootfallError):
        nearest_candidate(f, [np.nan, 0.0])


def test_the_terrain_window_samples_the_map_and_marks_no_data():
    h = np.arange(200 * 100, dtype=float).reshape(200, 100) * 1e-5
    h[50, 40] = np.nan
    hmap = HeightMap(h, 0.002, (0.0, -0.1))
    w = terrain_window(hmap, (0.1, -0.02), half=0.05, max_cells=30)
    x, y, heights = np.array(w["x"]), np.array(w["y"]), w["heights"]
    assert w["step"] == pytest.approx(0.004) and len(x) <= 30 and len(y) <= 30
    assert x[0] <= 0.05 + 1e-9 and x[-1] >= 0.15 - 0.004 and y[0] <= -0.07 + 1e-9
    i, j = np.rint(x[3] / 0.002).astype(int), np.rint((y[5] + 0.1) / 0.002).astype(int)
    assert heights[3][5] == h[i, j]
    edge = terrain_window(hmap, (0.0, 0.0), half=0.05, max_cells=100)  # leaves the map at x < 0
    assert edge["heights"][0][0] is None and edge["heights"][-1][-1] is not None
    holes = terrain_window(hmap, (0.1, -0.02), half=0.05, max_cells=200)
    assert None in holes["heights"][holes["x"].index(pytest.approx(0.1))]


def test_the_robot_pose_puts_the_hips_around_the_body():
    hmap = HeightMap(np.zeros((300, 200)), 0.002, (0.0, -0.2))
    state = nominal_state(hmap, (0.3, 0.0), 0.3, "LF")
    pose = robot_pose(state, LITTLEDOG)
    hips = np.array([pose["legs"][n]["hip"] for n in ("LF", "RF", "LH", "RH")])
    assert np.allclose(hips.mean(axis=0)[:2], state.body_position[:2], atol=1e-9)
    forward = hips[0] - hips[2]  # LF hip ahead of LH hip along the heading (yaw 0.3)
    assert np.degrees(np.arctan2(forward[1], forward[0])) == pytest.approx(np.degrees(0.3))
    assert pose["swing_leg"] == "LF" and pose["legs"]["RH"]["foot"] == state.feet[3].tolist()


def test_the_review_order_puts_big_slips_falls_and_disagreements_first():
    slips = np.array([0.001, 0.020, np.nan, 0.002, 0.001, 0.001])
    to_fall = steps_to_fall(6, fell=True)
    shortfall = np.array([0.0, 0.0, 30.0, 0.0, 0.5, 0.0])
    order = review_order(slips, to_fall, shortfall).tolist()
    assert sorted(order) == list(range(6))
    assert order[0] in (1, 2, 5)  # the biggest slip, the biggest disagreement, the fall
    assert set(order[:3]) == {1, 2, 5} and order[-1] == 0
    assert steps_to_fall(6, fell=False).tolist() == [-1] * 6
    assert steps_to_fall(6, True)[-FALL_LOOKBACK:].tolist() == list(range(FALL_LOOKBACK))[::-1]
    quiet = review_order(np.zeros(4), np.full(4, -1), np.zeros(4)).tolist()
    assert quiet == [0, 1, 2, 3]  # nothing stands out: as walked
