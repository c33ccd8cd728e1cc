"""Seed 001's second experiment through the lab's API on a virtual board: nine
slider trials (reference left as the band-pass samples, the sliders' texel
rendering right - seed 001's stimulus: 1 mm texels, pitches above 1 c/mm, no
phase continuity), then 25 ratings 0..10; every answer in the file, the
session replays, a refused request changes nothing."""
from __future__ import annotations

import json

from texelpad.study import protocols
from texelpad.study.mapping import DEFAULT_RATINGS, slider_values
from texelpad.study.session import Session

from texel.gen.lognormal import to_db


def _playing(lab) -> dict:
    return lab.lab.owner.scene_source()


def _n(lab, sid) -> int:
    return lab.lab._number(lab.lab.live[sid])


def test_a_mapping_session_end_to_end(lab, port):
    r = lab.post("/api/sessions", json={"config": "mapping", "participant": "p11", "seed": 6})
    assert r.status_code == 200, r.text
    sid, q = r.json()["id"], r.json()["question"]
    assert q["kind"] == "sliders" and q["sliders"] == {"pitch": [0.0, 100.0],
                                                       "irregularity": [0.0, 100.0], "step": 1.0}
    assert q["confidence"] is None and q["of"] == 9 and r.json()["sliders"] == [50.0, 50.0]
    assert "pitch_db" not in json.dumps(q) and "bp-" not in json.dumps(q)        # blind
    live = lab.lab.live[sid]
    # the start plays: the reference's 9,600 samples left, the rendering right
    left, right = (reg["texture"] for reg in _playing(lab)["regions"])
    assert left["kind"] == "samples"
    assert right["texel_samples"] == 189 and right["min_cpmm"] == 1.0
    assert right["phase"] == "reset"
    assert (right["pitch_db"], right["irregularity_db"]) == to_db(*slider_values(50.0, 50.0))
    # a slider change re-renders; a value off the slider is refused and changes nothing
    r = lab.post("/api/sessions/%s/feel" % sid, json={"pitch": 10, "irregularity": 0,
                                                       "question": 0})
    assert r.status_code == 200, r.text
    right = _playing(lab)["regions"][1]["texture"]
    assert right["pitch_db"] == to_db(0.75 * 1.04 ** 10, 0.0)[0]
    before = _playing(lab)
    for bad in ({"pitch": 101, "irregularity": 0}, {"pitch_db": 3, "irregularity_db": 1},
                {"option": 0}):
        assert lab.post("/api/sessions/%s/feel" % sid, json=bad).status_code == 400
    assert _playing(lab) == before
    answers = []
    for k in range(9):
        a = {"pitch": 10 * k, "irregularity": 5 * k}
        answers.append(a)
        assert lab.post("/api/sessions/%s/feel" % sid, json=a).status_code == 200
        assert lab.post("/api/sessions/%s/answer" % sid,
                        json={"answer": a, "question": _n(lab, sid)}).status_code == 200
    q = lab.get("/api/sessions/%s" % sid).json()["question"]
    assert q["kind"] == "rate" and q["answers"] == list(range(11)) and q["of"] == 25
    pairs = []
    while not live.state.done:
        pairs.append(live.state.current)
        left, right = (reg["texture"] for reg in _playing(lab)["regions"])
        assert left["kind"] == "samples" and right["kind"] == "texel"
        assert lab.post("/api/sessions/%s/answer" % sid,
                        json={"answer": 7, "question": _n(lab, sid)}).status_code == 200
    assert sorted(pairs) == sorted(DEFAULT_RATINGS)
    s = Session.open(live.session.path)
    file = [x["answer"] for x in s.answers()]
    assert file == answers + [7] * 25 and s.finished
    st = protocols.replay(s)
    assert st.matches == live.state.matches and st.ratings == live.state.ratings


def test_a_slider_answer_must_be_what_plays_and_a_restart_plays_the_recorded_scene(lab, port):
    """The match recorded is the texture that played: an answer naming other
    slider values is refused (409) and changes nothing; a server restart
    mid-trial plays again the scene the file's last move recorded (the same
    seed), not a new rendering of the same sliders."""
    for config, body, other in (("mapping", {"pitch": 33, "irregularity": 44},
                                 {"pitch": 30, "irregularity": 44}),
                                ("free-nine", {"pitch_db": 2.5, "irregularity_db": -7.0},
                                 {"pitch_db": 2.5, "irregularity_db": -7.5})):
        sid = lab.post("/api/sessions", json={"config": config, "participant": "p12",
                                              "seed": 4}).json()["id"]
        assert lab.post("/api/sessions/%s/feel" % sid,
                        json=dict(body, question=0)).status_code == 200
        playing = _playing(lab)
        ans = dict(other, confidence=3) if config == "free-nine" else other
        r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": ans, "question": 0})
        assert r.status_code == 409 and "not what plays" in r.json()["error"]
        live = lab.lab.live[sid]
        assert not list(live.session.answers()) and _playing(lab) == playing
        # a restart mid-trial: the recorded scene plays again, the same texture
        lab.lab.live.clear()
        r = lab.get("/api/sessions/%s" % sid).json()
        assert r["sliders"] == list(body.values())
        assert _playing(lab) == playing
        ok = dict(body, confidence=3) if config == "free-nine" else body
        assert lab.post("/api/sessions/%s/answer" % sid,
                        json={"answer": ok, "question": 0}).status_code == 200
        rec = list(Session.open(lab.lab.live[sid].session.path).answers())[0]
        assert rec["scene"] == playing
