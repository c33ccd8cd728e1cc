"""What every route of texelpad lab shares: a refusal (Refused: 400 with the
reason, nothing changed), the request body as checked JSON, the known-keys
check, and the endpoint wrapper that serialises requests (one lab lock) and
turns errors into answers (400 refused, 503 the board is gone). Route modules
(web/server.py, web/strip.py) build on this; nothing here knows a protocol.
"""
from __future__ import annotations

import json
import threading
from typing import Any, Awaitable, Callable

from starlette.requests import Request
from starlette.responses import JSONResponse, Response

from .owner import BoardLost

BODY_MAX = 16384


class Refused(ValueError):
    pass


async def body_of(request: Request) -> Any:
    """The request's JSON body (at most BODY_MAX bytes; empty = {}), sent as
    application/json only: a page of another site in the same browser can
    send a "simple" POST (text/plain, no preflight) to 127.0.0.1, which the
    host check cannot tell from ours; a JSON content type makes the browser
    ask first, and nothing here answers yes (no CORS headers)."""
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype != "application/json":
        raise Refused("send the body as application/json (got %s)"
                      % (json.dumps(ctype[:40]) if ctype else "no content type"))
    raw = await request.body()
    if len(raw) > BODY_MAX:
        raise Refused("request body over %d bytes" % BODY_MAX)
    try:
        return json.loads(raw or b"{}")
    except ValueError:
        raise Refused("the body is not JSON") from None


def keys(body: Any, allowed: set[str]) -> None:
    """body is a JSON object of known keys only."""
    if not isinstance(body, dict):
        raise Refused("expected a JSON object")
    bad = sorted(k for k in body if k not in allowed)
    if bad:
        raise Refused("unknown key %r (allowed: %s)" % (bad[0], ", ".join(sorted(allowed))))


def handle(lock: threading.Lock,
           fn: Callable[[Request], Awaitable[Any]]) -> Callable[[Request], Awaitable[Response]]:
    """A Starlette endpoint from fn (request -> JSON data or a Response): one
    request at a time under lock; ValueError (Refused, a session's or the
    board's refusal) -> 400 {"error"}, BoardLost -> 503 {"error"}."""
    async def endpoint(request: Request) -> Response:
        try:
            with lock:
                out = await fn(request)
            return out if isinstance(out, Response) else JSONResponse(out)
        except BoardLost as e:
            return JSONResponse({"error": str(e)}, status_code=503)
        except ValueError as e:
            return JSONResponse({"error": str(e)}, status_code=400)
    return endpoint
