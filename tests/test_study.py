"""``footfall study``: whole reproductions per seed, resumable, sharing no board or run seed."""

import json
import shutil
from dataclasses import replace

import pytest

from cli_helpers import assert_user_error, run
from footfall.core.errors import FootfallError
from footfall.data.store import DemoStore
from footfall.experiments.reproduce import STORE_NAME, ReproduceConfig
from footfall.experiments.study import SEED_FILE, run_study, seed_folder, study_markdown
from footfall.expert.synthetic import ExpertConfig
from footfall.sim.episode import WalkConfig

TINY = ReproduceConfig(
    train_boards=((("rocky", 0.5),),), test_kinds=("rocky",), difficulties=(0.6,),
    calibration_boards=1, calibration_runs=1, confirmation_runs=1, test_boards=1, eval_runs=1,
    sweep_runs=1,
    rounds=2, target_demos=1000, corrections_per_run=None, library_size=30,
    training_candidates=20, cv=2, final_bandwidth_rms=0.004, offline_demos=4,
    walk=WalkConfig(max_steps=6), expert=ExpertConfig(),
    teacher="expert")  # as tests/test_reproduce.py's, smaller


def tiny(seed: int) -> ReproduceConfig:
    return replace(TINY, seed=seed)


def _keys(out, seed):
    with DemoStore(seed_folder(out, seed) / STORE_NAME) as store:
        return sorted(r["key"] for r in store.runs())


def _store_facts(out, seed):
    """Every run seed of a seed's reproduction, and the content of every board but the flat one
    (flat ground is the same whatever its seed)."""
    from footfall.core.heightmap import HeightMap

    with DemoStore(seed_folder(out, seed) / STORE_NAME) as store:
        runs = {store.run(r["id"]).seed for r in store.runs()}
    boards = {HeightMap.load(p).content_hash()
              for p in (seed_folder(out, seed) / "terrain").glob("*.npz") if p.stem != "flat"}
    board_seeds = json.loads((seed_folder(out, seed) / "results.json").read_text())["boards"]
    return runs, boards, {b["seed"] for b in board_seeds.values()}


def test_a_study_resumes_after_an_interruption_and_its_seeds_share_nothing(tmp_path):
    first: list[str] = []

    def stop_in_the_second_seed(key: str) -> None:
        first.append(key)
        if (seed_folder(tmp_path, 1) / STORE_NAME).exists() and len(first) > 3 and \
                key.startswith("eval/"):
            raise KeyboardInterrupt  # seed 0 done, seed 1 part-way through its evaluation

    with pytest.raises(KeyboardInterrupt):
        run_study(tmp_path, [0, 1], config_for=tiny, processes=1, log=lambda s: None,
                  on_run=stop_in_the_second_seed)
    assert not (tmp_path / "summary.json").exists()
    kept = _keys(tmp_path, 0) + _keys(tmp_path, 1)
    assert sorted(kept) == sorted(first)  # every finished run was kept, in its seed's store

    second: list[str] = []
    summary = run_study(tmp_path, [0, 1], config_for=tiny, processes=1, log=lambda s: None,
                        on_run=second.append)
    assert second and not set(second) & set(_keys(tmp_path, 0))  # seed 0 not walked again
    assert len(second) == len(set(second))
    assert sorted(first + second) == sorted(_keys(tmp_path, 0) + _keys(tmp_path, 1))  # once each
    # Each reproduction is whole: its report, and every method's test runs on every board.
    for seed in (0, 1):
        r = json.loads((seed_folder(tmp_path, seed) / "results.json").read_text())
        assert r["table2_pooled"]["both"]["runs"] == TINY.test_boards * TINY.eval_runs
    # No two seeds share a board or a run seed.
    facts0, facts1 = _store_facts(tmp_path, 0), _store_facts(tmp_path, 1)
    for a, b in zip(facts0, facts1):  # run seeds, board contents, board seeds
        assert a and b and not a & b

    saved = json.loads((tmp_path / "summary.json").read_text())
    assert saved["seeds"] == [0, 1] and len(saved["verdicts"]) == 3
    for v in summary["verdicts"]:  # pooled over both seeds' paired runs
        assert v["pairs"] == 2 * TINY.test_boards * TINY.eval_runs
        assert v["success_verdict"] in ("held", "reversed", "not separated")
        assert set(v["per_seed"]) == {0, 1}
    md = (tmp_path / "summary.md").read_text()
    assert md == study_markdown(summary)
    assert "templates + features above templates" in md and "Spread across the seeds" in md

    for v in summary["against_start"]:  # the teacher and the functions against the start
        assert v["pairs"] == 2 * TINY.test_boards * TINY.eval_runs
    assert "Against the hand-tuned reward" in md
    for seed in (0, 1):  # each seed's teacher on its test boards against its confirmation
        held = summary["per_seed"][seed]["calibration_held"]
        assert held["against"] == "confirmation" and held["calibration"][1] == 1
        assert held["test"][1] == TINY.test_boards * TINY.eval_runs
        assert f"{held['test'][0]} / {held['test'][1]} against" in md
    assert set(summary["fewer_templates_than_demonstrations"]) == {"templates", "both"}

    again: list[str] = []  # a third time: nothing left to walk
    run_study(tmp_path, [0, 1], config_for=tiny, processes=1, log=lambda s: None,
              on_run=again.append)
    assert again == []

    # A finished seed travels as its study-seed.json alone: gathered into another folder
    # (without its store), it is read, not walked, and summarises the same.
    gathered = tmp_path / "gathered"
    for seed in (0, 1):
        seed_folder(gathered, seed).mkdir(parents=True)
        shutil.copy(seed_folder(tmp_path, seed) / SEED_FILE, seed_folder(gathered, seed))
    elsewhere: list[str] = []
    read = run_study(gathered, [0, 1], config_for=tiny, processes=1, log=lambda s: None,
                     on_run=elsewhere.append)
    assert elsewhere == [] and not (seed_folder(gathered, 0) / STORE_NAME).exists()
    for key in ("verdicts", "against_start", "spread"):
        assert json.dumps(read[key], sort_keys=True) == json.dumps(
            json.loads(json.dumps(summary[key])), sort_keys=True)
    # one of other settings is refused in one line
    with pytest.raises(FootfallError, match="other settings"):
        run_study(gathered, [0, 1], config_for=lambda s: replace(tiny(s), eval_runs=2),
                  processes=1, log=lambda s: None)


def test_a_study_folder_with_other_settings_is_refused(tmp_path, capsys):
    (tmp_path / "config.json").write_text(json.dumps({"study of": "reproduce",
                                                      "settings": {"eval_runs": 99}}))
    assert_user_error(*run(capsys, "study", "--seeds", 0, 1, "--out", tmp_path)[::2],
                      "other settings")


def test_bad_seed_lists_are_one_line_errors(tmp_path, capsys):
    for args, match in ((("--seeds", 0, 0), "distinct seeds"), ((), "--seeds"),
                        (("--seeds", "x"), "'x'")):
        code, _, err = run(capsys, "study", *args, "--out", tmp_path / "s")
        assert_user_error(code, err, match)
