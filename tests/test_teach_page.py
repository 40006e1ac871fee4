"""The teaching page as a labelling tool, in Debian's Chromium (Playwright): the bugs a person
labelling for an hour met (each test failed before its fix), the labeller's tools (queue,
zoom and pan, reset view, hotkey help, live updates, undo history, marks that never hide each
other), a run that opens before the expert has judged it, and a layout that fits from
800 x 600 up. Timings are not asserted here: ``footfall bench teach`` measures them.
"""

import dataclasses
import threading
import time

import pytest

from footfall.data.store import DemoStore
from footfall.experiments.batch import summarise
from footfall.teach.service import TeachService
from teach_helpers import serving, store_of_runs
from test_runlog import _run
from test_store import terrain
from test_teach_browser import browser  # noqa: F401 (the Chromium fixture)

STEPS = 8
WIDE, SMALL = {"width": 1400, "height": 900}, {"width": 800, "height": 600}


class SlowSteps(TeachService):
    """A server whose steps answer after a delay [s] per step, and whose judgement of a run
    waits until ``judged`` is set (to see what the page shows meanwhile)."""

    def __init__(self, path, delays=None, hold_judgement=False, **kwargs):
        super().__init__(path, **kwargs)
        self.delays = delays or {}
        self.judged = threading.Event()
        if not hold_judgement:
            self.judged.set()

    def step(self, run_id, k, judge=True):
        time.sleep(self.delays.get(k, 0.0))
        return super().step(run_id, k, judge)

    def run(self, run_id, judge=True):
        if judge:
            self.judged.wait(30)
        return super().run(run_id, judge)


@pytest.fixture
def store(tmp_path):
    return store_of_runs(tmp_path / "s.sqlite", runs=2, steps=STEPS)


@pytest.fixture
def open_page(browser):  # noqa: F811
    pages = []

    def new(address, viewport=WIDE, name="ada"):
        page = browser.new_page(viewport=viewport)
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(address)
        page.wait_for_selector("body[data-ready=yes]", timeout=30_000)
        if name is not None:
            page.fill("#labeler", name)
            page.dispatch_event("#labeler", "change")
        pages.append((page, errors))
        return page

    yield new
    for page, errors in pages:
        page.close()
        assert errors == []  # no script error on any page


def _open_run(page, row=1, order=None):
    """Open a run (``order="run"``: then show its steps as walked, from step 0)."""
    page.click(f"#runs tbody tr:nth-child({row})")
    page.wait_for_function("window.teach.state.step !== null", timeout=30_000)
    if order is not None:
        page.select_option("#order", order)
        page.wait_for_function("window.teach.state.step.k === 0 && window.teach.state.order[1]"
                               " === 1", timeout=30_000)
    return page.evaluate("window.teach.state.step")


def _judged(page):
    page.wait_for_function("!window.teach.state.judging && "
                           "window.teach.marks().some((m) => m.kind === 'expert')",
                           timeout=30_000)


def _click_candidate(page, i):
    at = page.evaluate(f"window.teach.pixelOf({i})")
    box = page.locator("#top").bounding_box()
    page.mouse.click(box["x"] + at["x"], box["y"] + at["y"])


def _message(page, text):
    page.wait_for_function(f"document.getElementById('message').textContent.includes({text!r})",
                           timeout=15_000)


def _other(step, *avoid):
    return next(i for i in range(len(step["candidates"]))
                if i not in (step["chosen"], *avoid))


def _labels(path):
    with DemoStore(path, read_only=True) as s:
        return s.labels()


# ---------------------------------------------------------------------- the bugs
def test_fast_arrows_show_the_step_at_the_position_reached(store, open_page):
    # steps 1-4 answer late, step 5 at once: answers arrive out of order
    with serving(SlowSteps(store, delays={1: 0.9, 2: 0.7, 3: 0.5, 4: 0.3})) as (_, _, address):
        page = open_page(address)
        _open_run(page, order="run")
        for _ in range(5):
            page.keyboard.press("ArrowRight")
        page.wait_for_function("window.teach.state.step.k === 5")
        page.wait_for_timeout(1500)  # every late answer has arrived by now
        assert page.evaluate("window.teach.state.step.k") == 5
        assert page.text_content("#step-title") == f"run 1, step 5 of {STEPS} (6 / {STEPS} in " \
                                                   "this order)"


def test_a_name_typed_in_the_page_outlives_a_reload_and_signs_the_labels(store, open_page):
    with serving(TeachService(store, labeler="ada")) as (_, _, address):
        page = open_page(address, name="grace")
        page.reload()
        page.wait_for_selector("body[data-ready=yes]")
        assert page.input_value("#labeler") == "grace"
        step = _open_run(page)
        _click_candidate(page, _other(step))
        _message(page, "saved")
    assert [label.labeler for label in _labels(store)] == ["grace"]


def test_a_stopped_server_is_said_so_and_nothing_hangs(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page)
    # the server has stopped; the page is still open
    page.keyboard.press("ArrowRight")
    _message(page, "not answering")
    assert page.is_visible("#offline-flag")
    page.click("#runs tbody tr:nth-child(2)")
    _message(page, "not answering")
    assert "opening" not in page.text_content("#message")
    _click_candidate(page, _other(step))
    _message(page, "not answering")
    assert "Failed to fetch" not in page.text_content("#message")


def test_undo_brings_back_the_label_a_new_one_replaced(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page)
        first = _other(step)
        _click_candidate(page, first)
        _message(page, f"saved: candidate {first}")
        second = _other(step, first)
        _click_candidate(page, second)
        _message(page, f"saved: candidate {second}")
        page.keyboard.press("f")
        _message(page, "fine")
        page.keyboard.press("u")
        _message(page, f"label undone: back to candidate {second}")
        assert [(x.verdict, x.chosen) for x in _labels(store)] == [("foothold", second)]
        page.keyboard.press("u")
        _message(page, f"label undone: back to candidate {first}")
        page.keyboard.press("u")
        page.wait_for_function("document.getElementById('message').textContent === "
                               "'label removed'")
        assert _labels(store) == []
        history = page.locator("#history li").all_text_contents()
        assert history[0].endswith(": undone") and f"candidate {first}" in history[-1]


def test_clicking_the_robots_own_choice_marks_it_fine(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page)
        _click_candidate(page, step["chosen"])
        _message(page, "saved: the robot's choice was fine")
    (label,) = _labels(store)
    assert (label.verdict, label.demonstration_id) == ("fine", None)


def test_a_failed_run_is_named_as_walk_many_names_it(tmp_path, open_page):
    hm = terrain()
    run = _run(hm, n_steps=STEPS, key="fell/0")
    fell = dataclasses.replace(run, result={
        "success": False, "reason": "fall: trunk tilted", "distance": 0.4,
        "explanation": {"cause": "stance foot slipped"}})
    path = tmp_path / "fell.sqlite"
    with DemoStore(path, create=True) as s:
        s.add_run(fell, terrains=[hm])
    assert summarise([fell]).causes == {"stance foot slipped": 1}  # what walk-many prints
    with serving(TeachService(path)) as (_, _, address):
        page = open_page(address)
        assert page.locator("#runs tbody td.fail").text_content() == "stance foot slipped"
        _open_run(page, order="run")
        assert "(stance foot slipped)" in page.text_content("#facts")


def test_a_click_on_a_run_survives_a_refresh_of_the_list(store, open_page):
    # the list refreshes after a label, a poll or a new name: a press and its release on a row
    # with a refresh between them still open that run
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        box = page.locator("#runs tbody tr:nth-child(2)").bounding_box()
        page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        page.mouse.down()
        page.dispatch_event("#labeler", "change")  # a new name: the list is fetched again
        page.wait_for_timeout(800)
        page.mouse.up()
        page.wait_for_function("window.teach.state.step !== null && "
                               "window.teach.state.step.run === 2", timeout=15_000)


# ---------------------------------------------------------------- the labeller's tools
def test_the_queue_counts_my_steps_and_finds_the_next_unlabelled(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page, order="run")
        assert page.text_content("#queue") == f"0 of {STEPS} steps labelled by ada"
        page.keyboard.press("f")
        _message(page, "fine")
        assert page.text_content("#queue") == f"1 of {STEPS} steps labelled by ada"
        page.keyboard.press("ArrowLeft")  # already first: stays
        page.keyboard.press("n")
        page.wait_for_function(f"window.teach.state.step.k !== {step['k']}")
        assert page.evaluate("window.teach.state.step.labels") == []
        page.wait_for_function("document.querySelector('#runs tbody tr td:last-child')"
                               f".textContent === '1 / {STEPS}'", timeout=15_000)


def test_a_label_given_while_the_expert_judges_is_not_lost_when_its_verdicts_arrive(
        store, open_page):
    """The judged run is read when judging begins; a label given before it arrives stays
    counted (it once went back to 0 until the next refresh)."""
    import re

    held = []
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        # the judged run read by the server at once, its answer held back
        page.route(re.compile(r"/api/runs/\d+$"), lambda route: held.append((route, route.fetch())))
        _open_run(page, order="run")
        page.wait_for_function("window.teach.state.judging", timeout=15_000)
        page.keyboard.press("f")
        _message(page, "fine")
        assert page.text_content("#queue") == f"1 of {STEPS} steps labelled by ada"
        page.wait_for_timeout(100)  # the route handler runs while Playwright waits
        assert len(held) == 1
        route, answer = held[0]
        route.fulfill(response=answer)  # now the verdicts arrive, read before the label
        _judged(page)
        assert page.text_content("#queue") == f"1 of {STEPS} steps labelled by ada"


def test_the_top_view_zooms_pans_and_still_labels_what_is_clicked(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page)
        box = page.locator("#top").bounding_box()
        centre = (box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        page.mouse.move(*centre)
        page.mouse.wheel(0, -300)
        page.wait_for_function("window.teach.topView().zoom > 1")
        before = page.evaluate("window.teach.topView()")
        page.mouse.move(*centre)
        page.mouse.down()
        page.mouse.move(centre[0] + 40, centre[1] + 25, steps=5)
        page.mouse.up()
        after = page.evaluate("window.teach.topView()")
        assert after["cx"] < before["cx"] and after["cy"] > before["cy"]  # dragged right, down
        assert _labels(store) == []  # a drag is not a click
        page.keyboard.press("r")
        assert page.evaluate("window.teach.topView().zoom") == 1
        page.mouse.move(*centre)
        page.mouse.wheel(0, -200)
        page.wait_for_function("window.teach.topView().zoom > 1")
        target = _other(step)
        at = page.evaluate(f"window.teach.pixelOf({target})")
        if 0 <= at["x"] <= box["width"] and 0 <= at["y"] <= box["height"]:
            _click_candidate(page, target)
            _message(page, f"saved: candidate {target}")
            assert [x.chosen for x in _labels(store)] == [target]


def test_the_3d_camera_stays_above_the_ground_and_resets(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        _open_run(page)
        assert page.evaluate("window.teach.has3D"), "no WebGL in this Chromium"
        home = page.evaluate("window.teach.camera()")
        box = page.locator("#view3d canvas").bounding_box()
        x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        page.mouse.move(x, y)
        page.mouse.down()
        page.mouse.move(x + 30, y - 600, steps=20)  # drag up: orbit the camera under the target
        page.mouse.up()
        moved = page.evaluate("window.teach.camera()")
        assert moved["position"] != home["position"]
        assert moved["position"][2] > moved["target"][2]  # above the point it looks at ...
        ground = page.evaluate("window.teach.groundUnderCamera()")
        assert ground is None or moved["position"][2] > ground  # ... and above the ground
        page.click("#reset-view")
        back = page.evaluate("window.teach.camera()")
        assert back["position"] == pytest.approx(home["position"])
        assert back["target"] == pytest.approx(home["target"])


def test_question_mark_shows_the_keys(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        _open_run(page)
        assert not page.is_visible("#help")
        page.keyboard.press("?")
        assert page.is_visible("#help") and "undo my last action" in page.text_content("#help")
        assert "never here" in page.text_content("#help")  # X: the "never here" mark
        page.keyboard.press("Escape")
        page.wait_for_function("!document.getElementById('help').open")


def test_anothers_label_appears_without_a_reload(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        ada = open_page(address, name="ada")
        bob = open_page(address, name="bob")
        step = _open_run(ada, order="run")
        _open_run(bob, order="run")
        target = _other(step)
        _click_candidate(bob, target)
        _message(bob, "saved")
        ada.wait_for_function("document.getElementById('labels').textContent.includes('bob')",
                              timeout=15_000)
        marks = ada.evaluate("window.teach.marks()")
        assert {"index": target, "kind": "other", "count": 1, "names": ["bob"]} in marks


def test_marks_on_one_candidate_nest_and_count_identical_labels(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        pages = [open_page(address, name=n) for n in ("ada", "bob", "cy")]
        step = _open_run(pages[0], order="run")
        _judged(pages[0])
        target = _other(step)
        for page in pages[1:]:
            _open_run(page, order="run")
            _click_candidate(page, target)
            _message(page, "saved")
        _click_candidate(pages[0], target)
        _message(pages[0], "saved")
        pages[0].wait_for_function("window.teach.marks().some((m) => m.kind === 'other' && "
                                   "m.count === 2)", timeout=15_000)
        marks = pages[0].evaluate("window.teach.marks()")
        on_target = [m for m in marks if m["index"] == target]
        assert [m["kind"] for m in on_target] == ["other", "mine"]
        assert on_target[0]["names"] == ["bob", "cy"]
        sizes = pages[0].evaluate("window.teach.sizes")
        kinds = [m["kind"] for m in marks]  # drawn in this order: each inside the one before
        assert kinds == sorted(kinds, key=["other", "mine", "chosen", "expert"].index)
        assert sizes["other"] > sizes["mine"] > sizes["chosen"] > sizes["expert"]


# ------------------------------------------------------------- opening and loading
def test_a_run_opens_at_its_first_step_before_the_expert_has_judged_it(store, open_page):
    service = SlowSteps(store, hold_judgement=True)
    with serving(service) as (_, _, address):
        page = open_page(address)
        _open_run(page)
        page.wait_for_selector("#judging", state="visible", timeout=5_000)
        assert "the expert is judging" in page.text_content("#facts")
        assert not any(m["kind"] == "expert" for m in page.evaluate("window.teach.marks()"))
        service.judged.set()
        _judged(page)
        assert not page.is_visible("#judging")


def test_a_slow_step_shows_the_page_is_loading(store, open_page):
    with serving(SlowSteps(store, delays={k: 1.5 for k in range(1, STEPS)})) as (_, _, address):
        page = open_page(address)
        _open_run(page, order="run")
        page.wait_for_selector("#busy", state="hidden", timeout=5_000)
        page.keyboard.press("ArrowRight")
        page.wait_for_selector("#busy", state="visible", timeout=5_000)
        page.wait_for_function("window.teach.state.step.k === 1", timeout=15_000)
        page.wait_for_selector("#busy", state="hidden", timeout=5_000)


def test_the_agreement_figures_are_on_the_page(store, open_page):
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        _open_run(page)
        page.keyboard.press("f")
        _message(page, "fine")
        page.click("#info details:nth-of-type(2) summary")
        page.wait_for_function("document.getElementById('agreement').textContent.includes("
                               "'ada agrees with the synthetic expert on 1 of 1 steps')"
                               " || document.getElementById('agreement').textContent.includes("
                               "'ada agrees with the synthetic expert on 0 of 1 steps')",
                               timeout=15_000)


# -------------------------------------------------------------------------- layout
LAID_OUT = ["header h1", "#labeler", "#help-button", "#runs-toggle", "#prev", "#next",
            "#step-title", "#order", "#fine", "#skip", "#unlabelled", "#undo", "#reset-view",
            "#view3d", "#top", "#info"]


def _inside(page, selector, within=None):
    box = page.locator(selector).first.bounding_box()
    view = page.viewport_size
    outer = within or {"x": 0, "y": 0, "width": view["width"], "height": view["height"]}
    assert box is not None and box["width"] > 0 and box["height"] > 0, selector
    assert box["x"] >= outer["x"] - 0.5 and box["y"] >= outer["y"] - 0.5, (selector, box)
    assert box["x"] + box["width"] <= outer["x"] + outer["width"] + 0.5, (selector, box)
    assert box["y"] + box["height"] <= outer["y"] + outer["height"] + 0.5, (selector, box)


@pytest.mark.parametrize("viewport", [SMALL, WIDE, {"width": 2560, "height": 1440}],
                         ids=["800x600", "1400x900", "2560x1440"])
def test_nothing_is_cut_off(tmp_path, open_page, viewport):
    path = store_of_runs(tmp_path / "many.sqlite", runs=24, steps=4)
    with serving(TeachService(path)) as (_, _, address):
        page = open_page(address, viewport=viewport)
        for i in range(page.locator("#runs th").count()):  # the runs list alone: every column
            _inside(page, f"#runs th >> nth={i}")
        _open_run(page)
        for selector in LAID_OUT:
            _inside(page, selector)
        top = page.locator("#top").bounding_box()
        assert abs(top["width"] - top["height"]) <= 1  # the top view stays square
        if viewport is SMALL:  # the runs list folds away beside a run; it opens over it
            assert not page.is_visible("#runs-panel")
            page.click("#runs-toggle")
        panel = page.locator("#runs-panel").bounding_box()
        _inside(page, "#runs-panel")
        for i in range(page.locator("#runs th").count()):
            if page.locator("#runs th").nth(i).is_visible():
                _inside(page, f"#runs th >> nth={i}", panel)

