"""Session files from before the protocols followed the papers (header format
texelpad-session/1, made by texelpad at commit 9ec54e9 with
tests/study/data/legacy/make_legacy.py) replay as they ran: reading such a
header fills in the old defaults (study/legacy.py), so every question's scene
is the one the file recorded, and export reads them. New sessions record
every field of their protocol's resolved Config."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from texelpad.study import protocols, questions
from texelpad.study.export import rows
from texelpad.study.legacy import OLD_DEFAULTS
from texelpad.study.session import FORMAT, Session

LEGACY = Path(__file__).with_name("data") / "legacy"
DISPLAY = {"positions": 19200, "dx_um": 5.3}
FILES = sorted(p.name for p in LEGACY.glob("*.jsonl")
               if not p.name.startswith(("quant-v2", "v3-")))
V2_FILES = sorted(p.name for p in LEGACY.glob("quant-v2-*.jsonl"))
V3_FILES = sorted(p.name for p in LEGACY.glob("v3-*.jsonl"))


def test_there_is_an_old_session_of_every_protocol_that_was():
    protos = {json.loads(open(LEGACY / f).readline())["protocol"] for f in FILES}
    assert protos == set(OLD_DEFAULTS) and len(FILES) == 5


@pytest.mark.parametrize("name", FILES)
def test_an_old_session_replays_question_by_question(name, tmp_path):
    s = Session.open(LEGACY / name)
    assert s.header["format"] == "texelpad-session/1" and s.header["legacy"]
    h = s.header
    proto = h["protocol"]
    state = protocols.start(proto, h["config"], h["seed"])
    records = list(s.answers())
    assert records
    for k, rec in enumerate(records):
        q = questions.ask(proto, state, h, DISPLAY)
        if proto == "free":
            a = rec["answer"]
            scene, _ = questions.slider_scene(state, h, DISPLAY, a["pitch_db"],
                                              a["irregularity_db"], 0)
        else:
            scene = q.options[0]
        assert scene == rec["scene"], (name, k)
        detail = json.loads(json.dumps(q.detail))       # (newer details say more)
        assert {key: detail.get(key) for key in rec["state"]} == rec["state"], (name, k)
        protocols.apply(proto, state, rec["answer"])
    again = protocols.replay(s)
    for attr in ("matches", "ratings", "track", "history"):
        if hasattr(state, attr):
            assert getattr(again, attr) == getattr(state, attr)
    assert len(rows(s)) == len(records)             # export reads it
    # a copy goes on: an answer appended to an old file keeps its header and replays
    copy = tmp_path / name
    copy.write_bytes((LEGACY / name).read_bytes())
    c = Session.open(copy)
    st = protocols.replay(c)
    if not st.done:
        a = records[-1]["answer"]
        c.append({"answer": a})
        protocols.apply(proto, st, a)
        c2 = Session.open(copy)
        assert c2.header["format"] == "texelpad-session/1"
        assert len(list(c2.answers())) == len(records) + 1
        protocols.replay(c2)


def test_a_new_sessions_header_names_every_choice(tmp_path):
    for proto, config in (("free", {}), ("pursuit", {}), ("staircase", {"condition": "wide"}),
                          ("mapping", {}), ("quant", {"matches": {
                              r: {"pitch_db": 1.0, "irregularity_db": -10.0}
                              for r in ("2sin", "3sin", "4sin", "white", "pink", "blue",
                                        "square", "triangle", "sawtooth")}})):
        state = protocols.start(proto, config, 3)
        full = protocols.resolved(proto, state, dict(config, texture_format=2))
        s = Session.create(tmp_path, proto, "p", full, 3)
        h = Session.open(s.path).header
        assert h["format"] == FORMAT and "legacy" not in h
        fields = set(type(state.config).__dataclass_fields__)
        assert fields <= set(h["config"]), (proto, fields - set(h["config"]))
        # the header starts the same protocol
        again = protocols.start(proto, h["config"], 3)
        assert again.config == state.config


def _digested(scene: dict) -> dict:
    """The scene as make_v2.py keeps it: each sample array as its sha256."""
    import hashlib
    out = json.loads(json.dumps(scene))
    for reg in out.get("regions", []):
        tex = reg.get("texture", reg)
        if "u16" in tex:
            tex["u16"] = "sha256:" + hashlib.sha256(json.dumps(tex["u16"]).encode()).hexdigest()
    return out


@pytest.mark.parametrize("name", V2_FILES)
def test_a_v2_quant_session_replays_as_it_ran(name):
    # format /2, made by texelpad at 882b9d3 (make_v2.py) before the rater's pitch file was
    # relabelled: its rater trials played the rows as they were read then (by statistics,
    # square's and triangle's swapped; or 'app' by index) and 'lab' read the app's rows in the
    # family order - every one of its 27 scenes, the rater's samples included, plays again
    s = Session.open(LEGACY / name)
    h = s.header
    assert s.header["format"] == "texelpad-session/2" and h["legacy"]
    assert h["config"]["rater_rows"] in ("statistics-2026", "index-2026")
    assert h["config"]["lab_rows"] == "family_order"
    state = protocols.start("quant", h["config"], h["seed"])
    records = list(s.answers())
    assert len(records) == 27
    for k, rec in enumerate(records):
        q = questions.ask("quant", state, h, DISPLAY)
        assert _digested(q.options[0]) == rec["scene"], (name, k)
        protocols.apply("quant", state, rec["answer"])
    assert state.done and len(rows(s)) == 27
    # the same session under today's reading plays other rater rows on some trials
    fresh = dict(h["config"], rater_rows="by_texture", lab_rows="test_order")
    if fresh.get("order") == "lab":
        fresh["exemplars"] = ["4sin", "blue", "sawtooth"]
    now = protocols.start("quant", fresh, h["seed"])
    differ = 0
    for rec in records:
        q = questions.ask("quant", now, h, DISPLAY)
        differ += _digested(q.options[0]) != rec["scene"]
        protocols.apply("quant", now, rec["answer"])
    assert differ > 0


def _close(a, b) -> bool:
    """a == b, floats to 1e-12 relative (the lists and dicts of a question's state)."""
    if isinstance(a, float) and isinstance(b, float):
        return a == pytest.approx(b, rel=1e-12, abs=0)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("name", V3_FILES)
def test_a_v3_session_replays_as_it_ran(name):
    # format /3, made by texelpad at 8c349e6 (make_v3.py) before issue 31 made the lab's apps'
    # ways the defaults: the similarity matrix on a split display in a seeded order, the
    # pursuit's points above Nyquist clamped. Every scene every question offered plays again.
    s = Session.open(LEGACY / name)
    h = s.header
    assert h["format"] == "texelpad-session/3" and h["legacy"]
    proto = h["protocol"]
    if proto == "quant":
        assert h["config"]["presentation"] == "split" and h["config"]["order"] == "seeded"
    elif proto == "pursuit":
        assert h["config"]["above_nyquist"] == "clamp"
    else:
        assert (h["config"]["cma_update"], h["config"]["level_slider"]) == ("active", False)
    state = protocols.start(proto, h["config"], h["seed"])
    records = list(s.answers())
    assert len(records) == {"quant": 9, "pursuit": 20, "search": 9}[proto]
    for k, rec in enumerate(records):
        q = questions.ask(proto, state, h, DISPLAY)
        assert q.options == rec["scenes"], (name, k)
        detail = json.loads(json.dumps(q.detail))
        # the search's state to 1e-12 relative: CMA-ES's step size is numpy's arithmetic,
        # whose SIMD paths sum in another order on another CPU (an AVX-512 CI machine
        # gave sigma 0.16893968797910042 for the recorded ...044, the scenes the same)
        assert _close({key: detail.get(key) for key in rec["state"]}, rec["state"]), \
            (name, k, detail, rec["state"])
        protocols.apply(proto, state, rec["answer"])
    assert state.done and len(rows(s)) == len(records)
    # today's defaults play it otherwise: the app's order one texture at a time, or the
    # points above Nyquist aliased (the fixture's pursuit always chose the higher pitch)
    fresh = {k: v for k, v in h["config"].items()
             if k not in ("presentation", "order", "above_nyquist", "cma_update",
                          "level_slider")}
    now = protocols.start(proto, fresh, h["seed"])
    differ = 0
    for rec in records:
        q = questions.ask(proto, now, h, DISPLAY)
        differ += q.options != rec["scenes"]
        protocols.apply(proto, now, rec["answer"])
    if proto == "search":
        # with the slider, every candidate says its gain (1.0 from the start): each scene
        # differs; and seed 003's rank-one update moves the mean otherwise
        assert differ == 9
        assert now.mean != state.mean and now.history[0]["candidates"] == \
            state.history[0]["candidates"]
        return
    above = sum(max(rec["state"]["A"]["pitch_db"], rec["state"]["B"]["pitch_db"]) > 19.747
                for rec in records) if proto == "pursuit" else None
    assert differ == (9 if proto == "quant" else above) and differ > 0
