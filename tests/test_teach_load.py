"""The teaching server under load and under fuzzing, over real HTTP.

8 labelers x 1 000 labels at once: every label lands once (none lost, none
doubled, a retried request not doubled either), no server error. 1 200 bad
requests of every kind: each answered 4xx, none 5xx, the store unchanged.
"""

import json
from concurrent.futures import ThreadPoolExecutor

import httpx
import numpy as np

from footfall.data.store import DemoStore
from footfall.teach.server import MAX_BODY
from footfall.teach.service import TeachService
from teach_helpers import serving, store_of_runs

LABELERS, LABELS, RUNS, STEPS = 8, 1000, 25, 40  # RUNS * STEPS = LABELS distinct steps
RETRY_EVERY = 50  # each labeler sends every 50th label twice, as a client retrying would


def _labeler(base, token, name, seed):
    """Label every step once (and some twice, same request id); return the answers' codes and
    what was sent."""
    rng = np.random.default_rng(seed)
    codes, sent = [], {}
    with httpx.Client(base_url=base, headers={"Authorization": f"token {token}"},
                      timeout=60) as http:
        for i in range(LABELS):
            run, k = 1 + i // STEPS, i % STEPS
            body = {"run": run, "step": k, "verdict": "foothold", "labeler": name,
                    "candidate": int(rng.integers(0, 6)), "request": f"{name}-{i}"}
            codes.append(http.post("/api/labels", json=body).status_code)
            if i % RETRY_EVERY == 0:
                codes.append(-http.post("/api/labels", json=body).status_code)  # a retry
            sent[(run, k)] = body["candidate"]
    return codes, sent


def test_eight_concurrent_labelers_lose_and_double_nothing(tmp_path):
    path = store_of_runs(tmp_path / "s.sqlite", runs=RUNS, steps=STEPS)
    names = [f"labeler{i}" for i in range(LABELERS)]
    with serving(TeachService(path)) as (base, token, _):
        with ThreadPoolExecutor(LABELERS) as pool:
            results = list(pool.map(_labeler, [base] * LABELERS, [token] * LABELERS, names,
                                    range(LABELERS)))
    for codes, _ in results:
        assert codes.count(201) == LABELS  # every label stored ...
        assert codes.count(-200) == LABELS // RETRY_EVERY  # ... and every retry answered "had it"
        assert not [c for c in codes if abs(c) >= 500]
    with DemoStore(path, read_only=True) as store:
        labels = store.labels()
        demos = {d.id: d for d in store.demonstrations(source_prefix="human")}
    assert len(labels) == LABELERS * LABELS
    # the robot's own choice labelled is the verdict "fine", which makes no demonstration
    assert len(demos) == sum(x.verdict == "foothold" for x in labels) > LABELS
    assert len({(x.labeler, x.run_id, x.k) for x in labels}) == len(labels)
    for name, (_, sent) in zip(names, results):
        mine = {(x.run_id, x.k): x for x in labels if x.labeler == name}
        assert {key: x.chosen for key, x in mine.items()} == sent
        assert all(demos[x.demonstration_id].chosen == x.chosen for x in mine.values()
                   if x.verdict == "foothold")


def _bad_requests(rng, token, n):
    """``n`` requests that must each be refused: (method, path, headers, body bytes)."""
    auth = {"Authorization": f"token {token}", "Content-Type": "application/json"}
    good = {"run": 1, "step": 0, "verdict": "foothold", "candidate": 1, "labeler": "fuzz"}
    wrong_values = {
        "run": [0, 99, 10**6, -1, 2**63, 1.5, "1", True, None, [], {}],
        "step": [40, 999, -1, 2**64, 0.5, "0", False, None, [0]],
        "verdict": ["", "FOOTHOLD", "good", 1, None, ["fine"]],
        "candidate": [6, 7, 10**9, -1, 2**63, 1.0, "1", True, [1], {}],
        "labeler": ["", " ", "a\nb", "a\x00b", "x" * 65, "<script>", 5, [], {}],
        "point": [[9.0, 9.0], [0.0], [0, 0, 0], ["a", "b"], "0,0", [None, 1]],
        "request": ["", "a b", "x" * 65, 7, "é", ["r"]],
        "extra": [1, "x", None],
    }
    out = []
    for i in range(n):
        kind = i % 8
        body = dict(good)
        if kind == 0:  # a field with a wrong value
            field = list(wrong_values)[rng.integers(len(wrong_values))]
            choices = wrong_values[field]
            body[field] = choices[rng.integers(len(choices))]
            if field == "point":
                del body["candidate"]
            out.append(("POST", "/api/labels", auth, json.dumps(body).encode()))
        elif kind == 1:  # a required field missing
            del body[["run", "step", "verdict", "labeler"][rng.integers(4)]]
            if "labeler" not in body and "run" in body:
                body["verdict"] = "foothold"
            out.append(("POST", "/api/labels", auth, json.dumps(body).encode()))
        elif kind == 2:  # malformed JSON: a valid body cut short, or random bytes
            raw = json.dumps(body).encode()
            cut = raw[:int(rng.integers(0, len(raw) - 1))] if rng.random() < 0.5 else \
                rng.integers(0, 256, int(rng.integers(1, 64)), dtype=np.uint8).tobytes()
            out.append(("POST", "/api/labels", auth, cut))
        elif kind == 3:  # no token, a wrong one, or a token in the wrong place
            headers = [{}, {"Authorization": "token " + token[:-1]},
                       {"Authorization": token}, {"Cookie": "footfall-teach-token=nope"}
                       ][rng.integers(4)]
            out.append(("POST", "/api/labels", headers | {"Content-Type": "application/json"},
                        json.dumps(body).encode()))
        elif kind == 4:  # too big
            size = MAX_BODY + 1 + int(rng.integers(0, 4 * MAX_BODY))
            out.append(("POST", "/api/labels", auth, b" " * size))
        elif kind == 5:  # unknown runs, steps and labels; paths outside the API
            paths = [f"/api/runs/{rng.integers(100, 10**9)}", f"/api/runs/1/steps/{40 + i}",
                     "/api/runs/abc", "/api/runs/1/steps/-3", f"/api/terrains/{'f' * 64}",
                     "/static/../server.py", "/static/%2e%2e/service.py", "/etc/passwd",
                     "/api/labels/1/x", f"/api/nothing/{i}"]
            out.append(("GET", paths[rng.integers(len(paths))], auth, b""))
        elif kind == 6:  # undo a label that is not there or not one's own
            out.append(("DELETE", f"/api/labels/{[1, 2, 10**6][rng.integers(3)]}"
                        f"?labeler=intruder{i}", auth, b""))
        else:  # methods the API does not have
            method = ["PUT", "PATCH", "DELETE", "POST"][rng.integers(4)]
            path = ["/api/runs", "/api/runs/1", "/api/labels", "/"][rng.integers(4)]
            if (method, path) == ("POST", "/api/labels"):
                path = "/api/runs"
            if (method, path) == ("DELETE", "/api/labels"):
                path = "/api/runs/1"
            out.append((method, path, auth, b""))
    return out


def _snapshot(path):
    with DemoStore(path, read_only=True) as store:
        return ([x.to_dict() for x in store.labels()],
                [(d.id, d.source, d.chosen) for d in store.demonstrations()])


def test_a_thousand_bad_requests_get_4xx_and_change_nothing(tmp_path):
    path = store_of_runs(tmp_path / "s.sqlite", runs=2, steps=40)
    with DemoStore(path) as store:  # labels someone gave before: an intruder cannot undo them
        store.add_label(1, 0, "ada", "foothold", 2)
        store.add_label(1, 1, "ada", "fine")
    before = _snapshot(path)
    with serving(TeachService(path)) as (base, token, _):
        requests = _bad_requests(np.random.default_rng(0), token, 1200)
        codes = []
        with httpx.Client(base_url=base, timeout=60) as http:
            for method, url, headers, body in requests:
                answer = http.request(method, url, headers=headers, content=body)
                codes.append(answer.status_code)
                assert 400 <= answer.status_code < 500, (method, url, body[:200], answer.text)
                assert "\n" not in answer.json()["detail"]
    assert len(codes) >= 1000 and not [c for c in codes if c >= 500]
    assert len(set(codes)) >= 6  # 400, 401, 403, 404, 405, 413, 422: every kind was reached
    assert _snapshot(path) == before
