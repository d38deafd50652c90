"""The studio's web application (Starlette): a JSON API over a :class:`~citygen_studio.session.Session` and the
browser app's static files.

Every request is bounded: bodies to :data:`MAX_BODY` bytes, work (and the wait for a scene still loading) to
:data:`TIME_LIMIT` seconds on a small pool of threads (a request past its time gets a 504; its thread finishes on its own, bounded by the solvers' budgets).
POSTs must be JSON from the studio's own page (a page of another site cannot send them), and the Host must be the
loopback, so neither another site nor a DNS-rebinding page can drive the studio.
"""
from __future__ import annotations

import base64
import binascii
import json
import threading
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import anyio
import anyio.to_thread
from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.middleware.trustedhost import TrustedHostMiddleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route
from starlette.staticfiles import StaticFiles

from citygen.errors import CitygenError
from citygen_studio.confinement import MAX_UPLOAD, StudioError, error_data

if TYPE_CHECKING:
    from citygen_studio.session import FaceRequestSize, Session

#: The largest request body (bytes): a ruleset text and a few numbers.
MAX_BODY = 512 * 1024
#: Seconds a request may compute.
TIME_LIMIT = 20.0
STATIC = Path(__file__).with_name("static")
LOOPBACK = ["127.0.0.1", "localhost"]
#: Seconds between the progress events of a generation.
PROGRESS_EVERY = 0.25


def create_app(session: Session, time_limit: float = TIME_LIMIT) -> Starlette:
    """The studio application over ``session``."""
    limiter = anyio.CapacityLimiter(2)

    def shown(exc: CitygenError) -> dict[str, Any]:
        """The error as data, its paths as the browser names them (when the session could be made)."""
        try:
            confinement = session.confinement
        except StudioError:
            confinement = None
        return error_data(exc, confinement)

    async def run(request: Request, work: Callable[[dict[str, Any]], Any], post: bool, limit: int,
                  ready: threading.Event) -> JSONResponse:
        try:
            body = await _json_body(request, limit) if post else dict(request.query_params)
            with anyio.fail_after(time_limit):
                result = await anyio.to_thread.run_sync(_when, ready, work, body, abandon_on_cancel=True,
                                                        limiter=limiter)
        except StudioError as exc:
            return JSONResponse({"error": shown(exc)}, status_code=exc.status)
        except CitygenError as exc:
            return JSONResponse({"error": shown(exc)}, status_code=400)
        except TimeoutError:
            return JSONResponse({"error": {"message": f"the request took longer than {time_limit:g} s",
                                           "hint": "try a smaller size"}}, status_code=504)
        except Exception as exc:  # a library bug: say so, keep serving
            return JSONResponse({"error": {"message": f"internal error {type(exc).__name__}: {exc}"}},
                                status_code=500)
        return JSONResponse(result)

    def route(path: str, work: Callable[[dict[str, Any]], Any], post: bool = False, limit: int = MAX_BODY,
              buildings: bool = False) -> Route:
        """An API route; its work waits for the scene (and with ``buildings`` for its footprints and masses)."""
        ready = session.loaded if buildings else session.scene_ready

        async def endpoint(request: Request) -> JSONResponse:
            return await run(request, work, post, limit, ready)
        return Route(path, endpoint, methods=["POST"] if post else ["GET"])

    async def output(request: Request) -> Response:
        try:
            await _ready(session.scene_ready, time_limit)
            path = session.output(request.query_params.get("name", ""))
        except StudioError as exc:
            return JSONResponse({"error": shown(exc)}, status_code=exc.status)
        return FileResponse(path, filename=path.name)

    async def progress(request: Request) -> Response:
        """The running generation's state as server-sent events, every :data:`PROGRESS_EVERY` s until it ends."""
        try:
            await _ready(session.scene_ready, time_limit)
        except StudioError as exc:
            return JSONResponse({"error": shown(exc)}, status_code=exc.status)

        async def events():
            while True:
                state = session.generation_state()
                yield f"data: {json.dumps(state)}\n\n"
                if not state["running"]:
                    return
                await anyio.sleep(PROGRESS_EVERY)
        return StreamingResponse(events(), media_type="text/event-stream", headers={"cache-control": "no-store"})

    def _preview(body: dict[str, Any]) -> dict[str, Any]:
        """A ruleset text at a size, or on a building's face (``building``, ``face``) under its own request."""
        name, text = _field(body, "ruleset", str), _field(body, "text", str)
        if body.get("building") is None:
            return session.preview(name, text, _size(body))
        loaded = session.loaded.wait(time_limit)  # (a face needs the building's mass; the route waits for the scene)
        if not loaded:
            raise StudioError("the buildings are still loading", 503, hint="try again in a moment")
        return session.preview_face(name, text, _field(body, "building", int), _field(body, "face", int))

    routes = [
        route("/api/scene", lambda q: session.info()),
        route("/api/buildings", lambda q: {"buildings": session.buildings()}, buildings=True),
        route("/api/ruleset", lambda q: session.read(_field(q, "name", str))),
        route("/api/ruleset", lambda b: session.save(_field(b, "name", str), _field(b, "text", str)), post=True),
        route("/api/check", lambda b: session.check(_field(b, "ruleset", str), _field(b, "text", str)), post=True),
        route("/api/preview", _preview, post=True),
        route("/api/variations", lambda b: session.variations(_field(b, "ruleset", str), _field(b, "text", str),
                                                              _size(b), b.get("count", 8)), post=True),
        route("/api/generate", lambda b: session.generate(_field(b, "format", str), b.get("jobs", 1), _overrides(b)),
              post=True),
        route("/api/generate", lambda q: session.generation_state()),
        Route("/api/generate/events", progress),
        Route("/api/output", output),
        route("/api/import", _import, post=True, limit=MAX_UPLOAD * 4 // 3 + 4096),  # (base64)
        route("/api/extract", _extract, post=True, limit=4 * MAX_BODY),
        route("/api/build", lambda b: session.build(_field(b, "index", int), _overrides(b)), post=True,
              buildings=True),
        Mount("/", StaticFiles(directory=STATIC, html=True), name="static"),
    ]
    return Starlette(routes=routes, middleware=[Middleware(TrustedHostMiddleware, allowed_hosts=LOOPBACK)])


async def _ready(ready: threading.Event, time_limit: float) -> None:
    """Wait (off the event loop) until ``ready``, at most ``time_limit`` seconds."""
    if not ready.is_set() and not await anyio.to_thread.run_sync(ready.wait, time_limit, abandon_on_cancel=True):
        raise StudioError("the studio is still loading its scene", 503, hint="try again in a moment")


def _when(ready: threading.Event, work: Callable[[dict[str, Any]], Any], body: dict[str, Any]) -> Any:
    """``work`` once ``ready`` (a studio loading its scene in the background answers when what it needs is)."""
    ready.wait()
    return work(body)


async def _json_body(request: Request, limit: int) -> dict[str, Any]:
    """The request's JSON object: same-origin, ``application/json``, at most ``limit`` bytes."""
    origin = request.headers.get("origin")
    if origin is not None and origin.split("://", 1)[-1] != request.headers.get("host"):
        raise StudioError(f"requests from {origin} are not accepted", 403, hint="use the studio's own page")
    if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
        raise StudioError("the body must be JSON (content-type: application/json)", 415)
    if int(request.headers.get("content-length") or 0) > limit:
        raise StudioError(f"the body is larger than {limit // 1024} KiB", 413)
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > limit:
            raise StudioError(f"the body is larger than {limit // 1024} KiB", 413)
        chunks.append(chunk)
    try:
        body = json.loads(b"".join(chunks) or b"{}")
    except (ValueError, UnicodeDecodeError) as exc:
        raise StudioError(f"the body is not JSON: {exc}") from None
    if not isinstance(body, dict):
        raise StudioError("the body must be a JSON object")
    return body


def _field(body: dict[str, Any], key: str, kind: type) -> Any:
    value = body.get(key)
    if kind is int and isinstance(value, str) and value.lstrip("-").isdigit():
        value = int(value)
    if not isinstance(value, kind) or isinstance(value, bool):
        raise StudioError(f"{key} must be {'a string' if kind is str else 'an integer'}, got {value!r}")
    return value


def _import(body: dict[str, Any]) -> dict[str, Any]:
    from citygen_studio.inverse import ImportOptions, import_layout
    return import_layout(_field(body, "name", str), _base64(body, "data"), body.get("width"),
                         body.get("floor_height", 3.0), _base64(body, "label_map") if body.get("label_map") else None,
                         ImportOptions.from_json(body.get("options")))


def _extract(body: dict[str, Any]) -> dict[str, Any]:
    from citygen_studio.inverse import extract
    return extract(body.get("layout"), body.get("method", "adp"), body.get("iterations", 2000), body.get("seed", 0))


def _size(body: dict[str, Any]) -> FaceRequestSize:
    from citygen_studio.session import FaceRequestSize
    return FaceRequestSize(width=body.get("width"), height=body.get("height"),
                           floor_height=body.get("floor_height", 3.0), ground_height=body.get("ground_height"),
                           seed=body.get("seed", 0))


def _base64(body: dict[str, Any], key: str) -> bytes:
    try:
        return base64.b64decode(_field(body, key, str), validate=True)
    except binascii.Error:
        raise StudioError(f"{key} must be the file's bytes in base64") from None


def _overrides(body: dict[str, Any]) -> dict[str, str]:
    overrides = body.get("rulesets") or {}
    if not isinstance(overrides, dict) or not all(isinstance(v, str) for v in overrides.values()):
        raise StudioError("rulesets must map ruleset names to their texts")
    return overrides
