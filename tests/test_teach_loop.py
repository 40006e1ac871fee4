"""The paper's loop through the teaching interface, with no person: walk, label over HTTP (the
synthetic expert answering through the API as a person's page would), learn from the human
source, walk again with what was learned."""

from footfall.data.store import DemoStore
from footfall.expert.synthetic import SyntheticExpert, walking_expert
from footfall.features.reward import default_reward
from footfall.learning.model import FootholdModel
from footfall.learning.train import learn_from_store
from footfall.sim.episode import WalkConfig, walk
from footfall.teach.client import ScriptedLabeler, TeachClient
from footfall.teach.service import TeachService
from footfall.terrain.modules import make_board
from teach_helpers import serving


def test_walk_label_over_http_learn_and_walk_again(tmp_path):
    board = make_board([("rocky", 0.6)], seed=11)  # a small board: one rocky module
    config = WalkConfig()
    reward = default_reward()
    store = tmp_path / "loop.sqlite"
    with DemoStore(store, create=True) as s:
        for seed in (1, 2):
            s.add_run(walk(board, lambda leg: reward, seed, config), terrains=[board])
    expert = SyntheticExpert(walking_expert(config.footstep.lead))
    with serving(TeachService(store)) as (_, _, address), TeachClient(address) as client:
        runs = client.runs()
        assert {r["chooser"] for r in runs} == {"hand-tuned default"}  # the run names its reward
        labeler = ScriptedLabeler(client, expert, name="scripted expert", seed=0)
        done = [labeler.label_run(r["id"]) for r in runs]
    assert [d.footholds + d.fine for d in done] == [r["steps"] for r in runs]  # every step
    footholds = sum(d.footholds for d in done)
    assert footholds >= 6, done  # the hand-tuned reward is not the expert: it has corrections
    with DemoStore(store, read_only=True) as s:
        labels = s.labels()
        human = s.demonstrations(source_prefix="human")
        assert s.summary()["labels"]["by_labeler"] == {
            "scripted expert": {"foothold": footholds, "fine": len(labels) - footholds}}
    assert len(human) == footholds
    assert all(d.expert == {"kind": "human", "labeler": "scripted expert"} for d in human)
    learned = learn_from_store(store, tmp_path / "human.npz", "terrain", source="human", cv=3)
    assert learned.demonstrations == footholds
    model = FootholdModel.load(tmp_path / "human.npz")
    again = walk(board, model.reward_for, 3, config)  # the robot walks with what it was taught
    assert len(again.steps) > 0 and "reason" in again.result
    assert again.settings.get("judge") is None
