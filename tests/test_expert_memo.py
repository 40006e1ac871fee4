"""The expert remembers each foothold's terrain terms: the same bits as computing them afresh.

A foothold's terrain terms are sampled from the whole map's surface, so they are a function of
the foothold alone -- not of the other candidates judged with it -- and a memo of them per map
and heading changes no value.
"""

from __future__ import annotations

import numpy as np

from footfall.core.robot import LEG_NAMES
from footfall.core.state import nominal_state
from footfall.expert.memo import RowMemo
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.features.candidates import reachable_footholds
from footfall.terrain import make_board


def test_a_memo_computes_each_new_row_once_and_returns_what_it_computed() -> None:
    calls: list[int] = []

    def compute(rows: np.ndarray) -> dict[str, np.ndarray]:
        calls.append(rows.shape[0])
        return {"sum": rows.sum(axis=1), "first": rows[:, 0].copy()}

    memo = RowMemo(compute, capacity=6)
    a = np.array([[1.0, 2.0], [3.0, 4.0], [1.0, 2.0]])  # a row repeated within the call
    out = memo(a)
    assert calls == [2] and len(memo) == 2
    assert np.array_equal(out["sum"], [3.0, 7.0, 3.0])
    out["sum"][:] = -1  # the caller's copy: the memo keeps its own
    b = np.array([[3.0, 4.0], [5.0, 6.0], [np.nan, 0.0]])
    out = memo(b)
    assert calls == [2, 2] and np.array_equal(out["sum"], [7.0, 11.0, np.nan], equal_nan=True)
    assert np.array_equal(memo(a)["sum"], [3.0, 7.0, 3.0]) and calls == [2, 2]
    # Full: it starts again, computing every row of the call that overflowed it.
    c = np.arange(10.0).reshape(5, 2)
    assert np.array_equal(memo(c)["first"], c[:, 0]) and calls == [2, 2, 5] and len(memo) == 5


def test_the_experts_values_do_not_depend_on_the_other_candidates_or_on_what_it_remembers() -> None:
    board = make_board([("rocky", 0.7), ("steps", 0.7)], seed=500)
    expert = walking_expert(0.02)
    for i, x in enumerate((0.8, 1.05, 1.3)):
        state = nominal_state(board, (x, 0.01), 0.0, LEG_NAMES[i])
        f = reachable_footholds(board, state)
        half = f.shape[0] // 2
        together = SyntheticExpert(expert).values(board, state, f)
        alone = SyntheticExpert(expert)  # a fresh expert: each half judged without the other
        apart = np.concatenate([alone.values(board, state, f[:half]),
                                SyntheticExpert(expert).values(board, state, f[half:])])
        assert np.array_equal(together, apart)
        # Remembered: the same set again, and a set overlapping the one it judged.
        assert np.array_equal(alone.values(board, state, f), together)
        assert np.array_equal(alone.values(board, state, f[::-1]), together[::-1])


def test_an_expert_keeps_a_bounded_number_of_footholds_over_all_maps(monkeypatch) -> None:
    from footfall.expert import synthetic

    monkeypatch.setattr(synthetic, "MEMO_ROWS", 50)
    expert = SyntheticExpert(walking_expert(0.02))
    boards = [make_board([("rocky", 0.5)], seed=s) for s in (1, 2)]
    first = None
    for board in boards:
        state = nominal_state(board, (0.8, 0.0), 0.0, "LF")
        f = reachable_footholds(board, state)[:40]  # two maps of them: past the bound
        values = expert.values(board, state, f)
        first = values if first is None else first
        remembered = sum(len(m) for per in expert._memos.values() for m in per.values())
        assert remembered == 40 and len(expert._memos) == 1  # only the memo in use
    state = nominal_state(boards[0], (0.8, 0.0), 0.0, "LF")
    again = expert.values(boards[0], state, reachable_footholds(boards[0], state)[:40])
    assert np.array_equal(again, first)  # computed afresh: the same bits
