"""texelpad lab stays right whatever participants, experimenters and browsers
do (issue 24): one answer per click, one server per data folder, no request
can hang the lab, the classroom cannot change a study's scene, a session file
missing its last newline takes the next answer cleanly. Against the app on a
real virtual board (TestClient) and against `texelpad lab` as a process
(HTTP over raw sockets for the slow and the huge clients). Timings appear
only as generous liveness bounds ("answers within 5 s while another stalls"),
never as measurements."""
from __future__ import annotations

import json
import signal
import threading
import time
from pathlib import Path

import pytest
from starlette.testclient import TestClient

from texelpad.study.session import DataLock, Session, SessionError
from texelpad.web.owner import BoardOwner
from texelpad.web.server import Lab, make_app

from labrun import LabRun, raw_head, read_response, rss_kb

pytestmark = pytest.mark.vboard
BASE = "http://127.0.0.1"


def _n(lab, sid) -> int:
    return lab.get("/api/sessions/%s" % sid).json()["question"]["number"]


def _answers(lab, sid) -> list:
    return [r["answer"] for r in Session.open(lab.lab.live[sid].session.path).answers()]


# --- 1. one click, one answer --------------------------------------------------------------

def test_an_answer_names_its_question_and_a_repeat_is_refused_changing_nothing(lab, port):
    sid = lab.post("/api/sessions", json={"config": "quant-exemplars", "participant": "d1",
                                          "seed": 1}).json()["id"]
    q = lab.get("/api/sessions/%s" % sid).json()
    assert q["question"]["number"] == 0 and q["answers_so_far"] == 0
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": 3, "question": 0})
    assert r.status_code == 200 and r.json()["question"]["number"] == 1, r.text
    playing = lab.lab.owner.scene_source()
    # the double-click's second request: question 0 again
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": 3, "question": 0})
    assert r.status_code == 409 and "answered already" in r.json()["error"], r.text
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": 3, "question": 2})
    assert r.status_code == 409 and "not asked yet" in r.json()["error"], r.text
    r = lab.post("/api/sessions/%s/feel" % sid, json={"option": 0, "question": 0})
    assert r.status_code == 409, r.text
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": 3})
    assert r.status_code == 400 and "question: required" in r.json()["error"], r.text
    assert _answers(lab, sid) == [3]
    assert lab.lab.live[sid].state.trial == 1 and lab.lab.owner.scene_source() == playing


def test_two_answers_to_one_question_at_once_make_one_answer(tmp_path):
    """The same answer sent twice at the same moment (two tabs, a page and a
    retry) against `texelpad lab`: one 200, one 409, one line in the file."""
    with LabRun(tmp_path / "data") as lab:
        code, res = lab.post("api/sessions", {"config": "free-nine", "participant": "d2",
                                              "seed": 5})
        assert code == 200, res
        sid = res["id"]
        code, res = lab.post("api/sessions/%s/feel" % sid, {"pitch_db": 1.0,
                                                            "irregularity_db": -9.0})
        assert code == 200, res                 # (the match answered is what plays)
        body = {"answer": {"pitch_db": 1.0, "irregularity_db": -9.0, "confidence": 4},
                "question": 0}
        got = []
        ts = [threading.Thread(target=lambda: got.append(
            lab.post("api/sessions/%s/answer" % sid, body)[0])) for _ in range(4)]
        for t in ts:
            t.start()
        for t in ts:
            t.join()
        assert sorted(got) == [200, 409, 409, 409]
        s = Session.open(tmp_path / "data" / (sid + ".jsonl"))
        assert [r["answer"]["pitch_db"] for r in s.answers()] == [1.0]
        assert [r["n"] for r in s.records] == list(range(len(s.records)))


# --- 2. one server per data folder ---------------------------------------------------------

def test_a_second_lab_on_the_same_data_folder_is_refused_naming_the_first(tmp_path):
    data = tmp_path / "data"
    with LabRun(data) as first:
        second = LabRun(data, tmp=tmp_path / "tmp2").start(wait=False)
        rc = second.p.wait(timeout=60)
        err = second.stderr()
        second.stop()
        assert rc == 1 and second.url == "", (rc, second.url, err)
        assert "in use by another texelpad lab (process %d on %s)" % (first.p.pid, first.url) \
            in err, err
        assert "Traceback" not in err and second.flash_left() == []
        # in-process too: a Lab on a folder another holds is refused
        with pytest.raises(SessionError, match="process %d" % first.p.pid):
            DataLock(data).acquire()
        assert first.get("api/status")["running"]


def test_the_lab_comes_back_on_the_port_of_its_data_folder(tmp_path):
    """A participant's open page (http://127.0.0.1:PORT/participant?...) finds
    the lab again after it stopped: the next run on the folder takes the
    same port; --http-port 0 asks for a free one."""
    data = tmp_path / "data"
    with LabRun(data) as a:
        port = a.port
    with LabRun(data, tmp=tmp_path / "t2") as b:
        assert b.port == port
    # the lock file after a process that never let go (the kernel dropped the flock)
    lock = json.loads((data / DataLock.NAME).read_text())
    assert lock["http_port"] == port
    with LabRun(data, "--http-port", "0", tmp=tmp_path / "t3") as c:
        assert c.port != 0


# --- 3. no request can hang the lab -----------------------------------------------------------

def test_a_trickling_body_does_not_delay_others_and_sigterm_still_ends_the_lab(tmp_path):
    lab = LabRun(tmp_path / "data").start()
    try:
        body = json.dumps({"config": "staircase", "participant": "slow1", "seed": 2}).encode()
        stop = threading.Event()
        slow = raw_head(lab.port, "POST", "/api/sessions", len(body))
        answered = {}

        def trickle():          # one byte every 0.1 s: ~5 s for the body
            try:
                for b in body:
                    if stop.is_set():
                        return
                    slow.sendall(bytes([b]))
                    time.sleep(0.1)
                answered["slow"] = read_response(slow)
            except OSError as e:
                answered["slow"] = e
        t = threading.Thread(target=trickle)
        t.start()
        # while it trickles: status, a session of its own, an answer - each within 5 s
        assert lab.get("api/status", timeout=5)["running"]
        code, res = lab.post("api/sessions", {"config": "staircase", "participant": "fast1"},
                             timeout=5)
        assert code == 200, res
        t.join(timeout=60)
        assert answered["slow"][0] == 200, answered        # and it was served whole
        # a body that stalls after its headers: the others go on, it alone is refused (408)
        stalled = raw_head(lab.port, "POST", "/api/sessions", 100)
        stalled.sendall(b'{"config"')
        assert lab.get("api/status", timeout=5)["running"]
        status, res = read_response(stalled)
        assert status == 408 and "did not arrive" in res["error"], res
        # SIGTERM while a client stalls: the lab ends, nothing left behind
        stuck = raw_head(lab.port, "POST", "/api/sessions", 100)
        stuck.sendall(b"{")
        assert lab.get("api/status", timeout=5)["running"]
        rc = lab.stop(signal.SIGTERM, timeout=30)
        stuck.close()
        stop.set()
        assert rc == 0, lab.stderr()
        assert lab.flash_left() == [] and "Traceback" not in lab.stderr(), lab.stderr()
        sessions = sorted(p.name for p in (tmp_path / "data").glob("*/*.jsonl"))
        assert sessions == ["staircase-1.jsonl", "staircase-1.jsonl"]   # fast1, slow1
    finally:
        if lab.p.poll() is None:
            lab.stop()


def test_a_300_mb_body_is_refused_by_its_length_before_it_is_read(tmp_path):
    with LabRun(tmp_path / "data") as lab:
        before = rss_kb(lab.p.pid)
        s = raw_head(lab.port, "POST", "/api/sessions", 300 * 1024 * 1024)
        try:
            s.sendall(b"{" + b" " * (1 << 20))         # 1 MB of it, then wait for the answer
        except OSError:
            pass                                        # (the lab may close first)
        status, res = read_response(s)
        s.close()
        assert status == 413 and "Content-Length: 314572800" in res["error"], res
        # chunked, no length: cut off once past 16 KB
        s = raw_head(lab.port, "POST", "/api/sessions", None,
                     extra="Transfer-Encoding: chunked\r\n")
        try:
            for _ in range(8):
                s.sendall(b"1000\r\n" + b" " * 4096 + b"\r\n")
        except OSError:
            pass
        status, res = read_response(s)
        s.close()
        assert status == 413 and "over 16384 bytes" in res["error"], res
        grown = rss_kb(lab.p.pid) - before
        assert grown < 50_000, "the lab grew by %d KB" % grown
        assert lab.get("api/status")["running"]


def test_a_deep_json_body_is_refused_with_a_reason(lab, port):
    for depth in (40, 50_000):
        raw = "[" * depth + "]" * depth
        r = lab.post("/api/sessions", content=raw, headers={"content-type": "application/json"})
        assert r.status_code in (400, 413), r.text
        if len(raw) <= 16384:
            assert "nests too deep" in r.json()["error"], r.text
    # deep enough for json's own recursion limit, small enough to be read
    raw = '{"config": "staircase", "participant": "p", "seed": ' + "[" * 7000 + "]" * 7000 + "}"
    r = lab.post("/api/sessions", content=raw, headers={"content-type": "application/json"})
    assert r.status_code == 400 and "nests too deep" in r.json()["error"], r.text
    assert not list(lab.lab.data.rglob("*.jsonl"))


# --- 4. the classroom cannot change a session's scene ----------------------------------------

def test_the_classroom_and_the_editor_cannot_replace_a_running_study(lab, port):
    sid = lab.post("/api/sessions", json={"config": "pursuit-4sin", "participant": "c1",
                                          "seed": 3}).json()["id"]
    assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 1}).status_code == 200
    playing = lab.lab.owner.scene_source()
    r = lab.post("/api/strip/texel", json={"pitch_db": 10.0, "irregularity_db": -20.0})
    assert r.status_code == 409 and sid in r.json()["error"], r.text
    r = lab.post("/api/editor/scene", json={"regions": []})
    assert r.status_code == 409 and sid in r.json()["error"], r.text
    assert lab.lab.owner.scene_source() == playing
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": "A", "question": 0})
    assert r.status_code == 200
    rec = list(Session.open(lab.lab.live[sid].session.path).answers())[0]
    assert rec["scene"] == playing and rec["playing"] == 1
    # the experimenter releases the board: the classroom plays; the session's
    # next answer is refused until its question plays again
    assert lab.post("/api/board/release", json={}).json() == {"released": sid}
    r = lab.post("/api/strip/texel", json={"pitch_db": 10.0, "irregularity_db": -20.0})
    assert r.status_code == 200, r.text
    classroom = lab.lab.owner.scene_source()
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": "B", "question": 1})
    assert r.status_code == 409 and "feel it again" in r.json()["error"], r.text
    assert lab.lab.owner.scene_source() == classroom and _answers(lab, sid) == ["A"]
    r = lab.get("/api/sessions/%s" % sid)               # the page reloads: it plays again
    assert r.json()["playing"] == 0 and lab.lab.owner.scene_source() != classroom
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": "B", "question": 1})
    assert r.status_code == 200, r.text
    rec = list(Session.open(lab.lab.live[sid].session.path).answers())[1]
    assert rec["scene"] == lab.lab.live[sid].session.records[-1]["scene"] != classroom
    # a finished session lets go by itself
    sid2 = lab.post("/api/sessions", json={"config": "search-4sin", "participant": "c1",
                                           "seed": 1}).json()["id"]
    assert lab.post("/api/strip/texel", json={"pitch_db": 1.0,
                                              "irregularity_db": -20.0}).status_code == 409
    r = lab.post("/api/sessions/%s/answer" % sid2, json={"answer": {"stop": True},
                                                         "question": 0})
    assert r.status_code == 200 and r.json()["question"]["done"], r.text
    assert lab.post("/api/strip/texel", json={"pitch_db": 1.0,
                                              "irregularity_db": -20.0}).status_code == 200


def test_another_session_taking_the_board_makes_the_first_feel_again(lab, port):
    a = lab.post("/api/sessions", json={"config": "pursuit-4sin", "participant": "c2",
                                        "seed": 1}).json()["id"]
    b = lab.post("/api/sessions", json={"config": "pursuit-pink", "participant": "c3",
                                        "seed": 1}).json()["id"]
    r = lab.post("/api/sessions/%s/answer" % a, json={"answer": "A", "question": 0})
    assert r.status_code == 409 and "does not play" in r.json()["error"]
    assert lab.post("/api/sessions/%s/feel" % a, json={"option": 0}).status_code == 200
    assert lab.post("/api/sessions/%s/answer" % a,
                    json={"answer": "A", "question": 0}).status_code == 200
    rec = list(Session.open(lab.lab.live[a].session.path).answers())[0]
    assert rec["scene"]["regions"][0]["texture"]["name"] == "4sin"
    assert lab.lab.live[b].playing is None


# --- 5. a file missing its last newline ------------------------------------------------------

def test_a_session_file_missing_its_last_newline_takes_the_next_answer_cleanly(lab, port):
    sid = lab.post("/api/sessions", json={"config": "quant-exemplars", "participant": "n1",
                                          "seed": 2}).json()["id"]
    for k in range(2):
        assert lab.post("/api/sessions/%s/answer" % sid,
                        json={"answer": 2 + k, "question": k}).status_code == 200
    path = lab.lab.live[sid].session.path
    path.write_bytes(path.read_bytes().rstrip(b"\n"))       # a copy that lost it
    lab.lab.live.clear()                                     # the lab restarted
    r = lab.get("/api/sessions/%s" % sid)
    assert r.status_code == 200 and r.json()["question"]["number"] == 2
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": 5, "question": 2})
    assert r.status_code == 200, r.text
    lines = path.read_bytes().split(b"\n")
    assert lines[-1] == b"" and all(json.loads(x) for x in lines[:-1])
    s = Session.open(path)
    assert [x["answer"] for x in s.answers()] == [2, 3, 5] and not s.torn
    lab.lab.live.clear()
    assert lab.get("/api/sessions/%s" % sid).json()["answers_so_far"] == 3


# --- 7. the lab's startup ----------------------------------------------------------------------

def test_an_unknown_board_is_said_at_startup(tmp_path):
    run = LabRun(tmp_path / "data", "--board", "pico-tpad").start(wait=False)
    rc = run.p.wait(timeout=120)
    err = run.stderr()
    run.stop()
    assert rc == 2 and run.url == "", (rc, err)
    line = [x for x in err.splitlines() if "error" in x]
    assert len(line) == 1 and "--board" in line[0] and "pico-tpad" in line[0], err
    assert "virtual" in line[0] and "Traceback" not in err      # what it can run
    assert run.flash_left() == []


def test_a_deep_configs_file_is_listed_as_broken_and_the_lab_starts(tmp_path, port):
    configs = tmp_path / "configs"
    configs.mkdir()
    (configs / "deep.json").write_text("[" * 50_000 + "]" * 50_000)
    (configs / "bytes.json").write_bytes(b"\xff\xfe{")
    owner = BoardOwner(port, "virtual", realtime=True)
    lab = Lab(owner, tmp_path / "data", configs)
    try:
        with TestClient(make_app(lab), base_url=BASE) as c:
            listed = c.get("/api/configs").json()["configs"]
            assert "nests too deep" in listed["deep"]["error"]
            assert "error" in listed["bytes"]
            r = c.post("/api/sessions", json={"config": "deep", "participant": "p"})
            assert r.status_code == 400 and "nests too deep" in r.json()["error"]
    finally:
        owner.close()
        lab.close()


def test_two_labs_in_one_process_on_one_folder_are_refused(tmp_path, port):
    owner = BoardOwner(port, "virtual", realtime=True)
    lab = Lab(owner, tmp_path / "data")
    try:
        with pytest.raises(SessionError, match="process %d" % __import__("os").getpid()):
            Lab(owner, tmp_path / "data")
    finally:
        lab.close()
        owner.close()
    Lab(BoardOwner(port, "virtual"), tmp_path / "data").close()    # let go: free again
    assert Path(tmp_path / "data" / DataLock.NAME).is_file()
