"""The "never here" mark on the teaching page, in Debian's Chromium (Playwright): X over a
candidate marks it, in the top view and in the 3D view; X again over my mark removes it; U
undoes my last action, a mark included; another labeler's page shows the mark without a reload;
the store holds each step; a mark joins my foothold label's demonstration as refused, and the
agreement panel counts it."""

import numpy as np

from footfall.data.store import DemoStore
from footfall.teach.service import TeachService
from teach_helpers import serving
from test_teach_browser import browser  # noqa: F401 (the Chromium fixture)
from test_teach_page import (  # noqa: F401 (the page's fixtures: a store of two runs, a page)
    _click_candidate,
    _message,
    _open_run,
    _other,
    open_page,
    store,
)


def _point_at(page, i, view="top"):
    """Move the mouse over candidate i in the top view or the 3D view."""
    if view == "top":
        at, box = page.evaluate(f"window.teach.pixelOf({i})"), page.locator("#top").bounding_box()
    else:
        at = page.evaluate(f"window.teach.screenOf3D({i})")
        box = page.locator("#view3d canvas").bounding_box()
    page.mouse.move(box["x"] + at["x"], box["y"] + at["y"])


def _marks(path):
    with DemoStore(path, read_only=True) as s:
        return [(m.run_id, m.k, m.labeler, m.candidate) for m in s.marks()]


def _never(page, kind):
    return [(m["index"], m["count"], m["names"]) for m in page.evaluate("window.teach.marks()")
            if m["kind"] == kind]


def test_x_marks_another_page_sees_it_and_u_undoes_it(store, open_page):  # noqa: F811
    with serving(TeachService(store)) as (_, _, address):
        ada = open_page(address, name="ada")
        bob = open_page(address, name="bob")
        step = _open_run(ada, order="run")
        _open_run(bob, order="run")
        target = _other(step)
        _point_at(ada, target)
        ada.keyboard.press("x")
        _message(ada, f"never here: candidate {target}")
        assert _marks(store) == [(1, 0, "ada", target)]
        assert _never(ada, "never_mine") == [(target, 1, ["ada"])]
        bob.wait_for_function("window.teach.marks().some((m) => m.kind === 'never_other')",
                              timeout=15_000)  # the poll: no reload
        assert _never(bob, "never_other") == [(target, 1, ["ada"])]
        assert "never here: ada" in bob.text_content("#labels")
        ada.keyboard.press("u")
        _message(ada, f"mark undone: candidate {target}")
        assert _marks(store) == [] and _never(ada, "never_mine") == []
        bob.wait_for_function("!window.teach.marks().some((m) => m.kind === 'never_other')",
                              timeout=15_000)


def test_x_in_the_3d_view_toggles_my_mark_and_u_walks_back(store, open_page):  # noqa: F811
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page, order="run")
        assert page.evaluate("window.teach.has3D"), "no WebGL in this Chromium"
        target = _other(step)
        _point_at(page, target, "3d")
        page.keyboard.press("x")
        _message(page, f"never here: candidate {target}")
        assert _marks(store) == [(1, 0, "ada", target)]
        _point_at(page, target, "3d")  # my mark's cross is over it now: it counts as the candidate
        page.keyboard.press("x")
        _message(page, f"mark removed: candidate {target}")
        assert _marks(store) == []
        page.keyboard.press("u")  # undoes the removal: marked again
        _message(page, f"mark back: never candidate {target}")
        assert _marks(store) == [(1, 0, "ada", target)]
        page.keyboard.press("u")  # and then the mark itself
        _message(page, f"mark undone: candidate {target}")
        assert _marks(store) == []


def test_a_mark_beside_my_label_is_its_refusal_and_never_my_label(store, open_page):  # noqa: F811
    with serving(TeachService(store)) as (_, _, address):
        page = open_page(address)
        step = _open_run(page, order="run")
        chosen = _other(step)
        refused = _other(step, chosen)
        _click_candidate(page, chosen)
        _message(page, f"saved: candidate {chosen}")
        _point_at(page, refused)
        page.keyboard.press("x")
        _message(page, f"never here: candidate {refused}")
        _point_at(page, chosen)
        page.keyboard.press("x")  # my own label: refused, one line, nothing stored
        _message(page, "undo that label before marking it")
        assert _marks(store) == [(1, 0, "ada", refused)]
        with DemoStore(store, read_only=True) as s:
            (demo,) = s.demonstrations(source_prefix="human")
        assert demo.chosen == chosen and np.flatnonzero(demo.refused).tolist() == [refused]
        kinds = [m["kind"] for m in page.evaluate("window.teach.marks()")
                 if m["index"] == refused]
        assert kinds[0] == "never_mine"  # outermost: it hides no other mark
        sizes = page.evaluate("window.teach.sizes")
        assert sizes["never_other"] > sizes["never_mine"] > sizes["other"]
        page.wait_for_function("document.getElementById('agreement').textContent.includes("
                               "\"ada's 'never here' marks: the synthetic expert also refuses\")",
                               timeout=15_000)  # the agreement panel counts the mark
        page.keyboard.press("u")  # my last action was the mark: it goes, the label stays
        _message(page, f"mark undone: candidate {refused}")
        assert _marks(store) == []
        with DemoStore(store, read_only=True) as s:
            assert [x.chosen for x in s.labels()] == [chosen]
        page.keyboard.press("?")
        assert "mark the candidate under the pointer" in page.text_content("#help")
