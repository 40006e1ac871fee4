"""The teaching server's HTTP API on a real socket: the token, every route, bad requests."""

import httpx
import numpy as np
import pytest

from footfall.data.store import DemoStore
from footfall.teach.client import TeachClient
from footfall.teach.server import MAX_BODY
from footfall.teach.service import TeachService
from teach_helpers import serving, store_of_runs


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    path = store_of_runs(tmp_path_factory.mktemp("teach") / "s.sqlite")
    with serving(TeachService(path)) as (base, token, page):
        with httpx.Client(base_url=base, headers={"Authorization": f"token {token}"}) as http:
            yield http, base, token, page, path


def test_every_request_needs_the_token(server):
    http, base, token, page, _ = server
    for path in ("/", "/api/runs", "/static/teach.js", "/api/runs/1", "/nothing"):
        bare = httpx.get(base + path)
        assert bare.status_code == 401 and "token" in bare.json()["detail"]
        wrong = httpx.get(base + path, headers={"Authorization": "token nope"})
        assert wrong.status_code == 403 and wrong.json() == {"detail": "wrong token"}
    assert httpx.post(base + "/api/labels", json={}).status_code == 401
    assert httpx.get(base + "/api/runs", params={"token": token}).status_code == 200
    with httpx.Client() as browser:  # the page's address sets a cookie the page's calls carry
        first = browser.get(page)
        assert first.status_code == 200 and "footfall teach" in first.text
        assert browser.get(base + "/api/runs").status_code == 200


def test_the_server_is_bound_to_loopback_by_default(server):
    assert server[1].startswith("http://127.0.0.1:")


def test_runs_steps_and_their_order(server):
    http, _, _, page, _ = server
    runs = http.get("/api/runs").json()
    assert [r["key"] for r in runs] == ["test/0", "test/1", "test/2"]
    assert runs[0]["steps"] == 8 and runs[0]["success"] is True and runs[0]["chooser"] == "default"
    run = http.get(f"/api/runs/{runs[0]['id']}").json()
    assert sorted(run["order"]) == list(range(8)) and len(run["steps"]) == 8
    step = http.get(f"/api/runs/{runs[0]['id']}/steps/2").json()
    assert len(step["candidates"]) == 6 and step["rewards"][1] is None  # -inf: invalid
    assert 0 <= step["chosen"] < 6 and 0 <= step["expert_best"] < 6
    assert set(step["robot"]["legs"]) == {"LF", "RF", "LH", "RH"} and len(step["state"]) == 20
    t = step["terrain"]
    assert len(t["heights"]) == len(t["x"]) and len(t["heights"][0]) == len(t["y"])
    with TeachClient(page) as client:  # the whole board, as footfall's height-map file
        board = client.terrain(step["terrain_hash"])
    assert board.shape == (120, 80) and np.isnan(board.heights[3, 5])


def test_a_click_labels_the_nearest_candidate_within_the_snap_radius(server):
    http, *_, path = server
    step = http.get("/api/runs/2/steps/1").json()
    i = next(i for i in (4, 3, 5) if i != step["chosen"])
    target = np.array(step["candidates"][i][:2])
    near = http.post("/api/labels", json={"run": 2, "step": 1, "verdict": "foothold",
                                          "point": (target + 0.002).tolist(), "labeler": "ada"})
    assert near.status_code == 201 and near.json()["chosen"] == i
    far = http.post("/api/labels", json={"run": 2, "step": 1, "verdict": "foothold",
                                         "point": [9.0, 9.0], "labeler": "ada"})
    assert far.status_code == 422 and "no candidate" in far.json()["detail"]
    with DemoStore(path, read_only=True) as store:
        (label,) = store.labels(run_id=2, k=1)
        assert label.chosen == i and store.demonstrations([label.demonstration_id])[0].chosen == i


def test_fine_undo_and_a_repeated_request(server):
    http, *_ = server
    body = {"run": 3, "step": 0, "verdict": "fine", "labeler": "bob", "request": "req-1"}
    first, again = http.post("/api/labels", json=body), http.post("/api/labels", json=body)
    assert (first.status_code, again.status_code) == (201, 200) and first.json() == again.json()
    other = http.delete(f"/api/labels/{first.json()['id']}", params={"labeler": "ada"})
    assert other.status_code == 404  # not ada's to undo
    mine = http.delete(f"/api/labels/{first.json()['id']}", params={"labeler": "bob"})
    assert mine.status_code == 200 and mine.json() == {"removed": first.json(), "restored": None}
    assert http.get("/api/runs/3/steps/0").json()["labels"] == []


def test_clicking_the_robots_own_choice_is_the_verdict_fine(server):
    http, *_, path = server
    step = http.get("/api/runs/1/steps/3").json()
    answer = http.post("/api/labels", json={"run": 1, "step": 3, "verdict": "foothold",
                                            "point": step["candidates"][step["chosen"]][:2],
                                            "labeler": "cy"})
    assert answer.status_code == 201 and answer.json()["verdict"] == "fine"
    assert answer.json()["demonstration_id"] is None
    with DemoStore(path, read_only=True) as store:
        assert store.demonstrations(source_prefix="human:run:1:step:3") == []


def test_undo_restores_the_label_it_replaced(server):
    http, *_ = server
    step = http.get("/api/runs/1/steps/4").json()
    other = next(i for i in range(6) if i != step["chosen"])
    first = http.post("/api/labels", json={"run": 1, "step": 4, "verdict": "foothold",
                                           "candidate": other, "labeler": "dee"}).json()
    fine = http.post("/api/labels", json={"run": 1, "step": 4, "verdict": "fine",
                                          "labeler": "dee"}).json()
    assert [lab["verdict"] for lab in http.get("/api/runs/1/steps/4/labels").json()["labels"]] \
        == ["fine"]
    undone = http.delete(f"/api/labels/{fine['id']}", params={"labeler": "dee"}).json()
    assert undone["removed"]["id"] == fine["id"] and undone["restored"]["id"] == first["id"]
    (back,) = http.get("/api/runs/1/steps/4/labels").json()["labels"]
    assert (back["verdict"], back["chosen"]) == ("foothold", other)
    assert http.get("/api/runs/1/steps/99/labels").status_code == 404


@pytest.mark.parametrize("method, path, kwargs, status, words", [
    ("get", "/api/runs/999", {}, 404, "run 999 is not in the store"),
    ("get", "/api/runs/1/steps/99", {}, 404, "has no step 99"),
    ("get", "/api/runs/x", {}, 422, "run_id"),
    ("get", "/api/runs/-1", {}, 422, "run_id"),
    ("get", "/api/terrains/abc", {}, 422, "terrain_hash"),
    ("get", "/api/terrains/" + "0" * 64, {}, 404, "not in the store"),
    ("post", "/api/labels", {"content": b"{\"run\": 1,",
                             "headers": {"Content-Type": "application/json"}}, 400,
     "malformed JSON"),
    ("post", "/api/labels", {"content": b"run=1"}, 400, "JSON object"),
    ("post", "/api/labels", {"json": [1, 2]}, 400, "JSON object"),
    ("post", "/api/labels", {"json": {"run": 1, "step": 0, "verdict": "foothold",
                                      "candidate": 6, "labeler": "a"}}, 422, "not in F"),
    ("post", "/api/labels", {"json": {"run": 1, "step": 0, "verdict": "foothold",
                                      "labeler": "a"}}, 422, "candidate index or a point"),
    ("post", "/api/labels", {"json": {"run": 1, "step": 0, "verdict": "fine"}}, 422,
     "labeler name"),
    ("post", "/api/labels", {"json": {"run": 1, "step": 0, "verdict": "fine", "labeler": "a",
                                      "extra": 1}}, 422, "extra"),
    ("post", "/api/labels", {"json": {"run": 1.5, "step": 0, "verdict": "fine",
                                      "labeler": "a"}}, 422, "run"),
    ("post", "/api/labels", {"json": {"run": 2**70, "step": 0, "verdict": "fine",
                                      "labeler": "a"}}, 422, "run"),
    ("post", "/api/labels", {"content": b"x" * (MAX_BODY + 1)}, 413, "over"),
    ("delete", "/api/labels/12345", {"params": {"labeler": "a"}}, 404, "label 12345"),
    ("get", "/static/../server.py", {}, 404, ""),
    ("get", "/api/nothing", {}, 404, ""),
    ("put", "/api/labels", {}, 405, ""),
])
def test_bad_requests_get_a_4xx_with_one_line_and_change_nothing(server, method, path, kwargs,
                                                                 status, words):
    http, *_, store_path = server
    with DemoStore(store_path, read_only=True) as store:
        before = (store.labels(), len(store))
    answer = http.request(method.upper(), path, **kwargs)
    assert answer.status_code == status, answer.text
    detail = answer.json()["detail"]
    assert words in detail and "\n" not in detail
    with DemoStore(store_path, read_only=True) as store:
        assert (store.labels(), len(store)) == before


def test_a_body_over_the_limit_without_a_declared_length_is_refused(server):
    http, *_ = server

    def chunks():
        for _ in range(MAX_BODY // 1024 + 2):
            yield b"x" * 1024

    answer = http.post("/api/labels", content=chunks())  # chunked: no Content-Length
    assert answer.status_code == 413


def test_a_websocket_upgrade_is_not_served(server):
    _, base, token, *_ = server
    answer = httpx.get(base + "/api/runs", params={"token": token},
                       headers={"Connection": "Upgrade", "Upgrade": "websocket",
                                "Sec-WebSocket-Version": "13",
                                "Sec-WebSocket-Key": "dGhlIHNhbXBsZSBub25jZQ=="})
    assert answer.status_code == 200 and isinstance(answer.json(), list)  # plain HTTP only


# ------------------------------------------------------------------ "never here" marks
def _marks(path):
    with DemoStore(path, read_only=True) as store:
        return [(m.run_id, m.k, m.labeler, m.candidate) for m in store.marks()]


def test_a_mark_by_candidate_or_point_is_in_the_step_and_its_poll_and_undoes(server):
    http, base, token, _, path = server
    assert httpx.post(base + "/api/marks", json={}).status_code == 401  # the token, as ever
    step = http.get("/api/runs/2/steps/5").json()
    assert step["marks"] == [] and step["snap_m"] == 0.03
    i, j = [c for c in range(6) if c != step["chosen"]][:2]
    body = {"run": 2, "step": 5, "candidate": i, "labeler": "ada", "request": "mark-1"}
    first, again = http.post("/api/marks", json=body), http.post("/api/marks", json=body)
    assert (first.status_code, again.status_code) == (201, 200) and first.json() == again.json()
    assert {k: first.json()[k] for k in ("run_id", "k", "labeler", "candidate", "request")} == \
        {"run_id": 2, "k": 5, "labeler": "ada", "candidate": i, "request": "mark-1"}
    near = (np.array(step["candidates"][j][:2]) + 0.002).tolist()
    by_point = http.post("/api/marks", json={"run": 2, "step": 5, "point": near, "labeler": "bob"})
    assert by_point.status_code == 201 and by_point.json()["candidate"] == j
    far = http.post("/api/marks", json={"run": 2, "step": 5, "point": [9.0, 9.0],
                                        "labeler": "bob"})
    assert far.status_code == 422 and "no candidate" in far.json()["detail"]
    shown = http.get("/api/runs/2/steps/5").json()["marks"]
    polled = http.get("/api/runs/2/steps/5/labels").json()
    assert shown == polled["marks"] == [first.json(), by_point.json()] and polled["labels"] == []
    assert _marks(path) == [(2, 5, "ada", i), (2, 5, "bob", j)]
    assert http.get("/api/counts").json()["marks"] == {"ada": 1, "bob": 1}
    mark_id = first.json()["id"]
    other = http.delete(f"/api/marks/{mark_id}", params={"labeler": "bob"})
    assert other.status_code == 404 and "of labeler 'bob'" in other.json()["detail"]
    mine = http.delete(f"/api/marks/{mark_id}", params={"labeler": "ada"})
    assert mine.status_code == 200 and mine.json() == {"removed": first.json()}
    assert _marks(path) == [(2, 5, "bob", j)]


def test_a_mark_on_ones_own_label_and_a_label_on_ones_mark_are_conflicts(server):
    http, *_, path = server
    step = http.get("/api/runs/2/steps/6").json()
    a, b = [c for c in range(6) if c != step["chosen"]][:2]
    http.post("/api/labels", json={"run": 2, "step": 6, "verdict": "foothold", "candidate": a,
                                   "labeler": "cy"})
    http.post("/api/marks", json={"run": 2, "step": 6, "candidate": b, "labeler": "cy"})
    with DemoStore(path, read_only=True) as store:
        before = (store.labels(), store.marks(), len(store))
    mark = http.post("/api/marks", json={"run": 2, "step": 6, "candidate": a, "labeler": "cy"})
    assert mark.status_code == 409 and "cy's own foothold label" in mark.json()["detail"]
    label = http.post("/api/labels", json={"run": 2, "step": 6, "verdict": "foothold",
                                           "candidate": b, "labeler": "cy"})
    assert label.status_code == 409 and "undo that mark first" in label.json()["detail"]
    with DemoStore(path, read_only=True) as store:
        assert (store.labels(), store.marks(), len(store)) == before
        (demo,) = store.demonstrations(source_prefix="human:run:2:step:6")
        assert np.flatnonzero(demo.refused).tolist() == [b]  # cy's mark joins cy's label


@pytest.mark.parametrize("method, path, kwargs, status, words", [
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "labeler": "a"}}, 422,
     "candidate index or a point"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "candidate": 6, "labeler": "a"}}, 422,
     "candidate 6 is not in F"),
    ("post", "/api/marks", {"json": {"run": 999, "step": 0, "candidate": 0, "labeler": "a"}},
     404, "run 999 is not in the store"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 99, "candidate": 0, "labeler": "a"}},
     404, "has no step 99"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "candidate": 0}}, 422,
     "labeler name"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "candidate": -1, "labeler": "a"}},
     422, "candidate"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "candidate": 0, "labeler": "a",
                                     "verdict": "foothold"}}, 422, "verdict"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "point": [0.1], "labeler": "a"}},
     422, "point"),
    ("post", "/api/marks", {"json": {"run": 2, "step": 0, "candidate": 0, "labeler": "a",
                                     "request": "a b"}}, 422, "request id"),
    ("post", "/api/marks", {"content": b"{\"run\": 2,",
                            "headers": {"Content-Type": "application/json"}}, 400,
     "malformed JSON"),
    ("post", "/api/marks", {"json": [2, 0, 0]}, 400, "JSON object"),
    ("post", "/api/marks", {"content": b"x" * (MAX_BODY + 1)}, 413, "over"),
    ("delete", "/api/marks/12345", {"params": {"labeler": "a"}}, 404, "mark 12345"),
    ("delete", "/api/marks/x", {"params": {"labeler": "a"}}, 422, "mark_id"),
    ("delete", "/api/marks/1", {}, 422, "labeler name"),
    ("put", "/api/marks", {}, 405, ""),
])
def test_bad_mark_requests_get_a_4xx_with_one_line_and_change_nothing(server, method, path,
                                                                      kwargs, status, words):
    http, *_, store_path = server
    with DemoStore(store_path, read_only=True) as store:
        before = (store.labels(), store.marks(), len(store))
    answer = http.request(method.upper(), path, **kwargs)
    assert answer.status_code == status, answer.text
    detail = answer.json()["detail"]
    assert words in detail and "\n" not in detail
    with DemoStore(store_path, read_only=True) as store:
        assert (store.labels(), store.marks(), len(store)) == before
