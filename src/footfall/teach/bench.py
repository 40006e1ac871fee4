"""Benchmark of the teaching page as a person uses it: how long they wait (``footfall bench
teach``).

``bench_teach`` walks a few runs with the hand-tuned reward on the controller test board,
stores each several times over (a store of at least 20 runs, none judged by the expert yet),
serves it, and drives the page in Chromium (Playwright, WebGL in software): it opens runs
never opened before, steps through each with the arrow key and labels steps by clicks in the
top view. The page itself times (``window.teach.state.timings``, milliseconds to the next
painted frame): the step view from its data's arrival when moving through a run, a label from
the server's answer, and a run's first step from the click that opened it (and, within that,
the drawing of the run's first step from its data's arrival). The baseline, in the same process: what
opening a run cost before the page stopped waiting for the expert -- the server's judgement
of a whole new run (``GET /api/runs/{id}``, judged), and the same request answered by a
second server start from the judgement kept in the store.
"""

from __future__ import annotations

import dataclasses
import statistics
import tempfile
import time
from pathlib import Path

import httpx

from footfall.data.store import DemoStore
from footfall.features.reward import default_reward
from footfall.sim.episode import Walk, WalkConfig
from footfall.teach.browser import FLAGS, require_browser
from footfall.teach.server import serving_in_thread
from footfall.teach.service import TeachService
from footfall.terrain import make_board

TEST_BOARD = ([("rocky", 0.7), ("steps", 0.7)], 500)  # the controller test board and its seed
SEARCH_RADIUS = 0.03  # [m] F within this of the gait's foothold, as the reproduction walks
TARGETS = {"step view": 300.0, "label": 200.0, "first step": 1000.0}  # [ms] at most: a step
# drawn when moving through a run, a label confirmed, a run's first step shown from the click
OPENING = "opening step view"  # [ms] the drawing of a run's first step: part of "first step"
VIEWPORT = {"width": 1400, "height": 900}


def bench_teach(walks: int = 2, copies: int = 10, runs: int = 3, steps: int = 10,
                labels: int = 8, seed: int = 5000) -> dict:
    """Time the teaching page on a store of ``walks`` x ``copies`` runs (see the module).

    ``runs`` runs are opened, ``steps`` arrow presses each, ``labels`` labels clicked in all.
    Returns the median and largest time of each kind [ms] with its target, and the baseline.
    """
    chromium = require_browser()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as folder:
        store = Path(folder) / "teach.sqlite"
        walk_seconds = _store_runs(store, walks, copies, seed)
        baseline = _baseline(store)
        with serving_in_thread(TeachService(store, labeler="bench")) as (_, _, address), \
                sync_playwright() as p:
            browser = p.chromium.launch(executable_path=chromium, args=FLAGS)
            try:
                page = browser.new_page(viewport=VIEWPORT)
                errors: list[str] = []
                page.on("pageerror", lambda e: errors.append(str(e)))
                t = time.perf_counter()
                page.goto(address)
                page.wait_for_selector("body[data-ready=yes]", timeout=60_000)
                ready = time.perf_counter() - t
                for row in range(2, 2 + runs):  # run 1's judgement is the baseline's
                    _walk_through(page, row, steps, labels // runs)
                timings = page.evaluate("window.teach.state.timings")
            finally:
                browser.close()
    kinds = {}
    for what, target in (*TARGETS.items(), (OPENING, None)):
        ms = [t["ms"] for t in timings if t["what"] == what]
        kinds[what] = {"n": len(ms), "median_ms": statistics.median(ms) if ms else None,
                       "max_ms": max(ms) if ms else None, "target_ms": target,
                       "median_within": None if target is None else
                       bool(ms) and statistics.median(ms) <= target,
                       "all_within": None if target is None else bool(ms) and max(ms) <= target}
    return {"store_runs": walks * copies, "walk_seconds": walk_seconds, "page_ready_s": ready,
            "timings": kinds, "baseline": baseline, "samples": timings, "page_errors": errors,
            "browser": "Chromium (headless, WebGL in SwiftShader)"}


def _store_runs(path: Path, walks: int, copies: int, seed: int) -> float:
    """Walk ``walks`` hand-tuned runs and store each ``copies`` times; returns the walking [s]."""
    board = make_board(*TEST_BOARD)
    base, reward = WalkConfig(), default_reward()
    config = dataclasses.replace(base, footstep=dataclasses.replace(base.footstep,
                                                                    search_radius=SEARCH_RADIUS))
    t = time.perf_counter()
    records = [Walk(board, lambda leg: reward, seed + i, config).run() for i in range(walks)]
    seconds = time.perf_counter() - t
    with DemoStore(path, create=True) as store:
        store.add_terrain(board)
        for c in range(copies):
            for i, record in enumerate(records):
                store.add_run(dataclasses.replace(record, key=f"bench/{i}/copy{c}", id=None))
    return seconds


def _baseline(store: Path) -> dict:
    """[s] the expert's judgement of run 1 (a new run) as the server's answer, unjudged and
    judged; then judged again by a new server, from the judgement kept in the store."""
    out = {}
    for name, judge in (("unjudged_s", False), ("judged_s", True), ("kept_s", True)):
        with serving_in_thread(TeachService(store)) as (base, token, _):
            with httpx.Client(base_url=base, headers={"Authorization": f"token {token}"},
                              timeout=600) as http:
                t = time.perf_counter()
                http.get("/api/runs/1", params={"judge": str(judge).lower()}).raise_for_status()
                out[name] = time.perf_counter() - t
    out["judged_over_unjudged"] = out["judged_s"] / out["unjudged_s"]
    out["judged_over_kept"] = out["judged_s"] / out["kept_s"]
    return out


def _walk_through(page, row: int, steps: int, labels: int) -> None:
    """Open the run in ``row`` of the list, step through it, label some steps by clicks."""
    page.click(f"#runs tbody tr:nth-child({row})")
    page.wait_for_function("window.teach.state.step !== null && "
                           f"window.teach.state.step.run === {row}", timeout=60_000)
    for i in range(steps):
        before = page.evaluate("window.teach.state.timings.length")
        page.keyboard.press("ArrowRight")
        page.wait_for_function(f"window.teach.state.timings.length > {before}", timeout=60_000)
        if i < labels:
            step = page.evaluate("window.teach.state.step")
            target = next(j for j in range(len(step["candidates"]))
                          if j != step["chosen"] and j % 5 == i % 5)
            at = page.evaluate(f"window.teach.pixelOf({target})")
            box = page.locator("#top").bounding_box()
            before = page.evaluate("window.teach.state.timings.length")
            page.mouse.click(box["x"] + at["x"], box["y"] + at["y"])
            page.wait_for_function(f"window.teach.state.timings.length > {before}",
                                   timeout=60_000)
    page.wait_for_function("!window.teach.state.judging", timeout=600_000)


def format_teach(r: dict) -> str:
    """The benchmark as text."""
    lines = [f"footfall bench teach: a store of {r['store_runs']} runs (walked in "
             f"{r['walk_seconds']:.0f} s), {r['browser']}; page ready in "
             f"{r['page_ready_s']:.2f} s"]
    for what, t in r["timings"].items():
        if not t["n"]:
            lines.append(f"  {what:<17} not measured")
            continue
        verdict = ("part of the first step" if t["target_ms"] is None else
                   f"target {t['target_ms']:.0f} ms: " + ("met" if t["all_within"] else
                                                          "median met" if t["median_within"]
                                                          else "NOT met"))
        lines.append(f"  {what:<17} median {t['median_ms']:6.0f} ms, largest {t['max_ms']:6.0f} "
                     f"ms over {t['n']:3d} ({verdict})")
    b = r["baseline"]
    lines.append(f"  baseline: a new run's steps judged by the expert before the page could show "
                 f"one {b['judged_s']:.2f} s, unjudged {b['unjudged_s']:.2f} s "
                 f"(x{b['judged_over_unjudged']:.1f}); judged again by a new server from the "
                 f"store {b['kept_s']:.2f} s (x{b['judged_over_kept']:.1f} faster)")
    if r["page_errors"]:
        lines.append(f"  page errors: {len(r['page_errors'])}: {r['page_errors'][0]}")
    return "\n".join(lines)
