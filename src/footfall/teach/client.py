"""Talking to ``footfall teach`` over HTTP: a client of its API, and a scripted labeler.

:class:`ScriptedLabeler` closes the paper's loop through the interface
without a person: it reads a run's steps from the server exactly as the page
does, lets the synthetic expert judge each one (on the board it fetched from
the server) and posts its verdict -- the expert's foothold where the robot's
choice falls short by more than a margin, "fine" otherwise -- as a person's
labels would be posted. Walk, label over HTTP, learn from source ``human``,
walk again: the path from a click to a better robot, tested end to end.
"""

from __future__ import annotations

import secrets
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import numpy as np

from footfall.core.errors import FootfallError
from footfall.core.heightmap import HeightMap
from footfall.core.state import RobotState
from footfall.expert.corrections import DEFAULT_MARGIN
from footfall.expert.protocol import Expert

TIMEOUT = 60.0  # [s] per request: judging a long run's steps the first time takes seconds


class TeachClient:
    """The teaching server's API, for scripts.

    Parameters
    ----------
    url : str
        The address ``footfall teach`` printed (``http://127.0.0.1:PORT/?token=...``),
        or its base with ``token`` given.
    token : str, optional
        The access token, if ``url`` does not hold it.
    """

    def __init__(self, url: str, token: str | None = None, timeout: float = TIMEOUT) -> None:
        parsed = httpx.URL(url)
        token = token or parsed.params.get("token")
        if not token:
            raise FootfallError("the teaching server's token is needed (in the URL or given)")
        self.http = httpx.Client(base_url=f"{parsed.scheme}://{parsed.netloc.decode()}",
                                 headers={"Authorization": f"token {token}"}, timeout=timeout)

    def close(self) -> None:
        """Close the connection."""
        self.http.close()

    def __enter__(self) -> TeachClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _get(self, path: str) -> Any:
        return _answer(self.http.get(path))

    def runs(self) -> list[dict[str, Any]]:
        """Every run, a line each."""
        return self._get("/api/runs")

    def run(self, run_id: int, judge: bool = True) -> dict[str, Any]:
        """A run's steps and the order worth a look (``judge=False``: without the server's
        synthetic expert, by slips and falls only)."""
        return self._get(f"/api/runs/{run_id}?judge={'true' if judge else 'false'}")

    def step(self, run_id: int, k: int, judge: bool = True) -> dict[str, Any]:
        """Step ``k`` of a run as the page draws it (``judge=False``: without the expert's best)."""
        return self._get(f"/api/runs/{run_id}/steps/{k}?judge={'true' if judge else 'false'}")

    def terrain(self, terrain_hash: str) -> HeightMap:
        """A whole board (sent as footfall's height-map file)."""
        response = self.http.get(f"/api/terrains/{terrain_hash}")
        if not response.is_success:
            _answer(response)
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "board.npz"
            path.write_bytes(response.content)
            hmap = HeightMap.load(path)
        if hmap.content_hash() != terrain_hash:
            raise FootfallError(f"the teaching server sent another board than {terrain_hash}")
        return hmap

    def label(self, run_id: int, k: int, verdict: str, labeler: str,
              candidate: int | None = None, point: tuple[float, float] | None = None,
              request: str | None = None) -> dict[str, Any]:
        """Post a label (a fresh request id unless one is given: a retry should reuse it)."""
        body = {"run": run_id, "step": k, "verdict": verdict, "labeler": labeler,
                "request": request or secrets.token_hex(12)}
        if candidate is not None:
            body["candidate"] = int(candidate)
        if point is not None:
            body["point"] = [float(point[0]), float(point[1])]
        return _answer(self.http.post("/api/labels", json=body))

    def undo(self, label_id: int, labeler: str) -> dict[str, Any]:
        """Remove one's own label."""
        return _answer(self.http.delete(f"/api/labels/{label_id}", params={"labeler": labeler}))

    def mark(self, run_id: int, k: int, labeler: str, candidate: int | None = None,
             point: tuple[float, float] | None = None, request: str | None = None
             ) -> dict[str, Any]:
        """Mark a candidate (or the one nearest ``point``, x, y [m]) "never here" (a fresh
        request id unless one is given: a retry should reuse it)."""
        body = {"run": run_id, "step": k, "labeler": labeler,
                "request": request or secrets.token_hex(12)}
        if candidate is not None:
            body["candidate"] = int(candidate)
        if point is not None:
            body["point"] = [float(point[0]), float(point[1])]
        return _answer(self.http.post("/api/marks", json=body))

    def unmark(self, mark_id: int, labeler: str) -> dict[str, Any]:
        """Remove one's own "never here" mark."""
        return _answer(self.http.delete(f"/api/marks/{mark_id}", params={"labeler": labeler}))


def _answer(response: httpx.Response) -> Any:
    if response.is_success:
        return response.json()
    try:
        detail = response.json().get("detail", response.text)
    except ValueError:
        detail = response.text
    raise FootfallError(f"the teaching server answered {response.status_code}: {detail}")


@dataclass(frozen=True)
class LabelledRun:
    """What a scripted labeler did with one run."""

    run: int  # the run's id
    footholds: int  # steps labelled with the expert's foothold
    fine: int  # steps where the robot's choice was within the margin


class ScriptedLabeler:
    """The synthetic expert labelling runs through the teaching server's HTTP API.

    Parameters
    ----------
    client : TeachClient
    expert : Expert
        Judges each step (e.g. ``SyntheticExpert(walking_expert(lead))``).
    name : str
        The labeler name its labels carry.
    margin : float
        [value units] a choice this much worse than the expert's best is
        labelled with the expert's foothold (as the synthetic corrections do).
    seed : int
        The expert's imperfection (``expert.choose``), step by step in order.
    noise : float
        [0-1] the share of steps labelled carelessly: a candidate of F drawn
        uniformly instead of the expert's verdict (a person of known noise,
        to test the agreement figures against).
    """

    def __init__(self, client: TeachClient, expert: Expert, name: str = "scripted expert",
                 margin: float = DEFAULT_MARGIN, seed: int = 0, noise: float = 0.0) -> None:
        if not 0.0 <= noise <= 1.0:
            raise FootfallError(f"a labeler's noise is a share in [0, 1], got {noise!r}")
        self.client, self.expert, self.name, self.margin = client, expert, name, float(margin)
        self.noise = float(noise)
        self.rng = np.random.default_rng(seed)
        self._maps: dict[str, HeightMap] = {}

    def label_run(self, run_id: int) -> LabelledRun:
        """Judge and label every step of a run, in the order the page shows first."""
        overview = self.client.run(run_id, judge=False)  # it judges the steps itself
        footholds = fine = 0
        for k in overview["order"]:
            s = self.client.step(run_id, k, judge=False)
            if s["terrain_hash"] not in self._maps:
                self._maps[s["terrain_hash"]] = self.client.terrain(s["terrain_hash"])
            hmap = self._maps[s["terrain_hash"]]
            state = RobotState.from_vector(np.array(s["state"], dtype=np.float64), s["leg"])
            candidates = np.array(s["candidates"], dtype=np.float64)
            if self.noise > 0 and self.rng.random() < self.noise:  # careless: any candidate
                self.client.label(run_id, k, "foothold", self.name,
                                  candidate=int(self.rng.integers(len(candidates))))
                footholds += 1
                continue
            values = np.asarray(self.expert.values(hmap, state, candidates), dtype=np.float64)
            if values.max() - values[s["chosen"]] > self.margin and len(candidates) >= 2:
                choice = int(self.expert.choose(hmap, state, candidates, self.rng))
                self.client.label(run_id, k, "foothold", self.name, candidate=choice)
                footholds += 1
            else:
                self.client.label(run_id, k, "fine", self.name)
                fine += 1
        return LabelledRun(run_id, footholds, fine)
