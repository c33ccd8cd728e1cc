"""Issue 31 item 4: the staircase records the finger. While a staircase
question plays, the lab reads the board's own telemetry (the virtual board,
its finger scripted from the host as a participant would swipe) and writes it
into the session as it happens - finger records, appended and fsynced like the
answers - so a server killed mid-trial keeps what was read; export gives
seed 001's swipe speed and directional proportion per trial."""
from __future__ import annotations

import time

from texelpad.study import finger as F
from texelpad.study.export import rows
from texelpad.study.session import Session



def _n(lab, sid) -> int:
    return lab.lab._number(lab.lab.live[sid])


def _playing(lab) -> dict:
    return lab.lab.owner.scene_source()


def _swipe(lab, keyframes):
    """Script the virtual board's finger (ms, mm), as the page's owner holds the port."""
    return lab.lab.owner._call(lambda b: b.finger(keyframes))


def test_a_staircase_records_the_finger_as_it_happens_and_exports_its_swipes(lab, port):
    r = lab.post("/api/sessions", json={"config": "staircase", "participant": "f1", "seed": 5})
    assert r.status_code == 200, r.text
    sid = r.json()["id"]
    lv = lab.lab.live[sid]
    assert lv.session.header["config"]["finger_hz"] == F.FINGER_HZ
    # rightward swipes only, lifted back: 10 -> 90 mm in 1 s (80 mm/s), twice
    _swipe(lab, [(0, 10.0), (1000, 90.0), (1001, None), (1500, None), (1501, 10.0),
                 (2500, 90.0), (2501, None)])
    time.sleep(2.0 + 2 * F.FINGER_POLL_S)
    # written as it happens: on disk before any answer (a server killed now keeps it)
    on_disk = [x for x in Session.open(lv.session.path).records if x.get("kind") == "finger"]
    assert on_disk and all(x["question"] == 0 and x["option"] == 0 for x in on_disk)
    assert sum(len(x["pos"]) for x in on_disk) > 100
    # the participant feels option 1, swiping both ways, then answers
    assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 1}).status_code == 200
    _swipe(lab, [(0, 10.0), (800, 90.0), (1600, 10.0), (1700, None)])
    time.sleep(1.9)
    odd = lv.question.odd
    r = lab.post("/api/sessions/%s/answer" % sid, json={"answer": odd, "question": _n(lab, sid)})
    assert r.status_code == 200, r.text
    s = Session.open(lv.session.path)
    recs = F.of_question(s.records, 0)
    n_answer = [k for k, x in enumerate(s.records) if x.get("kind") == "answer"][0]
    assert all(s.records.index(x) < n_answer for x in recs)      # before its answer
    one, both = ([x for x in recs if x["option"] == k] for k in (0, 1))
    assert one and both
    m1, m2 = F.measures(one), F.measures(both)
    # option 0: rightward only at 80 mm/s; option 1: both ways at 100 mm/s
    print("\nfinger: one way %.2f mm/s (SD %.2f), proportion %.3f, %d samples; both ways "
          "%.2f mm/s (SD %.2f), proportion %.3f, %d samples"
          % (m1["speed_mm_s"], m1["speed_sd_mm_s"], m1["directional_proportion"],
             m1["samples"], m2["speed_mm_s"], m2["speed_sd_mm_s"],
             m2["directional_proportion"], m2["samples"]))
    assert m1["left"] == 0 and m1["right"] > 100
    assert abs(m1["speed_mm_s"] - 80.0) < 4.0, m1["speed_mm_s"]
    assert m2["left"] > 50 and m2["right"] > 50
    assert abs(m2["speed_mm_s"] - 100.0) < 5.0, m2["speed_mm_s"]
    assert m1["directional_proportion"] > 0.3 > abs(m2["directional_proportion"])
    # the board's clock: samples 1/finger_hz apart (10 ms), none read twice
    t = [u for x in recs for u in x["t_us"]]
    assert len(set(t)) == len(t)
    steps = [b - a for a, b in zip(F.unwrap(t), F.unwrap(t)[1:])]
    assert abs(sorted(steps)[len(steps) // 2] - 0.01) < 0.002
    # export: the trial's swipe columns
    (row,) = rows(s)
    m = F.measures(recs)
    assert row["finger_samples"] == m["samples"]
    assert row["swipe_speed_mm_s"] == round(m["speed_mm_s"], 6)
    assert row["directional_proportion"] == round(m["directional_proportion"], 6)
    # the next question's samples start after this answer: question 1 holds none from before
    time.sleep(2 * F.FINGER_POLL_S)
    later = F.of_question(Session.open(lv.session.path).records, 1)
    assert all(t0 not in set(t) for x in later for t0 in x["t_us"])
    # the next question starts at its option 0; what came before its push is not its own
    assert later and all(x["option"] == 0 for x in later)
    assert all(0 < (u - t[-1]) % F.WRAP < F.WRAP // 2 for x in later for u in x["t_us"])
    assert _playing(lab) is not None


def test_a_protocol_that_records_no_finger_writes_none(lab, port):
    r = lab.post("/api/sessions", json={"protocol": "pursuit", "participant": "f2", "seed": 1})
    sid = r.json()["id"]
    _swipe(lab, [(0, 10.0), (1000, 90.0)])
    time.sleep(1.0 + 2 * F.FINGER_POLL_S)
    assert lab.post("/api/sessions/%s/feel" % sid, json={"option": 1}).status_code == 200
    s = Session.open(lab.lab.live[sid].session.path)
    assert not [x for x in s.records if x.get("kind") == "finger"]
    assert lab.lab._recorder is None          # (no thread for a lab that records nothing)
