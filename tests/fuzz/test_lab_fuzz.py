"""Fuzz target "lab": the HTTP API of `texelpad lab` (one process on the
virtual board, 127.0.0.1 only) under random requests, orders, concurrency
and slow clients (issue 24).

A case: 1 .. 8 steps, each one of
- a request: create a session (configs, participants, seeds valid and not),
  feel, answer (the question's own answers, others, junk; the question's
  number, a stale one, the next one, junk), replay, the classroom's push,
  the editor's push, release the board, GETs of every route and of odd paths;
- a body that is not what it should be: random bytes, not UTF-8, NaN,
  nesting 40 or 20,000 deep, the wrong content type, a Content-Length far
  over 16 KB, or over 16 KB chunked;
- a slow client: a body trickled a few bytes at a time, or one that stops
  half-way and hangs up;
- 2 .. 4 of the above at once (threads), which also races answers to the
  same question.

Properties, per case:
- every answer is 200, 400, 404, 405, 408, 409, 413 or 503 (never a 500, no
  hang: each request has 30 s), a refusal says why ({"error": text});
- the lab answers GET /api/status within 10 s after the case (a liveness
  bound, not a timing) and has written no traceback to its stderr;
- every session file opens and replays, its records numbered 0, 1, 2 ...
  without a gap or a repeat, and holds exactly the answers the lab counts
  for it (nothing doubled, nothing lost).
At the end of the run the lab stops on SIGTERM and leaves no flash folder.

Bounded in count (fuzzlib: 50 cases in the normal run, TEXELPAD_FUZZ_CASES
nightly) and in time: the cases after TEXELPAD_FUZZ_LAB_SECONDS (default 60 s
in the normal run, 1,200 s nightly) pass without running and are counted as
"over time" in the report.
"""
from __future__ import annotations

import http.client
import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

import fuzzlib
from texelpad.study import protocols
from texelpad.study.session import Session

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "web"))
from labrun import LabRun, raw_head, read_response  # noqa: E402

FUZZ_TARGET = "lab"
pytestmark = [pytest.mark.fuzz, pytest.mark.vboard]
OK_STATUS = {200, 400, 404, 405, 408, 409, 413, 503}
CONFIGS = ["free-nine", "quant-exemplars", "similarity-matrix", "pursuit-4sin", "staircase",
           "search-4sin", "search-4d-4sin"]
PARTICIPANTS = ["f1", "f2", "f3"]
BAD_IDS = ["../x", "", "a" * 41, "a b", "..", "%2e%2e", "é"]
GETS = ["/api/status", "/api/scene", "/api/configs", "/api/sessions", "/api/strip",
        "/api/editor/palette", "/api/editor/scene", "/api/editor/strip", "/",
        "/participant?s=f1/x", "/classroom", "/editor", "/api/strip?x=1", "/nope",
        "/api/sessions/..%2F..%2Fx/a-1", "/api/sessions/f1", "/static/lab.js"]
STATUS_S = 10.0


def budget() -> float:
    env = os.environ.get("TEXELPAD_FUZZ_LAB_SECONDS")
    if env:
        return float(env)
    return 1200.0 if fuzzlib.mode() == "nightly" else 60.0


class World:
    """The lab process of the run and what the cases learned of it."""

    def __init__(self, tmp: Path) -> None:
        self.run = LabRun(tmp / "data", tmp=tmp / "tmp").start()
        self.sids: list[str] = []
        self.lock = threading.Lock()
        self.t0 = time.monotonic()
        self.err_seen = 0


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    w = World(tmp_path_factory.mktemp("labfuzz"))
    yield w
    if w.run.p.poll() is None:
        w.run.stop()


# --- requests ---------------------------------------------------------------------------

def request(port: int, method: str, path: str, body: bytes | None = None,
            ctype: str | None = "application/json",
            headers: dict | None = None, timeout: float = 30) -> tuple[int, object]:
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        h = dict(headers or {})
        if ctype is not None:
            h["content-type"] = ctype
        c.request(method, path, body=body, headers=h)
        r = c.getresponse()
        raw = r.read()
        try:
            data = json.loads(raw) if raw else None
        except ValueError:
            data = raw[:100]
        return r.status, data
    finally:
        c.close()


def _json(v) -> bytes:
    return json.dumps(v).encode()


junk = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(-2 ** 70, 2 ** 70),
                              st.floats(allow_nan=True, allow_infinity=True),
                              st.text(max_size=20)),
                    lambda c: st.one_of(st.lists(c, max_size=4),
                                        st.dictionaries(st.text(max_size=8), c, max_size=4)),
                    max_leaves=12)


@st.composite
def steps(draw, depth: int = 0):
    kinds = ["create", "create", "answer", "answer", "answer", "feel", "get", "replay",
             "classroom", "editor", "release", "bad_body", "slow"]
    if depth == 0:
        kinds.append("parallel")
    kind = draw(st.sampled_from(kinds))
    if kind == "parallel":
        return ("parallel", draw(st.lists(steps(depth=1), min_size=2, max_size=4)))
    pick = draw(st.integers(0, 2 ** 16))
    if kind == "create":
        body = {"config": draw(st.sampled_from(CONFIGS + ["nope", "../x"])),
                "participant": draw(st.sampled_from(PARTICIPANTS + BAD_IDS[:3]))}
        if draw(st.booleans()):
            body["seed"] = draw(st.one_of(st.integers(0, 2 ** 31 + 5), junk))
        if draw(st.integers(0, 9)) == 0:
            body[draw(st.sampled_from(["protocol", "reference", "x", "matches_from"]))] = draw(junk)
        return ("create", body)
    if kind == "answer":
        return ("answer", pick, draw(st.sampled_from(["own", "own", "own", "junk"])),
                draw(st.sampled_from([0, 0, 0, -1, 1, "junk", "none"])), draw(junk))
    if kind == "feel":
        return ("feel", pick, draw(st.one_of(st.integers(-1, 3), junk)),
                draw(st.sampled_from([0, 0, -1, 1, "none"])))
    if kind == "get":
        return ("get", pick, draw(st.sampled_from(GETS + ["session", "monitor"])))
    if kind == "replay":
        return ("replay", pick, draw(st.one_of(st.integers(-1, 5), junk)))
    if kind == "classroom":
        return ("classroom", {"pitch_db": draw(st.one_of(st.floats(-25, 25), junk)),
                              "irregularity_db": draw(st.floats(-35, 5))})
    if kind == "editor":
        return ("editor", draw(st.sampled_from([{"regions": []}, {"regions": [{
            "start_mm": 0, "end_mm": 20, "texture": {"kind": "constant", "level": 0.3}}]},
            {"regions": "x"}])))
    if kind == "release":
        return ("release", draw(st.sampled_from([{}, {"x": 1}])))
    if kind == "bad_body":
        return ("bad_body", pick, draw(st.sampled_from(
            ["bytes", "utf8", "nan", "deep40", "deep20000", "ctype", "length", "chunked",
             "empty", "array"])), draw(st.binary(max_size=64)))
    return ("slow", pick, draw(st.sampled_from(["trickle", "hangup"])),
            draw(st.integers(2, 8)))


def _sid(w: World, pick: int) -> str:
    with w.lock:
        if w.sids and pick % 7:
            return w.sids[pick % len(w.sids)]
    return ["f1/staircase-99", "../x/y", "f1/nope"][pick % 3]


def do(w: World, step, seen: list) -> None:
    """Run one step, recording every (step kind, status, body) in seen."""
    port = w.run.port
    kind = step[0]

    def note(status, data, what=kind):
        seen.append((what, status, data))

    if kind == "parallel":
        ts = [threading.Thread(target=do, args=(w, s, seen)) for s in step[1]]
        for t in ts:
            t.start()
        for t in ts:
            t.join(120)
        return
    if kind == "create":
        status, data = request(port, "POST", "/api/sessions", _json(step[1]))
        if status == 200:
            with w.lock:
                w.sids.append(data["id"])
        note(status, data)
    elif kind == "answer":
        _, pick, how, dq, jv = step
        sid = _sid(w, pick)
        status, q = request(port, "GET", "/api/sessions/" + sid, ctype=None)
        note(status, q, "question")
        body: dict = {}
        if status == 200 and not q["question"]["done"]:
            qq = q["question"]
            if how == "own" and qq.get("answers"):
                body["answer"] = qq["answers"][pick % len(qq["answers"])]
            elif how == "own" and qq.get("kind") == "sliders":
                body["answer"] = {"pitch_db": (pick % 30) - 10.0,
                                  "irregularity_db": -(pick % 30) * 1.0,
                                  "confidence": 1 + pick % 5}
            else:
                body["answer"] = jv
            n = qq["number"]
        else:
            body["answer"], n = jv, 0
        if dq == "junk":
            body["question"] = jv
        elif dq != "none":
            body["question"] = n + dq
        status, data = request(port, "POST", "/api/sessions/%s/answer" % sid, _json(body))
        note(status, data)
    elif kind == "feel":
        _, pick, opt, dq = step
        sid = _sid(w, pick)
        body = {"option": opt}
        status, q = request(port, "GET", "/api/sessions/" + sid, ctype=None)
        if status == 200 and q["question"].get("kind") == "sliders":
            body = {"pitch_db": opt if not isinstance(opt, int) else opt * 3.0,
                    "irregularity_db": -10.0}
        if dq != "none" and status == 200:
            body["question"] = q["question"]["number"] + dq
        status, data = request(port, "POST", "/api/sessions/%s/feel" % sid, _json(body))
        note(status, data)
    elif kind == "get":
        _, pick, path = step
        if path in ("session", "monitor"):
            path = "/api/sessions/" + _sid(w, pick) + ("/monitor" if path == "monitor" else "")
        status, data = request(port, "GET", path, ctype=None)
        note(status, data)
    elif kind == "replay":
        status, data = request(port, "POST", "/api/sessions/%s/replay" % _sid(w, step[1]),
                               _json({"record": step[2]}))
        note(status, data)
    elif kind == "classroom":
        note(*request(port, "POST", "/api/strip/texel", _json(step[1])))
    elif kind == "editor":
        note(*request(port, "POST", "/api/editor/scene", _json(step[1])))
    elif kind == "release":
        note(*request(port, "POST", "/api/board/release", _json(step[1])))
    elif kind == "bad_body":
        _, pick, how, raw = step
        path = ["/api/sessions", "/api/sessions/%s/answer" % _sid(w, pick), "/api/finger",
                "/api/strip/texel", "/api/editor/scene"][pick % 5]
        if how in ("length", "chunked"):
            s = raw_head(port, "POST", path, 1 << 28 if how == "length" else None,
                         extra="" if how == "length" else "Transfer-Encoding: chunked\r\n")
            try:
                for _ in range(6 if how == "chunked" else 1):
                    s.sendall(b"1000\r\n" + b" " * 4096 + b"\r\n" if how == "chunked"
                              else b" " * 4096)
            except OSError:
                pass
            note(*read_response(s), what=how)
            s.close()
            return
        body = {"bytes": raw, "utf8": b'{"a": "\xff\xfe"}', "nan": b'{"answer": NaN}',
                "deep40": b"[" * 40 + b"]" * 40, "deep20000": b"[" * 8000 + b"]" * 8000,
                "ctype": b"{}", "empty": b"", "array": b"[1, 2]"}[how]
        note(*request(port, "POST", path, body,
                      ctype="text/plain" if how == "ctype" else "application/json"), what=how)
    elif kind == "slow":
        _, pick, how, n = step
        body = _json({"config": "staircase", "participant": "slow%d" % (pick % 3)})
        s = raw_head(port, "POST", "/api/sessions", len(body))
        try:
            for b in body[:n]:
                s.sendall(bytes([b]))
                time.sleep(0.02)
            if how == "hangup":
                s.close()
                note(None, None, "hangup")
                return
            s.sendall(body[n:])
            status, data = read_response(s)
            if status == 200:
                with w.lock:
                    w.sids.append(data["id"])
            note(status, data, "trickle")
        finally:
            s.close()


def check_files(w: World) -> None:
    """Every session file opens and replays, numbered without a gap, and
    holds the answers the lab counts for it."""
    for path in sorted(w.run.data.glob("*/*.jsonl")):
        s = Session.open(path)
        assert not s.torn, path
        assert [r["n"] for r in s.records] == list(range(len(s.records))), path
        protocols.replay(s)
        sid = "%s/%s" % (path.parent.name, path.stem)
        status, mon = request(w.run.port, "GET", "/api/sessions/%s/monitor" % sid, ctype=None)
        assert status == 200, (sid, status, mon)
        assert mon["answers_so_far"] == sum(1 for _ in s.answers()), sid
        assert mon["records"] == len(s.records), sid


@fuzzlib.fuzz_settings()
@given(st.lists(steps(), min_size=1, max_size=8))
def test_the_lab_api_under_random_requests(world, program):
    if time.monotonic() - world.t0 > budget():
        fuzzlib.STATS[FUZZ_TARGET].outcomes["over time (not run)"] += 1
        return
    seen: list = []
    with fuzzlib.case(FUZZ_TARGET, lambda: fuzzlib.short(program, 300)) as s:
        with fuzzlib.watchdog(180, "a lab case"):
            for step in program:
                do(world, step, seen)
            for what, status, data in seen:
                s.outcomes["%s %s" % (what, status)] += 1
                if status is None:
                    continue
                assert status in OK_STATUS, (what, status, data, program)
                if status >= 400 and status not in (404, 405):
                    assert isinstance(data, dict) and isinstance(data.get("error"), str) \
                        and data["error"], (what, status, data)
            # liveness: the lab answers within STATUS_S (a bound, not a timing)
            st_ = request(world.run.port, "GET", "/api/status", ctype=None, timeout=STATUS_S)
            assert st_[0] == 200, st_
            err = world.run.stderr()
            assert "Traceback" not in err and "Exception in ASGI" not in err, err[-3000:]
            check_files(world)


def test_the_lab_stops_on_sigterm_after_the_fuzz_leaving_nothing(world):
    """Last in the module: whatever the cases left open, SIGTERM ends the
    lab (rc 0), with no flash folder left behind and no traceback."""
    stuck = raw_head(world.run.port, "POST", "/api/sessions", 50)
    stuck.sendall(b"{")
    rc = world.run.stop(signal.SIGTERM, timeout=60)
    stuck.close()
    assert rc == 0, world.run.stderr()[-3000:]
    assert world.run.flash_left() == []
    assert "Traceback" not in world.run.stderr()
