"""The student's walking learning curve: a reproduction's loop continued in a folder of its own,
each variant learned at each point from exactly its labels, walked paired with the references."""

import json
from dataclasses import replace

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.executors import LocalPool
from footfall.experiments.reproduce import STORE_NAME, correction_rounds
from footfall.experiments.runs import Runner
from footfall.experiments.student_curve import (
    CURVE_STORE,
    StudentCurveConfig,
    parse_variant,
    run_student_curve,
)
from footfall.experiments.workspace import open_workspace
from test_reproduce import DAGGER

ONE_ROUND = replace(DAGGER, rounds=1)  # a reproduction's loop of one round: nothing learned yet
CURVE = StudentCurveConfig(rounds=2, points=(1, 2),
                           variants=("both:graded+veto", "terrain:choice"),
                           boards=(((("rocky", 0.5),), 9001, 1),))


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    out = tmp_path_factory.mktemp("source")
    ws = open_workspace(out, ONE_ROUND)
    with DemoStore(out / STORE_NAME, create=True) as store:
        correction_rounds(ws, Runner(store, ws.by_hash, LocalPool(1), None, lambda s: None))
    return out


def _count(path):
    with DemoStore(path, read_only=True) as store:
        return len(store.runs()), len(store.demonstrations())


def test_a_loop_continued_learns_each_variant_at_each_point_and_walks_them_paired(source,
                                                                                  tmp_path):
    before = _count(source / STORE_NAME)
    lines: list[str] = []
    summary = run_student_curve([source], tmp_path / "curve", CURVE, processes=1,
                                log=lines.append)
    assert _count(source / STORE_NAME) == before  # the source is read, never written
    draw = tmp_path / "curve" / "draw0"
    runs, labels = _count(draw / STORE_NAME)
    assert runs == before[0] + 2 and labels > before[1]  # round 1: two more runs labelled
    # the loop's own student after one round is its round model; the rest learned once each
    models = sorted(p.name for p in (draw / "models").glob("*.npz"))
    assert models == ["curve-both-graded-veto-p2.npz", "curve-terrain-choice-p1.npz",
                      "curve-terrain-choice-p2.npz", "round1.npz"]
    graded = summary["variants"]["both:graded+veto"]["points"]
    assert graded["1"]["labels"] == [before[1]] and graded["2"]["labels"] == [labels]
    # every method walked the one board's one run seed: the references and four functions
    with DemoStore(tmp_path / "curve" / CURVE_STORE, read_only=True) as store:
        keys = sorted(r["key"] for r in store.runs())
    assert keys == sorted(["walk/teacher/rocky0.5-9001/s1000", "walk/hand-tuned/rocky0.5-9001/s1000"]
                          + [f"walk/draw0/{v}/p{p}/rocky0.5-9001/s1000"
                             for v in ("both-graded-veto", "terrain-choice") for p in (1, 2)])
    for v in summary["variants"].values():
        assert v["flattens_at"] in (1, 2)
        for row in v["points"].values():
            assert row["runs"] == 1 and row["against_hand_tuned"]["pairs"] == 1
    assert (tmp_path / "curve" / "curve.md").read_text().startswith("# The student's walking")
    assert (tmp_path / "curve" / "curve.png").stat().st_size > 0
    # run again: nothing walked or learned twice
    mtimes = {p.name: p.stat().st_mtime_ns for p in (draw / "models").glob("*.npz")}
    again = run_student_curve([source], tmp_path / "curve", CURVE, processes=1,
                              log=lambda s: None)
    assert json.dumps(again, sort_keys=True) == json.dumps(summary, sort_keys=True)  # NaN too
    assert {p.name: p.stat().st_mtime_ns for p in (draw / "models").glob("*.npz")} == mtimes
    assert _count(draw / STORE_NAME)[0] == runs


def test_bad_curves_are_refused_in_one_line(source, tmp_path, capsys):
    with pytest.raises(FootfallError, match="FEATURES:SUPERVISION"):
        parse_variant("both:grades")
    with pytest.raises(FootfallError, match="variants"):
        replace(CURVE, variants=("both",))
    with pytest.raises(FootfallError, match="rounds >= 3"):
        replace(CURVE, points=(1, 3))
    with pytest.raises(FootfallError, match="given twice"):
        run_student_curve([source, source], tmp_path / "twice", CURVE, processes=1)
    worst_only = tmp_path / "worst"
    open_workspace(worst_only, replace(ONE_ROUND, every_step=False))
    with pytest.raises(FootfallError, match="not every step"):
        run_student_curve([worst_only], tmp_path / "c", CURVE, processes=1)
    code, _, err = run(capsys, "student-curve", source, "--out", tmp_path / "x", "--variant",
                       "both:nothing")
    assert_user_error(code, err, "FEATURES:SUPERVISION")
    code, _, err = run(capsys, "student-curve", source, "--out", tmp_path / "x", "--points",
                       "1,two")
    assert_user_error(code, err, "--points")
