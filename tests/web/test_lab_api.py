"""texelpad lab's API (texelpad.web) against a real virtual board (the device
image under the MicroPython unix port, on a pty): a session per protocol
driven by the simulated participant, every answer in the session file with
the scene the board played, resume from the file, refusals that change
nothing, localhost only, and `texelpad lab` itself (the URL first)."""
from __future__ import annotations

import json

import pytest
from starlette.testclient import TestClient

from texelpad.study.participant import SimulatedParticipant
from texelpad.study.session import Session
from texelpad.study.space import Point
from texelpad.web.owner import BoardOwner
from texelpad.web.server import Lab, make_app

from support.lab import lab_process

pytestmark = pytest.mark.vboard
BASE = "http://127.0.0.1"


# port and lab: tests/web/conftest.py


def _playing(lab) -> dict:
    """What the board plays, asked through the lab's own owner (it holds the port)."""
    return lab.lab.owner.scene_source()


def _n(lab, sid) -> int:
    """The number of the question session sid asks now (its answers so far)."""
    return lab.lab._number(lab.lab.live[sid])


def _answer_all(lab, sid, sim, protocol, limit=100):
    """Answer as the simulated participant until the session is done (or
    limit answers); returns the last reply."""
    live = lab.lab.live[sid]
    r = None
    for _ in range(limit):
        if live.question.done:
            break
        a = sim.answer(protocol, live.state)
        if protocol == "staircase":                 # the page sends the texture picked
            a = live.question.odd if a else (live.question.odd + 1) % 3
        if protocol == "free":                      # the sliders go there first: the match
            assert lab.post("/api/sessions/%s/feel" % sid,       # is what plays
                            json={k: a[k] for k in ("pitch_db", "irregularity_db")}
                            ).status_code == 200
        r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": a, "question": _n(lab, sid)})
        assert r.status_code == 200, r.text
    return r


def test_a_pursuit_session_end_to_end_with_the_simulated_participant(lab, port):
    r = lab.post("/api/sessions", json={"config": "pursuit-4sin", "participant": "p01",
                                        "seed": 4})
    assert r.status_code == 200, r.text
    sid, q = r.json()["id"], r.json()["question"]
    # seed 000 / the lab's app: the reference, A or B, one at a time on the whole display
    assert q["options"] == ["reference", "A", "B"] and "pitch_db" not in json.dumps(q)  # blind
    assert _playing(lab)["regions"] == [{"start_mm": 0.0, "end_mm": 101.76, "texture": {
        "kind": "reference", "name": "4sin"}}]         # a question starts on the reference
    mon = lab.get("/api/sessions/%s/monitor" % sid).json()           # the experimenter's view
    assert mon["detail"]["centre"] == {"pitch_db": 5.0, "irregularity_db": -10.0}
    assert mon["config"]["config_file"] == "pursuit-4sin"
    live = lab.lab.live[sid]
    sim = SimulatedParticipant(Point(0.3, 0.7))
    n = 0
    while not q["done"]:
        # feel B, then answer as the participant would
        assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 2}).json() == {"playing": 2}
        comp = live.state.next_comparison()
        r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": sim.compare(comp.a, comp.b),
                                                               "question": n})
        assert r.status_code == 200, r.text
        q = r.json()["question"]
        n += 1
    assert n == 20 and live.state.centre.v > 0.5
    s = Session.open(live.session.path)
    answers = list(s.answers())
    assert len(answers) == 20 and all(rec["playing"] == 2 for rec in answers)
    assert s.finished and s.records[-1]["result"]["trials"] == 5
    assert answers[0]["state"]["edge"] == 1.0 and answers[-1]["state"]["edge"] == pytest.approx(0.2)
    # the scene recorded is the one that played: B alone on the whole display, a fresh
    # rendering for every comparison (seeds drawn from the session's seed)
    last = answers[-1]["scene"]
    assert len(last["regions"]) == 1 and last["regions"][0]["texture"]["kind"] == "texel"
    assert last["regions"][0]["texture"]["v"] == 2
    seeds = [rec["scene"]["regions"][0]["texture"]["seed"] for rec in answers]
    assert len(set(seeds)) == 20
    assert _playing(lab) == last            # the board still plays the last scene felt
    # replay: what answer 0 heard plays again
    assert lab.post("/api/sessions/%s/replay" % sid, json={"record": 0}).status_code == 200
    assert _playing(lab) == answers[0]["scene"]


def test_free_exploration_then_the_quantization_test_with_its_matches(lab, port):
    r = lab.post("/api/sessions", json={"config": "free-nine", "participant": "p05", "seed": 2})
    assert r.status_code == 200, r.text
    sid = r.json()["id"]
    live = lab.lab.live[sid]
    first = live.state.reference
    # the sliders start where the lab's app's did (5 dB, sigma 0.5 decade); every change
    # re-draws and plays
    assert r.json()["sliders"] == [5.0, -3.01]
    seeds = set()
    for p, s in ((0.0, -20.0), (4.5, -12.25), (20.0, -3.0)):
        r = lab.post("/api/sessions/%s/feel" % sid, json={"pitch_db": p, "irregularity_db": s})
        assert r.status_code == 200, r.text
        right = _playing(lab)["regions"][1]["texture"]
        assert right["pitch_db"] == min(p, 19.747) and right["irregularity_db"] == s
        seeds.add(right["seed"])
        assert _playing(lab)["regions"][0]["texture"] == {"kind": "reference", "name": first}
    assert len(seeds) == 3
    for bad in ({"pitch_db": 21, "irregularity_db": 0}, {"pitch_db": 1}, {"option": 0}):
        assert lab.post("/api/sessions/%s/feel" % sid, json=bad).status_code == 400
    moves = [x for x in Session.open(live.session.path).records if x["kind"] == "move"]
    assert [m["pitch_db"] for m in moves] == [5.0, 0.0, 4.5, 20.0]
    # a server restart: the sliders come back where they were
    lab.lab.live.clear()
    assert lab.get("/api/sessions/%s" % sid).json()["sliders"] == [20.0, -3.0]
    sim = SimulatedParticipant(Point(0.5, 0.4))
    _answer_all(lab, sid, sim, "free")
    st = lab.lab.live[sid].state
    assert st.done and [m["reference"] for m in st.matches] == st.order
    # the quantization test without the participant's own matches is refused
    r = lab.post("/api/sessions", json={"config": "quant-paper", "participant": "p05"})
    assert r.status_code == 400 and "matches_from" in r.json()["error"]
    # seed 000's 27 trials on this participant's own matches: the texture felt at submission
    felt = {m["reference"]: rec["scene"]["regions"][1]["texture"]
            for rec, m in zip(Session.open(live.session.path).answers(), st.matches)}
    r = lab.post("/api/sessions", json={"config": "quant-paper", "participant": "p05",
                                        "seed": 3, "matches_from": sid})
    assert r.status_code == 200, r.text
    qid = r.json()["id"]
    qs = lab.lab.live[qid]
    assert qs.session.header["config"]["match_source"] == sid
    assert "quant" not in json.dumps(r.json()["question"])                 # blind
    kinds = []
    while not qs.state.done:
        tex = _playing(lab)["regions"][1]["texture"]
        trial = qs.state.plan[qs.state.trial]
        if trial["source"] == "own":        # the very texture felt, quantized or not
            want = {k: felt[trial["reference"]][k] for k in
                    ("pitch_db", "irregularity_db", "seed", "texel_samples", "v")}
            assert {k: tex[k] for k in want} == want
            assert tex["quant_db"] == trial["quant_db"]
        else:                               # the rater's logged sequence, as samples
            assert tex["kind"] == "samples" and len(tex["u16"]) == 9600
            assert list(tex["u16"]) == list(qs.state.texture()["u16"])
        kinds.append((trial["source"], trial["quant_db"]))
        a = sim.answer("quant", qs.state)
        assert lab.post("/api/sessions/%s/answer" % qid,
                        json={"answer": a, "question": _n(lab, qid)}).status_code == 200
    assert sorted(kinds) == sorted([("own", 0.0)] * 9 + [("rater", 0.0)] * 9
                                   + [("rater", q) for q in (1.0, 3.0, 5.0)] * 3)
    file = [x["answer"] for x in Session.open(qs.session.path).answers()]
    assert [x["similarity"] for x in qs.state.ratings] == file and len(file) == 27
    assert all(x in range(1, 6) for x in file)


def test_the_similarity_matrix_rates_each_exemplar_against_each_pursuit_match(lab, port):
    sim = SimulatedParticipant(Point(0.3, 0.6))
    ends, sids = {}, []
    for ref in ("4sin", "pink", "sawtooth"):
        sid = lab.post("/api/sessions", json={"config": "pursuit-%s" % ref, "participant": "p07",
                                              "seed": 2}).json()["id"]
        _answer_all(lab, sid, sim, "pursuit")
        ends[ref] = lab.lab.live[sid].state.centre
        sids.append(sid)
    r = lab.post("/api/sessions", json={"config": "similarity-matrix", "participant": "p07",
                                        "matches_from": sids[:2]})
    assert r.status_code == 400 and "no match of sawtooth" in r.json()["error"]
    r = lab.post("/api/sessions", json={"config": "similarity-matrix", "participant": "p07",
                                        "matches_from": sids, "seed": 1})
    assert r.status_code == 200, r.text
    qid = r.json()["id"]
    st = lab.lab.live[qid].state
    assert st.config.matches["pink"]["pitch_db"] == round(-15 + 40 * ends["pink"].u, 3)
    assert st.config.order == "lab" and st.config.presentation == "whole"
    pairs = []
    for _ in range(9):
        # the guided app's way: the reference, then the rendering, one at a time, whole display
        assert _playing(lab)["regions"] == [{"start_mm": 0.0, "end_mm": 101.76, "texture": {
            "kind": "reference", "name": st.current[0]}}]
        assert lab.post("/api/sessions/%s/feel" % qid, json={"option": 1}).json() == \
            {"playing": 1}
        (region,) = _playing(lab)["regions"]
        tex = region["texture"]
        pairs.append((st.current_match, st.current[0]))
        assert tex["pitch_db"] == st.config.matches[st.current_match]["pitch_db"]
        assert tex["texel_samples"] == 50           # the app's texelLength (the pursuit's too)
        assert lab.post("/api/sessions/%s/answer" % qid,
                        json={"answer": 3, "question": _n(lab, qid)}).status_code == 200
    # the app's ratingorder [3,1; 2,1; 1,1; 3,2; ...] as (match, reference)
    ex = ("4sin", "pink", "sawtooth")
    assert pairs == [(ex[m - 1], ex[r - 1]) for m, r in ((3, 1), (2, 1), (1, 1), (3, 2), (2, 2),
                                                         (1, 2), (3, 3), (2, 3), (1, 3))]
    assert st.done


def test_search_and_staircase_sessions_and_resume_from_the_file(lab, port):
    r = lab.post("/api/sessions", json={"protocol": "search", "participant": "p02", "seed": 9})
    sid = r.json()["id"]
    sim = SimulatedParticipant(Point(0.4, 0.6))
    _answer_all(lab, sid, sim, "search", limit=4)
    assert lab.post("/api/sessions/%s/answer" % sid, json={"answer": {"save": 2},
                                                                 "question": 4}).status_code == 200
    mean = lab.lab.live[sid].state.mean
    # a server restart: the session comes back from its file, the same state
    lab.lab.live.clear()
    r = lab.get("/api/sessions/%s" % sid)
    assert r.status_code == 200 and r.json()["answers_so_far"] == 5
    assert lab.lab.live[sid].state.mean == mean and len(lab.lab.live[sid].state.saved) == 1
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": {"stop": True}, "question": 5})
    assert r.json()["question"]["done"] and Session.open(lab.lab.live[sid].session.path).finished
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": {"choose": 0}, "question": 6})
    assert r.status_code == 409 and "finished" in r.json()["error"], r.text
    # staircase: pick the odd one (the simulated participant finds it at long texels)
    r = lab.post("/api/sessions", json={"config": "staircase", "participant": "p02", "seed": 3})
    sid = r.json()["id"]
    for _ in range(3):
        odd = lab.lab.live[sid].question.odd
        r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": odd,
                                                             "question": _n(lab, sid)})
        assert r.status_code == 200
    st = lab.lab.live[sid].state
    assert st.length_mm == 23.5 and [t["correct"] for t in st.track] == [True] * 3
    tex = _playing(lab)["regions"][0]["texture"]
    assert tex["texel_samples"] == round(23.5 / 0.0053) and tex["v"] == 2
    listed = {x["id"]: x for x in lab.get("/api/sessions").json()["sessions"]}
    assert listed[sid]["answers"] == 3 and listed[sid]["config_file"] == "staircase"


@pytest.mark.parametrize("path, body, fragment", [
    ("/api/sessions", {"protocol": "nope", "participant": "p"}, "protocol: expected one of"),
    ("/api/sessions", {"protocol": "pursuit", "participant": "../etc"}, "participant: expected"),
    ("/api/sessions", {"protocol": "pursuit", "participant": "p", "x": 1}, "unknown key 'x'"),
    ("/api/sessions", {"protocol": "pursuit", "participant": "p", "seed": -1}, "seed: expected"),
    ("/api/sessions", {"protocol": "pursuit", "participant": "p",
                       "reference": {"kind": "reference", "name": "nope"}}, "reference"),
    ("/api/sessions", [1, 2], "expected a JSON object"),
    ("/api/sessions", {"config": "nope", "participant": "p"}, "config: no 'nope'"),
    ("/api/sessions", {"config": "../x", "participant": "p"}, "config: expected"),
    ("/api/sessions", {"config": "free-nine", "protocol": "free", "participant": "p"}, "not both"),
    ("/api/sessions", {"config": "free-nine", "participant": "p",
                       "reference": {"kind": "reference", "name": "4sin"}}, "only the pursuit"),
    ("/api/sessions", {"config": "quant-exemplars", "participant": "p",
                       "matches_from": "p/free-7"}, "no session p/free-7"),
    ("/api/sessions", {"protocol": "quant", "participant": "p"}, "give matches_from"),
])
def test_refused_requests_say_why_and_change_nothing(lab, port, path, body, fragment):
    lab.lab.owner.display()     # (the board started, as any earlier test of the file leaves it)
    before = _playing(lab)
    r = lab.post(path, json=body)
    assert r.status_code == 400 and fragment in r.json()["error"], r.text
    assert _playing(lab) == before
    assert not list((lab.lab.data).rglob("*.jsonl"))


def test_a_refused_answer_changes_nothing(lab, port):
    sid = lab.post("/api/sessions", json={"protocol": "pursuit", "participant": "p03",
                                          "seed": 1}).json()["id"]
    before = _playing(lab)
    for body in ({"answer": "C", "question": 0}, {"answer": None, "question": 0}, {"option": 0},
                 {}, {"answer": ["A"], "question": 0}, {"answer": "A"},
                 {"answer": "A", "question": "0"}, {"answer": "A", "question": True}):
        r = lab.post("/api/sessions/%s/answer" % sid, json=body)
        assert r.status_code == 400, (body, r.text)
    assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 3}).status_code == 400
    r = lab.post("/api/sessions/%s/feel" % sid, content="x" * 20000,
                 headers={"content-type": "application/json"})
    assert r.status_code == 413 and "over 16384 bytes" in r.json()["error"], r.text
    assert len(Session.open(lab.lab.live[sid].session.path).records) == 0
    assert lab.lab.live[sid].state.trial == 0 and not lab.lab.live[sid].state.answers[0]
    assert _playing(lab) == before
    assert lab.get("/api/sessions/p03/pursuit-9").status_code == 400
    assert lab.get("/api/sessions/..%2F..%2Fx/pursuit-1").status_code in (400, 404)


def test_a_cross_site_simple_post_is_refused_and_changes_nothing(lab, port):
    """A page elsewhere can POST text/plain to 127.0.0.1 without asking: only
    application/json bodies are taken (the browser asks before sending
    those, and nothing here says yes)."""
    before = _playing(lab)
    body = json.dumps({"config": "staircase", "participant": "x1"})
    for ctype in ("text/plain", "application/x-www-form-urlencoded", None):
        r = lab.post("/api/sessions", content=body,
                     headers={"content-type": ctype} if ctype else {})
        assert r.status_code == 400 and "application/json" in r.json()["error"], r.text
    assert _playing(lab) == before and not list(lab.lab.data.rglob("*.jsonl"))
    assert "access-control-allow-origin" not in {k.lower() for k in r.headers}


def test_only_localhost_names_are_served(lab):
    assert lab.get("/api/status").status_code == 200
    assert lab.get("/api/status", headers={"host": "evil.example"}).status_code == 400


def test_texelpad_lab_prints_its_url_first_and_serves_the_virtual_board(tmp_path):
    with lab_process(tmp_path) as (url, st):
        assert st["running"] and st["board"] == "virtual"


def test_the_server_survives_a_board_that_disappears_and_says_so(tmp_path):
    """The board is unplugged mid-session (its process killed): the next
    requests answer 503 saying so, nothing is written, the server goes on; the
    board comes back (a new one on the owner's port, as a replugged board
    reappears on its port) and the session goes on where it stopped."""
    from texelpad.sim.virtual import VirtualBoard
    vb = VirtualBoard(image="source")
    vb.__enter__()
    owner = BoardOwner(vb.port, "virtual", realtime=True, timeout=5.0)
    lab = Lab(owner, tmp_path / "data")
    with TestClient(make_app(lab), base_url=BASE) as c:
        sid = c.post("/api/sessions", json={"config": "pursuit-4sin", "participant": "p09",
                                            "seed": 1}).json()["id"]
        assert c.post("/api/sessions/%s/answer" % sid,
                      json={"answer": "A", "question": 0}).status_code == 200
        vb.stop()                                               # unplugged
        # the answer to what was felt is kept; the reply says the board is gone
        r = c.post("/api/sessions/%s/answer" % sid, json={"answer": "B", "question": 1})
        assert r.status_code == 200 and "board" in r.json()["board_lost"], r.text
        assert r.json()["playing"] is None
        r = c.get("/api/status")
        assert r.status_code == 503 and "does not answer" in r.json()["error"], r.text
        assert c.post("/api/sessions/%s/feel" % sid, json={"option": 1}).status_code == 503
        assert c.post("/api/sessions", json={"config": "staircase",
                                             "participant": "p09"}).status_code == 503
        s = Session.open(lab.live[sid].session.path)
        assert [x["answer"] for x in s.answers()] == ["A", "B"]
        assert [p.name for p in (tmp_path / "data" / "p09").iterdir()] == [s.path.name]
        assert c.get("/").status_code == 200                    # the page still loads
        vb2 = VirtualBoard(image="source")                      # plugged back in
        vb2.__enter__()
        try:
            owner.port = vb2.port
            assert c.get("/api/status").status_code == 200
            r = c.get("/api/sessions/%s" % sid)          # the page reloads: plays again
            assert r.status_code == 200 and r.json()["answers_so_far"] == 2
            assert r.json()["playing"] == 0
            q = lab.live[sid].question
            assert owner.scene_source() == lab.owner.push(q.options[0])[1]
            r = c.post("/api/sessions/%s/answer" % sid, json={"answer": "unsure", "question": 2})
            assert r.status_code == 200 and "board_lost" not in r.json()
            assert [x["answer"] for x in Session.open(s.path).answers()] == ["A", "B", "unsure"]
        finally:
            owner.close()
            lab.close()
            vb2.stop()


def test_browser_tabs_at_once_are_served_one_at_a_time(tmp_path):
    """Six tabs (threads) feel and answer on their own sessions at once
    against `texelpad lab`: every request is answered, every session file
    holds exactly its tab's answers in order, and the board ends playing the
    scene of one of the last requests - pushes are never interleaved. An
    answer to a question whose scene another tab replaced meanwhile is
    refused (409: the board does not play it now); the tab feels it again
    and answers, as the page does."""
    import threading
    import urllib.error
    import urllib.request

    def call(url, body=None):
        req = urllib.request.Request(url, data=None if body is None else json.dumps(body).encode(),
                                     headers={"content-type": "application/json"},
                                     method="GET" if body is None else "POST")
        with urllib.request.urlopen(req, timeout=60) as r:
            return json.loads(r.read())

    with lab_process(tmp_path) as (url, _):
        sids = [call(url + "api/sessions", {"config": "pursuit-4sin", "participant": "t%d" % k,
                                            "seed": k})["id"] for k in range(6)]
        errors, sent = [], {sid: [] for sid in sids}

        def tab(sid):
            # an answer counts once the lab took it (200); a 409 (another tab played since)
            # is felt again and answered again, as the page does. Six tabs on one board
            # contend for it: a tab that loses every round gives up (the board belongs to
            # whoever felt last - test_lab_robust), and the file must still hold exactly
            # the answers the lab took
            try:
                for i in range(8):
                    a = ["A", "B", "unsure"][(i + len(sid)) % 3]
                    for _ in range(200):
                        call(url + "api/sessions/%s/feel" % sid, {"option": i % 2})
                        try:
                            call(url + "api/sessions/%s/answer" % sid, {"answer": a, "question": i})
                            sent[sid].append(a)
                            break
                        except urllib.error.HTTPError as e:
                            if e.code != 409:
                                raise
                    else:
                        return
            except Exception as e:          # noqa: BLE001 - reported below
                errors.append(repr(e))

        threads = [threading.Thread(target=tab, args=(sid,)) for sid in sids]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert not errors
        assert sum(len(v) for v in sent.values()) >= 8, sent    # the lab made progress
        playing = call(url + "api/scene")["scene"]
        # what each session last played (the lab's own record): the board plays one of them
        lasts = [call(url + "api/sessions/%s/monitor" % sid)["playing_scene"] for sid in sids]
    assert playing in lasts
    for sid in sids:
        s = Session.open(tmp_path / (sid + ".jsonl"))
        assert [r["answer"] for r in s.answers()] == sent[sid]


def test_the_searchs_friction_slider_plays_and_is_answered_as_it_plays(lab, port):
    # seed 003's friction slider: a feel with a level plays that candidate at that gain; an
    # answer must carry the level that plays (409 otherwise, nothing changed); the state keeps it
    r = lab.post("/api/sessions", json={"config": "search-4sin", "participant": "s1", "seed": 3})
    sid = r.json()["id"]
    lv = lab.lab.live[sid]
    q = lab.get("/api/sessions/%s" % sid).json()["question"]
    assert q["level"] == {"range": [0.2, 1.0], "start": 1.0, "step": 0.01}
    assert lv.session.header["config"]["cma_update"] == "rank_one"
    assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 2, "level": 0.55}
                    ).json() == {"playing": 2}
    assert _playing(lab)["regions"][1]["texture"]["gain"] == 0.55
    for bad in (1.2, "x", True):
        r = lab.post("/api/sessions/%s/feel" % sid, json={"option": 1, "level": bad})
        assert r.status_code == 400 and "level" in r.json()["error"], r.text
    assert _playing(lab)["regions"][1]["texture"]["gain"] == 0.55
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": {"choose": 2}, "question": 0})
    assert r.status_code == 409 and "level answered (1.0) is not what plays (0.55)" in r.text
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": {"choose": 2, "level": 0.55},
                                                         "question": 0})
    assert r.status_code == 200, r.text
    assert lv.state.level == 0.55 and lv.state.tunings == 1
    # the next iteration starts at that level, every candidate
    assert _playing(lab)["regions"][1]["texture"]["gain"] == 0.55
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": {"stop": True}, "question": 1})
    assert r.status_code == 200, r.text
    # replayed from the file: the same level and tunings
    from texelpad.study import protocols
    st = protocols.replay(Session.open(lv.session.path))
    assert (st.level, st.tunings, st.cma_update) == (0.55, 1, "rank_one")


def test_seed_003s_phase_2_rates_the_textures_stopped_searches_saved(lab, port):
    # Phase 1: two participants' searches, each saving a texture and stopping
    sids = []
    for who, ref in (("s2", "4sin"), ("s3", "pink")):
        r = lab.post("/api/sessions", json={"protocol": "search", "participant": who,
                                            "seed": 4, "reference": {"kind": "reference",
                                                                     "name": ref}})
        sid = r.json()["id"]
        sids.append(sid)
        for n, a in enumerate(({"choose": 1, "level": 1.0}, {"save": 2, "level": 1.0})):
            assert lab.post("/api/sessions/%s/answer" % sid,
                            json={"answer": a, "question": n}).status_code == 200
    # not stopped yet: refused, and nothing made
    r = lab.post("/api/sessions", json={"config": "evaluate-search", "participant": "e1",
                                        "matches_from": sids})
    assert r.status_code == 400 and "is not stopped" in r.json()["error"], r.text
    r = lab.post("/api/sessions", json={"config": "evaluate-search", "participant": "e1"})
    assert r.status_code == 400 and "give matches_from" in r.json()["error"], r.text
    for sid in sids:            # (each feels its question again, then stops)
        assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 0}).status_code == 200
        assert lab.post("/api/sessions/%s/answer" % sid,
                        json={"answer": {"stop": True}, "question": 2}).status_code == 200
    saved = [lab.lab.live[sid].state.saved[-1]["params"] for sid in sids]
    # Phase 2: another participant rates them
    r = lab.post("/api/sessions", json={"config": "evaluate-search", "participant": "e1",
                                        "matches_from": sids, "seed": 6})
    assert r.status_code == 200, r.text
    eid = r.json()["id"]
    st = lab.lab.live[eid].state
    h = lab.lab.live[eid].session.header["config"]
    assert [t["texture"] for t in h["textures"]] == saved
    assert h["match_source"] == ", ".join(sids)
    # 2 real, 2 data-driven stand-ins, 2 saved: 6 x 3 adjectives + 4 similarity pairs
    assert len(st.plan) == 22
    for n in range(22):
        step, t, adjective = st.current
        q = lab.get("/api/sessions/%s" % eid).json()["question"]
        if step == "similarity":
            assert q["options"] == ["real", "virtual"]
            assert _playing(lab)["regions"][0]["texture"] == {"kind": "reference",
                                                              "name": t["reference"]}
            assert lab.post("/api/sessions/%s/feel" % eid, json={"option": 1}).status_code == 200
            if t["source"] == "preference":
                assert _playing(lab)["regions"][0]["texture"]["pitch_db"] == \
                    t["texture"]["pitch_db"]
        else:
            assert q["adjective"] == adjective and q["options"] == ["texture"]
        assert lab.post("/api/sessions/%s/answer" % eid, json={"answer": 2.5, "question": n}
                        ).status_code == 200
    assert st.done and len(st.ratings) == 22
