"""The teaching interface's web server: ``footfall teach STORE`` (paper §II-B, Fig. 3a).

A FastAPI application served by uvicorn, bound to 127.0.0.1 unless the user
asks otherwise, on a free port, behind a random access token (as Jupyter
does): the address printed holds ``?token=...``; opening it sets a cookie
that the page's later requests carry, and a request with neither the token
(query, ``Authorization: token ...`` header) nor the cookie is refused (401,
403 for a wrong one). Nothing is served but the package's static files and
the API:

========================================  =============================================
``GET  /``                                the page
``GET  /api/session``                     the default labeler, the store
``GET  /api/runs``                        every run, a line each
``GET  /api/runs/{run}[?judge=false]``    a run's steps and the order worth a look
``GET  /api/runs/{run}/steps/{k}``        a step: terrain, robot, F, rewards, labels,
                                          marks (``?judge=false``: without the expert's
                                          best)
``GET  /api/terrains/{hash}``              a whole board, as a height-map file (.npz)
``GET  /api/runs/{run}/steps/{k}/labels`` the step's labels and marks now: ``{labels,
                                          marks}`` (the page polls them)
``POST /api/labels``                      a label: ``{run, step, verdict, candidate |
                                          point, labeler?, request?}`` (201; 200 for
                                          a repeated request or the same verdict again)
``DELETE /api/labels/{id}?labeler=NAME``  undo one's own label: ``{removed, restored}``
                                          (the label it had replaced comes back)
``POST /api/marks``                       a "never here" mark: ``{run, step, candidate |
                                          point, labeler?, request?}`` (201; 200 for a
                                          repeated request or a candidate marked already;
                                          409 on one's own label's candidate)
``DELETE /api/marks/{id}?labeler=NAME``   remove one's own mark: ``{removed}``
``GET  /api/counts``                      labels and marks by labeler, demonstrations by
                                          source
``GET  /api/agreement``                   each labeler's labels and marks against the
                                          synthetic expert and against each other
========================================  =============================================

Every bad request -- unknown run or step, a foothold not in F, malformed
JSON, a missing or wrong token, a body over :data:`MAX_BODY` bytes, a mark
on one's own label -- is a 4xx answer ``{"detail": "one line"}`` and changes
nothing.
"""

from __future__ import annotations

import contextlib
import secrets
import socket
import threading
import time
from collections.abc import Iterator
from importlib import resources
from typing import Annotated, Any, Literal
from urllib.parse import parse_qs

from fastapi import FastAPI, Path, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt, StrictStr
from starlette.exceptions import HTTPException as StarletteHTTPException

from footfall.core.errors import FootfallError, NotFound, one_line
from footfall.data.label_queries import LabelConflict
from footfall.data.mark_queries import MarkConflict
from footfall.teach.service import TeachService

MAX_BODY = 16 * 1024  # [bytes] the largest request body accepted (a label is ~200 bytes)
MAX_ID = 2**63 - 1  # the largest row id or index SQLite keeps
Id = Annotated[int, Field(ge=0, le=MAX_ID)]  # a run id, step number, label id or index
COOKIE = "footfall-teach-token"
LOOPBACK = "127.0.0.1"
STATIC = resources.files("footfall.teach") / "static"


class LabelRequest(BaseModel):
    """A label as the page (or a scripted labeler) posts it."""

    model_config = ConfigDict(extra="forbid")

    run: Annotated[StrictInt, Field(ge=0, le=MAX_ID)]  # the run's id
    step: Annotated[StrictInt, Field(ge=0, le=MAX_ID)]  # the step number k
    verdict: Literal["foothold", "fine"]
    candidate: Annotated[StrictInt, Field(ge=0, le=MAX_ID)] | None = None  # index in the step's F
    point: Annotated[list[StrictFloat | StrictInt], Field(min_length=2, max_length=2)] | None \
        = None  # [m] x, y of a click on the terrain: the nearest candidate of F
    labeler: StrictStr | None = None  # who labels (default: the server's --labeler)
    request: StrictStr | None = None  # the client's id of this request (a retry is not doubled)


class MarkRequest(BaseModel):
    """A "never here" mark as the page (or a script) posts it."""

    model_config = ConfigDict(extra="forbid")

    run: Annotated[StrictInt, Field(ge=0, le=MAX_ID)]  # the run's id
    step: Annotated[StrictInt, Field(ge=0, le=MAX_ID)]  # the step number k
    candidate: Annotated[StrictInt, Field(ge=0, le=MAX_ID)] | None = None  # index in the step's F
    point: Annotated[list[StrictFloat | StrictInt], Field(min_length=2, max_length=2)] | None \
        = None  # [m] x, y on the terrain: the nearest candidate of F (within SNAP_RADIUS)
    labeler: StrictStr | None = None  # who marks (default: the server's --labeler)
    request: StrictStr | None = None  # the client's id of this request (a retry is not doubled)


def create_app(service: TeachService, token: str) -> Guard:
    """The ASGI application serving ``service`` to holders of ``token`` (behind :class:`Guard`)."""
    app = FastAPI(title="footfall teach", docs_url=None, redoc_url=None, openapi_url=None)
    _answer_errors(app)

    @app.get("/", include_in_schema=False)
    def page(token_query: Annotated[str | None, Query(alias="token")] = None) -> Response:
        response = FileResponse(str(STATIC / "index.html"), media_type="text/html")
        if token_query is not None:  # remember the token: the page's later requests carry it
            response.set_cookie(COOKIE, token, httponly=True, samesite="strict")
        response.headers["Cache-Control"] = "no-store"
        return response

    @app.get("/favicon.ico", include_in_schema=False)
    def favicon() -> Response:
        return Response(status_code=204)

    @app.get("/api/session")
    def session() -> dict[str, Any]:
        return {"labeler": service.labeler, "store": service.path.name}

    @app.get("/api/runs")
    def runs() -> list[dict[str, Any]]:
        return service.runs()

    @app.get("/api/runs/{run_id}")
    def run(run_id: Id, judge: bool = True) -> dict[str, Any]:
        return service.run(run_id, judge)

    @app.get("/api/runs/{run_id}/steps/{k}")
    def step(run_id: Id, k: Id, judge: bool = True) -> dict[str, Any]:
        return service.step(run_id, k, judge)

    @app.get("/api/runs/{run_id}/steps/{k}/labels")
    def step_labels(run_id: Id, k: Id) -> dict[str, list[dict[str, Any]]]:
        return service.step_labels(run_id, k)

    @app.get("/api/agreement")
    def agreement() -> dict[str, Any]:
        return service.agreement()

    @app.get("/api/terrains/{terrain_hash}")
    def terrain(terrain_hash: Annotated[str, Path(pattern="^[0-9a-f]{64}$")]) -> Response:
        return Response(service.terrain_file(terrain_hash),
                        media_type="application/octet-stream")

    @app.post("/api/labels")
    def label(body: LabelRequest) -> JSONResponse:
        stored, new = service.label(body.run, body.step, body.verdict, body.labeler,
                                    body.candidate, body.point, body.request)
        return JSONResponse(stored, status_code=201 if new else 200)

    @app.delete("/api/labels/{label_id}")
    def undo(label_id: Id, labeler: str | None = None) -> dict[str, Any]:
        return service.undo(label_id, labeler)

    @app.post("/api/marks")
    def mark(body: MarkRequest) -> JSONResponse:
        stored, new = service.mark(body.run, body.step, body.labeler, body.candidate, body.point,
                                   body.request)
        return JSONResponse(stored, status_code=201 if new else 200)

    @app.delete("/api/marks/{mark_id}")
    def unmark(mark_id: Id, labeler: str | None = None) -> dict[str, Any]:
        return service.unmark(mark_id, labeler)

    @app.get("/api/counts")
    def counts() -> dict[str, Any]:
        return service.counts()

    app.mount("/static", StaticFiles(directory=str(STATIC)), name="static")
    return Guard(app, token)


def _answer_errors(app: FastAPI) -> None:
    """Every error as a 4xx answer ``{"detail": "one line"}``: HTTP's own, a request that does
    not parse (400 malformed, else 422), and footfall's (404 not found, 409 a conflict, 422)."""

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        return _error(exc.status_code, str(exc.detail))

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        line = _validation_line(exc)
        return _error(400 if line.startswith("malformed") else 422, line)

    @app.exception_handler(FootfallError)
    async def _footfall(request: Request, exc: FootfallError) -> JSONResponse:
        status = 404 if isinstance(exc, NotFound) else \
            409 if isinstance(exc, (LabelConflict, MarkConflict)) else 422
        return _error(status, str(exc))


class Guard:
    """ASGI middleware in front of the application: the token, then the body's size.

    A request must carry the token (``?token=``, ``Authorization: token ...``
    or the page's cookie): 401 without one, 403 with a wrong one. A body
    longer than :data:`MAX_BODY` bytes is refused with 413 before the
    application sees it, whether its length is declared or not.
    """

    def __init__(self, app: FastAPI, token: str) -> None:
        self.app, self.token = app, token

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            if scope["type"] == "lifespan":
                await self.app(scope, receive, send)
            return
        given = _token_of(scope)
        if given is None:
            return await _send_error(send, 401, "missing token: open the address that "
                                                "footfall teach printed")
        if not secrets.compare_digest(given.encode(), self.token.encode()):
            return await _send_error(send, 403, "wrong token")
        headers = dict(scope.get("headers") or [])
        declared = headers.get(b"content-length")
        if declared is not None and (not declared.isdigit() or int(declared) > MAX_BODY):
            return await _send_error(send, 413, f"request body over {MAX_BODY} bytes")
        body, more = b"", True
        while more:  # read it all (up to the limit) before the application sees any
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            body += message.get("body", b"")
            more = message.get("more_body", False)
            if len(body) > MAX_BODY:
                return await _send_error(send, 413, f"request body over {MAX_BODY} bytes")
        sent = False

        async def replay() -> dict:
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send)


def _token_of(scope: dict) -> str | None:
    """The token a request carries: query ``token``, ``Authorization: token X``, or the cookie."""
    query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
    if query.get("token"):
        return query["token"][0]
    for name, value in scope.get("headers") or []:
        if name == b"authorization":
            scheme, _, rest = value.decode("latin-1").partition(" ")
            if scheme.lower() in ("token", "bearer") and rest:
                return rest.strip()
        elif name == b"cookie":
            for part in value.decode("latin-1").split(";"):
                key, _, v = part.strip().partition("=")
                if key == COOKIE and v:
                    return v
    return None


async def _send_error(send: Any, status: int, detail: str) -> None:
    response = _error(status, detail)
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", b"application/json"),
                            (b"content-length", str(len(response.body)).encode())]})
    await send({"type": "http.response.body", "body": response.body})


def _error(status: int, detail: str) -> JSONResponse:
    return JSONResponse({"detail": one_line(detail)}, status_code=status)


def _validation_line(exc: RequestValidationError) -> str:
    """The first problem of a request that does not parse, on one line."""
    errors = exc.errors()
    if not errors:
        return "malformed request"
    first = errors[0]
    loc = tuple(first.get("loc", ()))
    if first.get("type") == "json_invalid":
        return "malformed JSON"
    if loc in (("body",), ()):
        return "malformed request: the body must be a JSON object (Content-Type: application/json)"
    where = ".".join(str(p) for p in loc[1:]) or str(loc[0])  # ("body", "point", 0): point.0
    return f"{where}: {first.get('msg', 'invalid')}"


def bind(host: str = LOOPBACK, port: int = 0) -> socket.socket:
    """A listening socket on ``host``:``port`` (port 0: a free one), refused with one line when
    the address cannot be bound."""
    sock = None
    try:
        info = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        # The protocol given explicitly: asyncio sets TCP_NODELAY only on sockets it knows are
        # TCP, and without it every keep-alive answer waits ~40 ms for a delayed ACK.
        sock = socket.socket(info[0], socket.SOCK_STREAM, info[2] or socket.IPPROTO_TCP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(info[4])
        sock.listen(128)
    except OSError as exc:
        if sock is not None:
            sock.close()
        raise FootfallError(f"cannot listen on {host}:{port} ({exc.strerror or exc})") from None
    return sock


def address(sock: socket.socket, token: str) -> str:
    """The address to open: http://HOST:PORT/?token=TOKEN."""
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}/?token={token}"


def new_token() -> str:
    """A random access token (192 bits)."""
    return secrets.token_urlsafe(24)


def serve(service: TeachService, sock: socket.socket, token: str,
          log_level: str = "warning") -> None:
    """Serve until Ctrl-C or SIGTERM: uvicorn finishes the requests in flight (each label is
    one transaction: a label lands whole or not at all), then the store is closed."""
    import uvicorn  # the server itself: only `footfall teach` serves

    config = uvicorn.Config(create_app(service, token), log_level=log_level, access_log=False,
                            server_header=False, lifespan="off", ws="none")  # HTTP only
    try:
        uvicorn.Server(config).run(sockets=[sock])
    except KeyboardInterrupt:  # uvicorn re-raises the SIGINT it handled, once it has stopped
        pass
    finally:
        service.close()
        sock.close()


@contextlib.contextmanager
def serving_in_thread(service: TeachService, timeout: float = 20.0) -> Iterator[tuple[str, str, str]]:
    """Serve ``service`` from a thread on a free loopback port (for tests and benchmarks);
    yield (base URL, token, the page's address). The server stops when the block ends."""
    import uvicorn

    token, sock = new_token(), bind()
    server = uvicorn.Server(uvicorn.Config(create_app(service, token), log_level="error",
                                           access_log=False, lifespan="off", ws="none"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + timeout
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise FootfallError("the teaching server did not start")
        time.sleep(0.01)
    host, port = sock.getsockname()[:2]
    try:
        yield f"http://{host}:{port}", token, address(sock, token)
    finally:
        server.should_exit = True
        thread.join(timeout)
        service.close()
        sock.close()
