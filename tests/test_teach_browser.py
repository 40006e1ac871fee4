"""The teaching page in a real browser: Debian's Chromium driven by Playwright.

The page opens with its token, goes to a step, and a click on a candidate --
in the top view and in the 3D view -- lands in the store as that person's
label; the keyboard moves between steps, marks a choice fine and undoes it.
Without the token the page is refused. Where no Chromium is installed the
tests are skipped, except when FOOTFALL_REQUIRE_BROWSER is set (CI sets it):
then a missing browser fails the run.
"""

import os

import pytest

from footfall.data.store import DemoStore
from footfall.teach.browser import FLAGS, chromium_path
from footfall.teach.service import TeachService
from teach_helpers import serving, store_of_runs

CHROMIUM = chromium_path()


@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None:
        if os.environ.get("FOOTFALL_REQUIRE_BROWSER"):
            pytest.fail("no Chromium: install Debian's chromium (make test does where it can)")
        pytest.skip("no Chromium installed (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        yield b
        b.close()


@pytest.fixture
def teach(tmp_path, browser):
    path = store_of_runs(tmp_path / "s.sqlite", runs=2, steps=6)
    with serving(TeachService(path)) as (base, token, address):
        page = browser.new_page(viewport={"width": 1500, "height": 900})
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        yield page, base, address, path
        page.close()
        assert errors == []  # the page ran without a script error


def _open_first_run(page, address):
    page.goto(address)
    page.wait_for_selector("body[data-ready=yes]", timeout=30_000)
    page.fill("#labeler", "ada")
    page.click("#runs tbody tr:first-child")
    page.wait_for_function("window.teach.state.step !== null", timeout=30_000)
    return page.evaluate("window.teach.state.step")


def _other_candidate(step):
    return next(i for i in range(len(step["candidates"]))
                if i not in (step["chosen"], step["expert_best"]))


def _labels(path):
    with DemoStore(path, read_only=True) as store:
        return store.labels(), store.demonstrations(source_prefix="human")


def test_without_the_token_the_page_is_refused(teach):
    page, base, _, _ = teach
    answer = page.goto(base + "/")
    assert answer.status == 401 and "missing token" in page.content()
    assert page.goto(base + "/?token=wrong").status == 403


def test_a_click_in_the_top_view_labels_that_candidate(teach):
    page, _, address, path = teach
    step = _open_first_run(page, address)
    target = _other_candidate(step)
    at = page.evaluate(f"window.teach.pixelOf({target})")
    box = page.locator("#top").bounding_box()
    page.mouse.click(box["x"] + at["x"], box["y"] + at["y"])
    page.wait_for_function("document.getElementById('message').textContent.startsWith('saved')")
    (label,), (demo,) = _labels(path)
    assert (label.run_id, label.k, label.labeler, label.chosen) == \
        (step["run"], step["k"], "ada", target)
    assert demo.id == label.demonstration_id and demo.source == f"human:run:{step['run']}:" \
        f"step:{step['k']}"


def test_a_click_in_the_3d_view_labels_that_candidate(teach):
    page, _, address, path = teach
    step = _open_first_run(page, address)
    assert page.evaluate("window.teach.has3D"), "no WebGL in this Chromium"
    target = _other_candidate(step)
    at = page.evaluate(f"window.teach.screenOf3D({target})")
    box = page.locator("#view3d canvas").bounding_box()
    page.mouse.click(box["x"] + at["x"], box["y"] + at["y"])
    page.wait_for_function("document.getElementById('message').textContent.startsWith('saved')")
    (label,), _ = _labels(path)
    assert (label.run_id, label.k, label.chosen) == (step["run"], step["k"], target)


def test_the_keyboard_steps_marks_fine_and_undoes(teach):
    page, _, address, path = teach
    first = _open_first_run(page, address)
    page.keyboard.press("ArrowRight")
    page.wait_for_function(f"window.teach.state.step.k !== {first['k']}")
    second = page.evaluate("window.teach.state.step")
    page.keyboard.press("f")
    page.wait_for_function("document.getElementById('message').textContent.includes('fine')")
    (label,), demos = _labels(path)
    assert (label.k, label.verdict, label.chosen, demos) == \
        (second["k"], "fine", second["chosen"], [])
    page.keyboard.press("u")
    page.wait_for_function("document.getElementById('message').textContent === 'label removed'")
    assert _labels(path) == ([], [])
    page.keyboard.press("ArrowLeft")
    page.wait_for_function(f"window.teach.state.step.k === {first['k']}")


def test_a_step_the_rollout_teacher_labelled_shows_what_followed_each_candidate(tmp_path,
                                                                               browser):
    """Where the store holds the rollout teacher's label of a step, the page lists what followed
    each candidate it tried in its branches -- here: fell; there: slid 22 mm -- and which it
    taught; a step without one shows nothing of the kind."""
    import numpy as np

    from footfall.data.demonstration import Demonstration
    from footfall.expert.corrections import source_of
    from footfall.sim.rollout import BranchOutcome, RolloutVerdict, verdict_record

    path = store_of_runs(tmp_path / "s.sqlite", runs=1, steps=4)
    with DemoStore(path) as store:
        run = store.run(store.runs()[0]["id"])
        step = run.steps[0]
        other = next(i for i in range(len(step.candidates)) if i != step.chosen)
        outcomes = (BranchOutcome(step.chosen, 0, "fall: trunk tilted", True, False, 0.0, 0.0,
                                  0.01, -0.99),
                    BranchOutcome(other, 0, "step limit", False, False, 0.022, 0.0, 0.06, -0.01))
        verdict = RolloutVerdict(0, step.chosen, np.array([step.chosen, other]),
                                 np.array([-0.99, -0.01]), outcomes, other)
        store.add_demonstrations([Demonstration(
            run.terrain_hash, step.state, step.candidates, other, source=source_of(run.key, 0),
            expert={"class": "footfall.sim.rollout.RolloutVerdict",
                    "verdict": verdict_record(verdict)})])
    with serving(TeachService(path)) as (_, _, address):
        page = browser.new_page(viewport={"width": 1500, "height": 900})
        _open_first_run(page, address)
        page.select_option("#order", "run")
        page.wait_for_function("window.teach.state.step.k === 0")
        page.wait_for_selector("#branches:not([hidden])")
        text = page.inner_text("#branches")
        assert f"candidate {step.chosen} (the robot's choice): fell" in text
        assert f"candidate {other} (taught): slid 22 mm" in text
        page.keyboard.press("ArrowRight")
        page.wait_for_function("window.teach.state.step.k === 1")
        assert page.is_hidden("#branches")
        page.close()
