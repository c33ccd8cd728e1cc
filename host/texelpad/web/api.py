"""What every route of texelpad lab shares: a refusal (Refused: 400 with the
reason, nothing changed; Conflict 409, TooLarge 413, TooSlow 408), the
request body read, bounded and checked before anything else, the known-keys
check, and the endpoint wrapper that serialises the work (one lab lock) and
turns errors into answers (400 refused, 503 the board is gone). Route modules
(web/server.py, web/strip.py, web/editor.py) build on this; nothing here
knows a protocol.

The order inside one request (docs/lab.md): the body is read first, on
the event loop and without any lock - refused by its Content-Length before a
byte of it is read when it is over BODY_MAX, cut off at BODY_MAX when it comes
without one, and given BODY_SECONDS to arrive (408 after that: a client that
stalls times out alone). Only then does the route's work run, in a worker
thread under the lab's lock: the board and the session files, one request at
a time. The lock is never held across an await, so a slow client cannot
block the event loop, the other requests or the server's shutdown.
"""
from __future__ import annotations

import json
import threading
from typing import Any, Callable

import anyio
from starlette.concurrency import run_in_threadpool
from starlette.requests import ClientDisconnect, Request
from starlette.responses import JSONResponse, Response

from .owner import BoardLost

BODY_MAX = 16384            # bytes: the largest body any page sends is a painted scene, ~10 KB
BODY_SECONDS = 10.0         # a body not all there by then is refused (408)
DEPTH_MAX = 32              # JSON nesting: the deepest body a page sends is 6 levels
BODY_METHODS = ("POST", "PUT", "PATCH", "DELETE")


class Refused(ValueError):
    """A request refused with its reason; nothing changed (400)."""
    status = 400


class Conflict(Refused):
    """A request that does not fit the state now (409): an answer to a
    question already answered or not yet asked, a push onto a board a
    study session owns. Nothing changed."""
    status = 409


class TooLarge(Refused):
    status = 413


class TooSlow(Refused):
    status = 408


class Stopping(Refused):
    status = 503


# The body reads in progress (their cancel scopes): stop_reading() ends them
# when the server stops, so a client that stalls cannot hold up the shutdown
_reading: set[anyio.CancelScope] = set()
_stopping = False


def stop_reading() -> None:
    """The server is stopping: every body still being read is refused (503)
    at once, and so is every one that starts. Call it on the event loop
    (texelpad lab's server does, from its signal handler, with
    call_soon_threadsafe)."""
    global _stopping
    _stopping = True
    for scope in list(_reading):
        scope.cancel()


def depth_ok(value: Any, limit: int = DEPTH_MAX) -> bool:
    """Whether value nests at most `limit` lists/objects deep (iterative: a
    deep value cannot exhaust the stack here)."""
    stack = [(value, 1)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict):
            v = list(v.values())
        elif not isinstance(v, list):
            continue
        if d > limit:
            return False
        stack.extend((x, d + 1) for x in v if isinstance(x, (dict, list)))
    return True


def parse_json(raw: bytes | str, what: str = "the body") -> Any:
    """JSON text -> data, or Refused: not JSON, not UTF-8, or nested deeper
    than DEPTH_MAX (json's recursion would raise RecursionError - a 500 -
    at some thousands of levels; the routes' own checks recurse too)."""
    try:
        v = json.loads(raw)
    except RecursionError:
        raise Refused("%s nests too deep (at most %d levels)" % (what, DEPTH_MAX)) from None
    except ValueError:                  # (UnicodeDecodeError is one)
        raise Refused("%s is not JSON" % what) from None
    if not depth_ok(v):
        raise Refused("%s nests too deep (at most %d levels)" % (what, DEPTH_MAX))
    return v


async def read_body(request: Request) -> Any:
    """The request's JSON body (at most BODY_MAX bytes; empty = {}), sent as
    application/json only: a page of another site in the same browser can
    send a "simple" POST (text/plain, no preflight) to 127.0.0.1, which the
    host check cannot tell from ours; a JSON content type makes the browser
    ask first, and nothing here answers yes (no CORS headers).

    A body over BODY_MAX is refused by its Content-Length before it is read
    (and cut off at BODY_MAX when it comes without one); one that has not
    arrived after BODY_SECONDS is refused (408). Awaited without any lock."""
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype != "application/json":
        raise Refused("send the body as application/json (got %s)"
                      % (json.dumps(ctype[:40]) if ctype else "no content type"))
    declared = request.headers.get("content-length")
    if declared is not None:
        if not declared.strip().isdigit():
            raise Refused("Content-Length: expected a number of bytes, got %s"
                          % json.dumps(declared[:40]))
        if int(declared) > BODY_MAX:
            raise TooLarge("request body over %d bytes (Content-Length: %d)"
                           % (BODY_MAX, int(declared)))
    parts: list[bytes] = []
    size = 0
    if _stopping:
        raise Stopping("texelpad lab is stopping")
    scope = anyio.CancelScope(deadline=anyio.current_time() + BODY_SECONDS)
    _reading.add(scope)
    try:
        with scope:
            async for chunk in request.stream():
                size += len(chunk)
                if size > BODY_MAX:
                    raise TooLarge("request body over %d bytes" % BODY_MAX)
                parts.append(chunk)
    finally:
        _reading.discard(scope)
    if scope.cancelled_caught:
        if _stopping:
            raise Stopping("texelpad lab is stopping")
        raise TooSlow("the request body did not arrive within %g s" % BODY_SECONDS)
    raw = b"".join(parts)
    return parse_json(raw) if raw.strip() else {}


def body_of(request: Request) -> Any:
    """The body handle() read and checked (read_body) before the route ran."""
    try:
        return request.state.body
    except AttributeError:
        raise RuntimeError("body_of: %s %s was not read by web.api.handle"
                           % (request.method, request.url.path)) from None


def keys(body: Any, allowed: set[str]) -> None:
    """body is a JSON object of known keys only."""
    if not isinstance(body, dict):
        raise Refused("expected a JSON object")
    bad = sorted(k for k in body if k not in allowed)
    if bad:
        raise Refused("unknown key %s (allowed: %s)" % (_key(bad[0]), ", ".join(sorted(allowed))))


def _key(k: str) -> str:
    return repr(k) if len(k) <= 40 else repr(k[:40]) + "..."


def _error(status: int, text: str, close: bool = False) -> Response:
    # close: the body was not read (too large, too slow): the connection ends
    # with the answer rather than reading the rest of it
    return JSONResponse({"error": text}, status_code=status,
                        headers={"connection": "close"} if close else None)


def handle(lock: threading.Lock,
           fn: Callable[[Request], Any]) -> Callable[[Request], Any]:
    """A Starlette endpoint from fn (request -> JSON data or a Response; a
    plain function, its body from body_of(request)): the body read first
    (read_body, no lock), then fn in a worker thread under lock, one at a
    time; Refused -> its status, ValueError (a session's or the board's
    refusal) -> 400, BoardLost -> 503, each {"error": reason}."""
    def locked(request: Request) -> Any:
        with lock:
            return fn(request)

    async def endpoint(request: Request) -> Response:
        try:
            if request.method in BODY_METHODS:
                request.state.body = await read_body(request)
            out = await run_in_threadpool(locked, request)
            return out if isinstance(out, Response) else JSONResponse(out)
        except (TooLarge, TooSlow, Stopping) as e:
            return _error(e.status, str(e), close=True)
        except BoardLost as e:
            return _error(503, str(e))
        except Refused as e:
            return _error(e.status, str(e))
        except ValueError as e:
            return _error(400, str(e))
        except ClientDisconnect:            # gone: no one to answer
            return Response(status_code=400)
    return endpoint
