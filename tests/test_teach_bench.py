"""``footfall bench teach`` end to end on a tiny store: every kind of wait is measured. Its own
module: the benchmark starts its own Playwright, which must not run beside the browser fixture
of the page tests (one synchronous Playwright per thread)."""

import os

import pytest

from footfall.teach.bench import bench_teach, format_teach
from footfall.teach.browser import chromium_path


@pytest.fixture(autouse=True)
def _chromium():
    if chromium_path() is None:
        if os.environ.get("FOOTFALL_REQUIRE_BROWSER"):
            pytest.fail("no Chromium: install Debian's chromium (make test does where it can)")
        pytest.skip("no Chromium installed (apt-get install chromium)")


def test_the_benchmark_times_every_kind_of_wait():
    # the figures are the benchmark's to print; here only that each kind was measured
    result = bench_teach(walks=1, copies=2, runs=1, steps=2, labels=1)
    assert result["store_runs"] == 2 and result["page_errors"] == []
    assert {k: t["n"] for k, t in result["timings"].items()} == \
        {"step view": 2, "label": 1, "first step": 1, "opening step view": 1}
    assert result["baseline"]["kept_s"] > 0 and result["baseline"]["judged_s"] > 0
    assert "target 300 ms" in format_teach(result)
