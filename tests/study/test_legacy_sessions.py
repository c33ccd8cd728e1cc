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
FILES = sorted(p.name for p in LEGACY.glob("*.jsonl"))


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
