"""The scene editor (issue 12, item 6: painting in the browser):
host/texelpad/web/editor.py and static/editor.{html,js} against a real
virtual board (the device image under the MicroPython unix port, on a pty;
the fixtures `port` and `lab` of tests/web/conftest.py).

- Each kind painted (texel, reference, constant, brush) plays on the board
  as the editor answered it (GET /api/scene, the board's own canonical
  scene).
- A brush from a file and from a design: the board plays a "brush" region
  with the document's numbers, the editor's strip is texel.gen.brush.paint
  of that brush and seed (8-bit), and the board's own telemetry under the
  virtual finger is the painting itself (uint16, exact).
- Overlaps: a later region wins; earlier ones are trimmed, split or dropped,
  judged on the board's positions.
- Refusals (a bad kind, bad brush numbers, a brush name leading out of the
  folder, a body that is not JSON, a region off the display, ...) answer 400
  with the reason, push nothing (the board's push count stays) and write no
  file; 503 when the board is gone.
- In Chromium (slow): /editor, a drag on the strip, a designed brush picked
  and painted; the board plays it where the drag was.
"""
from __future__ import annotations

import base64
import json
import os
import shutil
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from starlette.testclient import TestClient

import texel
import texel.runtime.scene as S
from texel.gen import brush as B
from texel.gen import params as P
from texelpad.brush import document as D
from texelpad.web import editor as E
from texelpad.web import strip as strip_mod
from texelpad.web.owner import BoardOwner
from texelpad.web.server import Lab, make_app

from support.lab import lab_process

BASE = "http://127.0.0.1"
DISPLAY = {"positions": 19200, "dx_um": 5.3}
LENGTH = 101.76
PINK = {"shape": "pink", "level": 0.05, "mean": 0.5}


def pos(mm: float) -> int:
    return S.to_position(mm, DISPLAY["dx_um"])


def u8_of(strip: dict[str, Any]) -> np.ndarray:
    return np.frombuffer(base64.b64decode(strip["amplitude"]), dtype=np.uint8)


def region(s: float, e: float, tex: dict[str, Any]) -> dict[str, Any]:
    return {"start_mm": s, "end_mm": e, "texture": tex}


def paint(client, regions, **extra):
    r = client.post("/api/editor/scene", json=dict(regions=regions, **extra))
    assert r.status_code == 200, r.text
    return r.json()


def owner_regions(client) -> list[dict[str, Any]]:
    return client.lab.owner.scene_source()["regions"]


def folder(client) -> Path:
    return Path(client.lab.data) / "brushes"


def files(client) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder(client).iterdir())}


# --- the palette ------------------------------------------------------------------------
@pytest.mark.vboard
def test_the_palette_lists_what_can_be_painted(lab):
    D.save(D.design("brown", 0.1, 0.4, name="rough"), folder(lab) / "rough.json")
    D.save(D.design("blue", 0.02, 0.6), folder(lab) / "fine.tpb")
    (folder(lab) / "broken.json").write_text("{\"k\": [1]}")
    (folder(lab) / "notes.txt").write_text("not a brush")
    r = lab.get("/api/editor/palette")
    assert r.status_code == 200, r.text
    p = r.json()
    assert p["references"] == texel.reference_names()
    assert sorted(p["shapes"]) == sorted(D.SHAPES)
    assert p["display"] == {"positions": 19200, "dx_um": 5.3, "length_mm": LENGTH}
    for k in ("pitch_db", "irregularity_db", "texel_samples", "seed"):
        kind, default, lo, hi = P.SPEC[k]
        assert (p["texel"][k]["min"], p["texel"][k]["max"], p["texel"][k]["default"]) == \
            (lo, hi, default)
    listed = {b["file"]: b for b in p["brushes"]}
    assert sorted(listed) == ["broken.json", "fine.tpb", "rough.json"]    # not notes.txt
    assert listed["rough.json"]["name"] == "rough" and "error" not in listed["rough.json"]
    assert "lam" in listed["broken.json"]["error"] or "k" in listed["broken.json"]["error"]
    page = lab.get("/editor")
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    for src in ("/static/strip.js", "/static/lab.js", "/static/editor.js"):
        assert '<script src="%s">' % src in page.text
        assert lab.get(src).status_code == 200
    assert lab.get("/api/editor/palette?x=1").status_code == 400


# --- painting ---------------------------------------------------------------------------
@pytest.mark.vboard
def test_each_kind_is_painted_and_plays_as_answered(lab):
    regions = [
        region(0, 20, {"kind": "texel", "pitch_db": 6.0, "irregularity_db": -20.0,
                       "texel_samples": 60, "seed": 4}),
        region(20, 40, {"kind": "reference", "name": "4sin"}),
        region(40, 60, {"kind": "constant", "level": 0.3}),
        region(60, 101.76, {"kind": "brush", "design": PINK, "seed": 9})]
    a = paint(lab, regions, name="four kinds")
    played = lab.get("/api/scene").json()["scene"]
    assert played == a["scene"]                         # the board's own canonical scene
    assert played["name"] == "four kinds"
    assert [r["texture"]["kind"] for r in played["regions"]] == \
        ["texel", "reference", "constant", "brush"]
    tex = played["regions"][0]["texture"]
    assert (tex["texel_samples"], tex["seed"], tex["v"]) == (60, 4, 2)     # format 2 by default
    assert played["regions"][2]["texture"]["level"] == 0.3
    assert played["regions"][3]["texture"]["seed"] == 9
    # the editor's form comes back: the brush by its design, every label
    assert a["regions"][3]["texture"] == {"kind": "brush", "seed": 9,
                                          "design": dict(PINK, k=2.0)}
    assert [r["label"] for r in a["regions"]] == [
        "texel 6.0/-20.0 dB, 0.318 mm, seed 4", "reference 4sin", "constant 0.30",
        "brush pink 0.05/0.5, seed 9"]
    assert [r["from"] for r in a["regions"]] == [0, 1, 2, 3]
    # the strip: the board's rendering, labelled, and the same from GET
    strip = a["strip"]
    assert [g["label"] for g in strip["regions"]] == [r["label"] for r in a["regions"]]
    u16, _ = strip_mod.render(played, DISPLAY, strip["idle"])
    assert np.array_equal(u8_of(strip), strip_mod.to_u8(u16))
    assert lab.get("/api/editor/strip").json() == strip
    # loaded back (a reloaded page) in the editor's form
    back = lab.get("/api/editor/scene").json()
    assert back["scene_id"] == a["scene_id"]
    assert [(r["start_mm"], r["end_mm"], r["label"]) for r in back["regions"]] == \
        [(r["start_mm"], r["end_mm"], r["label"]) for r in a["regions"]]
    assert back["regions"][3]["texture"] == a["regions"][3]["texture"]


@pytest.mark.vboard
def test_a_kind_the_editor_has_no_form_of_comes_with_its_fields_and_plays(lab):
    """A region kind beyond the editor's hand-made forms (kinds/bump.py):
    the palette carries its module's FIELDS, a painted one plays as the
    board's canonical texture, labelled in the kind's own words."""
    p = lab.get("/api/editor/palette").json()
    assert [f["key"] for f in p["forms"]["bump"]] == ["shape", "width_mm", "height", "at", "level"]
    assert p["forms"]["bump"][0]["words"] == ["gaussian", "cosine", "edge"]
    assert "constant" not in p["forms"] and "texel" not in p["forms"]
    a = paint(lab, [region(10, 30, {"kind": "bump", "shape": "cosine", "width_mm": 5})])
    (r,) = lab.get("/api/scene").json()["scene"]["regions"]
    assert r["texture"] == {"kind": "bump", "shape": "cosine", "width_mm": 5.0, "height": 1.0,
                            "at": 0.5, "level": 1.0}
    assert a["regions"][0]["label"] == "bump cosine 5 mm, height 1"
    bad = lab.post("/api/editor/scene", json={"regions": [
        region(10, 30, {"kind": "bump", "width_mm": 0})]})
    assert bad.status_code == 400 and "width_mm: 0 is out of range" in bad.json()["error"]
    assert lab.get("/api/scene").json()["scene"]["regions"][0]["texture"] == r["texture"]


def test_a_brush_from_a_file_and_from_a_design_is_what_the_board_paints(lab):
    owner = lab.lab.owner
    doc = D.design("brown", 0.08, 0.45, name="rough")
    D.save(doc, folder(lab) / "rough.json")
    saved = lab.post("/api/editor/brushes", json={"name": "bluish", "design":
                                                  {"shape": "blue", "level": 0.03, "mean": 0.6}})
    assert saved.status_code == 200 and saved.json()["saved"] == "bluish.json", saved.text
    assert D.load(folder(lab) / "bluish.json")["name"] == "bluish"
    designed = D.design("pink", 0.05, 0.5)
    a = paint(lab, [region(5.0, 45.0, {"kind": "brush", "file": "rough.json", "seed": 3}),
                    region(45.0, 80.0, {"kind": "brush", "design": PINK, "seed": 11}),
                    region(80.0, 101.76, {"kind": "brush", "file": "bluish.json", "seed": 0})])
    played = owner.scene_source()
    assert [r["texture"]["kind"] for r in played["regions"]] == ["brush"] * 3
    u8 = u8_of(a["strip"])
    u16_all, _ = strip_mod.render(played, DISPLAY, a["strip"]["idle"])
    cases = [(doc, 3, 5.0, 45.0), (designed, 11, 45.0, 80.0),
             (D.load(folder(lab) / "bluish.json"), 0, 80.0, 101.76)]
    for (d, seed, s, e), r in zip(cases, played["regions"]):
        assert r["texture"]["seed"] == seed
        assert r["texture"]["brush"] == {"k": d["k"], "lam": d["lam"], "range": d["range"]}
        n = pos(e) - pos(s)
        want = np.frombuffer(B.paint(B.validate(r["texture"]["brush"]), seed, n), dtype=np.uint16)
        assert np.array_equal(want, D.paint(d, seed, n))
        assert np.array_equal(u16_all[pos(s):pos(e)], want)
        assert np.array_equal(u8[pos(s):pos(e)], strip_mod.to_u8(want))
    assert [g["label"] for g in a["strip"]["regions"]] == [
        "brush rough.json, seed 3", "brush pink 0.05/0.5, seed 11", "brush bluish.json, seed 0"]
    # the board's own record of what it plays under the virtual finger
    for mm in (20.0, 60.0):
        assert lab.post("/api/finger", json={"position_mm": mm}).status_code == 200
        time.sleep(0.03)
        samples = owner.telemetry(0.12, rate_hz=250)
        assert len(samples) >= 5
        assert all(p >= 0 and amp == u16_all[p] for _, p, amp in samples), mm
    assert lab.post("/api/finger", json={"position_mm": None}).status_code == 200
    # the strip renders only what an edit made or trimmed: a constant painted
    # over the last brush's end is two regions rendered, not four
    renders = lab.lab.editor.renders
    n0 = renders.renders
    b = paint(lab, [{k: x[k] for k in ("start_mm", "end_mm", "texture")} for x in a["regions"]]
              + [region(95.0, 101.76, {"kind": "constant", "level": 0.2})])
    assert renders.renders == n0 + 2
    u16_b, _ = strip_mod.render(owner.scene_source(), DISPLAY, b["strip"]["idle"])
    assert np.array_equal(u8_of(b["strip"]), strip_mod.to_u8(u16_b))
    assert np.array_equal(u16_b[:pos(80.0)], u16_all[:pos(80.0)])


@pytest.mark.vboard
def test_a_later_region_wins_and_trims_splits_or_covers_the_earlier_ones(lab):
    texel6 = {"kind": "texel", "pitch_db": 6.0, "irregularity_db": -20.0, "seed": 1}
    const = {"kind": "constant", "level": 0.2}
    ref = {"kind": "reference", "name": "pink"}
    brush = {"kind": "brush", "design": PINK, "seed": 2}
    a = paint(lab, [region(0, 60, texel6),          # split by the brush
                    region(60, 80, const),          # trimmed on its left by the reference
                    region(75, 90, ref),            # ... which the next one covers
                    region(20, 40, brush),
                    region(74, 95, {"kind": "constant", "level": 0.9})])
    got = [(r["start_mm"], r["end_mm"], r["from"]) for r in a["regions"]]
    assert got == [(0, 20, 0), (20, 40, 3), (40, 60, 0), (60, 74, 1), (74, 95, 4)]
    played = lab.get("/api/scene").json()["scene"]["regions"]
    assert [(r["start_mm"], r["end_mm"]) for r in played] == [g[:2] for g in got]
    assert [r["texture"]["kind"] for r in played] == \
        ["texel", "brush", "texel", "constant", "constant"]
    # each piece keeps its texture (the split texel's two pieces: the same parameters)
    assert played[0]["texture"] == played[2]["texture"]
    # painting on top of what plays: the page sends the answer back plus the new one
    b = paint(lab, [{k: x[k] for k in ("start_mm", "end_mm", "texture")} for x in a["regions"]]
              + [region(10, 50, const)])
    assert [(r["start_mm"], r["end_mm"]) for r in b["regions"]] == \
        [(0, 10), (10, 50), (50, 60), (60, 74), (74, 95)]
    # touching in positions is not overlapping: 30.0 and 30.0005 mm are both position 5,660
    assert pos(30.0) == pos(30.0005) == 5660
    c = paint(lab, [region(0, 30.0005, const), region(30.0, 50, ref)])
    assert [(r["start_mm"], r["end_mm"]) for r in c["regions"]] == [(0, 30.0005), (30.0, 50)]
    assert [(r["start_mm"], r["end_mm"]) for r in owner_regions(lab)] == [(0, 30.0005), (30.0, 50)]
    # a piece that rounds to no position is dropped: [30.0, 30.0005) is none
    d = paint(lab, [region(0, 30.0005, const), region(0, 30.0, ref)])
    assert [(r["start_mm"], r["end_mm"], r["from"]) for r in d["regions"]] == [(0, 30.0, 1)]
    # painting the whole display covers everything
    e = paint(lab, [region(0, 50, const), region(50, 70, ref), region(0, LENGTH, brush)])
    assert [(r["start_mm"], r["end_mm"], r["from"]) for r in e["regions"]] == [(0, LENGTH, 2)]


@pytest.mark.vboard
def test_remove_clear_undo_and_a_scene_loaded_from_the_board(lab):
    owner = lab.lab.owner
    const = {"kind": "constant", "level": 0.4}
    brush = {"kind": "brush", "design": PINK, "seed": 5}
    first = paint(lab, [region(0, 50, const), region(50, 90, brush)])
    bare = lambda x: {k: x[k] for k in ("start_mm", "end_mm", "texture")}   # noqa: E731
    # remove region 1: the rest is sent
    rm = paint(lab, [bare(first["regions"][1])], base=first["scene_id"])
    assert [r["texture"]["kind"] for r in owner.scene_source()["regions"]] == ["brush"]
    # clear: the board's idle level everywhere, loaded back as no region
    clear = paint(lab, [], base=rm["scene_id"])
    assert clear["regions"] == []
    idle = owner.status()["scene"]["idle"]
    assert set(u8_of(clear["strip"]).tolist()) == {(idle + 128) // 257}
    assert lab.get("/api/editor/scene").json()["regions"] == []
    # undo (the page's history: the scene before) plays exactly what played
    undo = paint(lab, [bare(r) for r in first["regions"]], base=clear["scene_id"])
    assert undo["scene_id"] == first["scene_id"]
    assert owner.scene_source() == first["scene"]
    # a stale page: another page pushed since -> refused, nothing changes
    owner.push({"regions": [region(0, 10, {"kind": "reference", "name": "4sin"})]})
    pushes = owner.status()["pushes"]
    r = lab.post("/api/editor/scene", json={"regions": [], "base": undo["scene_id"]})
    assert r.status_code == 400 and "changed since" in r.json()["error"], r.text
    assert owner.status()["pushes"] == pushes
    # a scene pushed elsewhere with an upload and a brush the editor never saw:
    # held by id, and painting next to them keeps them
    values = [0.1, 0.9, 0.5, 0.7] * 50
    other = D.region(D.design("white", 0.02, 0.3), 77, 50.0, 80.0)
    owner.push({"regions": [region(0, 30, {"kind": "samples", "values": values}), other]})
    loaded = lab.get("/api/editor/scene").json()
    assert [r["texture"]["kind"] for r in loaded["regions"]] == ["kept", "kept"]
    assert "(as loaded)" in loaded["regions"][1]["label"]
    kept = paint(lab, [bare(r) for r in loaded["regions"]] + [region(20, 60, const)],
                 base=loaded["scene_id"])
    played = owner.scene_source()["regions"]
    assert [(r["start_mm"], r["end_mm"], r["texture"]["kind"]) for r in played] == \
        [(0, 20, "samples"), (20, 60, "constant"), (60, 80.0, "brush")]
    assert played[0]["texture"]["u16"] == [int(v * 65535 + 0.5) for v in values]
    assert played[2]["texture"]["seed"] == 77
    # a server that forgot what it held says so
    lab.lab.editor.memory.kept.clear()
    pushes = owner.status()["pushes"]
    r = lab.post("/api/editor/scene", json={"regions": [bare(x) for x in kept["regions"]]})
    assert r.status_code == 400 and "not held any more" in r.json()["error"], r.text
    assert owner.status()["pushes"] == pushes
    # ... and a reloaded page holds them again, by the same ids
    again = lab.get("/api/editor/scene").json()
    assert [r["texture"] for r in again["regions"]] == [r["texture"] for r in kept["regions"]]
    assert paint(lab, [bare(x) for x in again["regions"]])["scene_id"] == kept["scene_id"]


# --- refusals ---------------------------------------------------------------------------
@pytest.mark.vboard
def test_refused_requests_change_nothing_and_write_no_file(lab, tmp_path):
    owner = lab.lab.owner
    D.save(D.design("pink", 0.05, 0.5, name="ok"), folder(lab) / "ok.json")
    outside = tmp_path / "outside.json"
    D.save(D.design("white", 0.05, 0.5), outside)
    (folder(lab) / "link.json").symlink_to(outside)
    ok = {"kind": "constant", "level": 0.5}
    base = paint(lab, [region(0, 50, ok)])
    before, pushes, on_disk = owner.scene_source(), owner.status()["pushes"], files(lab)
    good = region(60, 70, {"kind": "reference", "name": "4sin"})
    lam = list(D.design("pink", 0.05, 0.5)["lam"])
    lam[3] = -1.0
    k_short = {"k": [2.0] * 10, "lam": lam, "range": [0, 1]}
    cases = [
        # kinds
        (region(0, 10, {"kind": "paint"}), "regions[1].texture.kind: expected one of"),
        (region(0, 10, {"kind": "samples", "values": [0.5]}), "texelpad push"),
        (region(0, 10, {"name": "4sin"}), "regions[1].texture.kind"),
        (region(0, 10, "4sin"), "expected a texture object"),
        (region(0, 10, {"kind": "reference", "name": "velvet"}),
         "regions[1].texture.name: unknown reference texture"),
        (region(0, 10, {"kind": "texel", "pitch_db": 30, "irregularity_db": -10}),
         "regions[1].texture.pitch_db"),
        (region(0, 10, {"kind": "constant", "level": 1.5}), "regions[1].texture.level"),
        # brush numbers
        (region(0, 10, {"kind": "brush", "brush": {"k": [2.0] * B.K, "lam": lam,
                                                   "range": [0, 1]}, "seed": 1}),
         "regions[1].texture.brush.lam[3]"),
        (region(0, 10, {"kind": "brush", "brush": k_short}), "regions[1].texture.brush.k"),
        (region(0, 10, {"kind": "brush", "design": dict(PINK, level=5)}),
         "regions[1].texture.design.level: expected a number in [0, 1]"),
        (region(0, 10, {"kind": "brush", "design": dict(PINK, level="0.1")}),
         "design.level"),
        (region(0, 10, {"kind": "brush", "design": dict(PINK, shape="purple")}),
         "design.shape: expected one of white, pink, brown, blue"),
        (region(0, 10, {"kind": "brush", "design": {"shape": "pink", "level": 0.1}}),
         "missing required key 'mean'"),
        (region(0, 10, {"kind": "brush", "design": dict(PINK, band=[1, 2])}),
         "unknown key 'band'"),
        (region(0, 10, {"kind": "brush", "design": dict(PINK, k=0.0)}), "design.k"),
        (region(0, 10, {"kind": "brush", "design": PINK, "seed": -1}), "texture.seed"),
        (region(0, 10, {"kind": "brush", "design": PINK, "seed": 2 ** 32}), "texture.seed"),
        (region(0, 10, {"kind": "brush", "design": PINK, "seed": True}), "texture.seed"),
        (region(0, 10, {"kind": "brush", "design": PINK, "file": "ok.json"}), "exactly one of"),
        (region(0, 10, {"kind": "brush", "seed": 1}), "exactly one of"),
        (region(0, 10, {"kind": "brush", "file": "ok.json", "colour": 1}), "unknown key 'colour'"),
        # brush files: only NAME.json / NAME.tpb inside the folder
        (region(0, 10, {"kind": "brush", "file": "../outside.json"}), "file"),
        (region(0, 10, {"kind": "brush", "file": "/etc/passwd"}), "NAME.json or NAME.tpb"),
        (region(0, 10, {"kind": "brush", "file": "sub/ok.json"}), "file"),
        (region(0, 10, {"kind": "brush", "file": str(folder(lab) / "ok.json")}), "file"),
        (region(0, 10, {"kind": "brush", "file": "..json"}), "file"),
        (region(0, 10, {"kind": "brush", "file": "ok.txt"}), "NAME.json or NAME.tpb"),
        (region(0, 10, {"kind": "brush", "file": "ok"}), "NAME.json or NAME.tpb"),
        (region(0, 10, {"kind": "brush", "file": "link.json"}), "leads out of the brush folder"),
        (region(0, 10, {"kind": "brush", "file": "missing.json"}), "no brush"),
        (region(0, 10, {"kind": "brush", "file": 3}), "NAME.json or NAME.tpb"),
        # regions off the display, or no span
        (region(90, 120, ok), "regions[1].end_mm: 120 is off the display (a number of mm, "
                              "0 .. 101.76)"),
        (region(-1, 10, ok), "regions[1].start_mm: -1 is off the display"),
        (region(0, 1e308, ok), "off the display"),
        (region(0, "10", ok), "regions[1].end_mm"),
        (region(0, True, ok), "regions[1].end_mm"),
        (region(20, 10, ok), "regions[1].end_mm: 10 is not after start_mm 20"),
        ({"start_mm": 0, "end_mm": 10}, "regions[1]: missing required key 'texture'"),
        (dict(region(0, 10, ok), colour=1), "regions[1]: unknown key 'colour'"),
        ([0, 10], "regions[1]: expected {start_mm"),
    ]
    for bad, fragment in cases:
        r = lab.post("/api/editor/scene", json={"regions": [good, bad]})
        assert r.status_code == 400 and fragment in r.json()["error"], (bad, r.text)
    # whole bodies
    many = [region(i * 5, i * 5 + 4, ok) for i in range(17)]
    for body, fragment in [({"regions": many}, "17 regions; a board plays at most 16"),
                           ({"regions": [good] * 65}, "at most 64 regions"),
                           ({"regions": {"a": good}}, "regions: expected a list"),
                           ({"regions": [good], "name": ""}, "name: expected a string"),
                           ({"regions": [good], "name": "x" * 65}, "name"),
                           ({"regions": [good], "idle_amplitude": 3}, "unknown key"),
                           ({"regions": [good], "base": 3}, "base"),
                           ({"regions": [good], "base": "0" * 16}, "changed since"),
                           ([good], "expected a JSON object")]:
        r = lab.post("/api/editor/scene", json=body)
        assert r.status_code == 400 and fragment in r.json()["error"], (body, r.text)
    for raw, ctype, fragment in [('{"regions": [', "application/json", "not JSON"),
                                 ('{"regions": []}', "text/plain", "application/json"),
                                 ('{"regions": []}', None, "application/json"),
                                 ("x" * 20000, "application/json", "over 16384 bytes"),
                                 ('{"regions": [{"start_mm": NaN, "end_mm": 1, "texture": '
                                  '{"kind": "constant", "level": 0}}]}', "application/json",
                                  "off the display")]:
        r = lab.post("/api/editor/scene", content=raw,
                     headers={"content-type": ctype} if ctype else {})
        assert r.status_code == (413 if "over" in fragment else 400) and fragment in r.json()["error"], (raw[:30], r.text)
    # saving a design: no overwrite unless asked, names inside the folder only
    for body, fragment in [({"name": "ok", "design": PINK}, "ok.json exists"),
                           ({"name": "ok.json", "design": PINK, "replace": 1}, "replace"),
                           ({"name": "../x", "design": PINK}, "name"),
                           ({"name": "a/b.json", "design": PINK}, "name"),
                           ({"name": "x.csv", "design": PINK}, "NAME.json or NAME.tpb"),
                           ({"name": "link", "design": PINK}, "leads out of the brush folder"),
                           ({"name": "new", "design": dict(PINK, level=-0.1)}, "design.level"),
                           ({"name": "new"}, "design: expected"),
                           ({"name": "new", "design": PINK, "x": 1}, "unknown key 'x'")]:
        r = lab.post("/api/editor/brushes", json=body)
        assert r.status_code == 400 and fragment in r.json()["error"], (body, r.text)
    assert lab.get("/api/editor/scene?x=1").status_code == 400
    assert lab.get("/api/editor/strip?x=1").status_code == 400
    assert lab.post("/api/editor/scene", json={"regions": []},
                    headers={"host": "evil.example"}).status_code == 400
    # nothing played, nothing written
    assert owner.status()["pushes"] == pushes
    assert owner.scene_source() == before
    assert files(lab) == on_disk
    assert D.load(outside)["source"].startswith("texelpad brush design shape=white")
    # replace: true overwrites (beside and renamed), and a new name is written
    r = lab.post("/api/editor/brushes", json={"name": "ok", "design": dict(PINK, level=0.07),
                                              "replace": True})
    assert r.status_code == 200 and D.load(folder(lab) / "ok.json")["lam"][4] == 0.07
    assert not any(p.name.endswith(".tmp") for p in folder(lab).iterdir())
    assert base["scene_id"] == lab.get("/api/editor/scene").json()["scene_id"]


def test_a_board_that_is_gone_is_503_and_nothing_is_written(tmp_path):
    owner = BoardOwner(str(tmp_path / "no-such-port"), "virtual", timeout=2.0)
    lab = Lab(owner, tmp_path / "data")
    lab.brushes = tmp_path / "my-brushes"          # the Lab's own brush folder, made here
    with TestClient(make_app(lab), base_url=BASE) as c:
        assert (tmp_path / "my-brushes").is_dir()
        for method, path, body in [("GET", "/api/editor/palette", None),
                                   ("GET", "/api/editor/scene", None),
                                   ("GET", "/api/editor/strip", None),
                                   ("POST", "/api/editor/scene",
                                    {"regions": [region(0, 10, {"kind": "constant",
                                                                "level": 0.5})]})]:
            r = c.request(method, path, json=body)
            assert r.status_code == 503 and "does not answer" in r.json()["error"], (path, r.text)
        # saving a brush needs no board
        r = c.post("/api/editor/brushes", json={"name": "mine", "design": PINK})
        assert r.status_code == 200 and r.json()["saved"] == "mine.json"
        assert [p.name for p in (tmp_path / "my-brushes").iterdir()] == ["mine.json"]
        assert c.get("/editor").status_code == 200


def test_overlaps_are_judged_on_positions():
    """editor.paint_order alone (no board): later wins, pieces keep their
    payload, every boundary one of the given values."""
    po = lambda regs: [(s, e, x) for s, e, x in E.paint_order(regs, 5.3)]   # noqa: E731
    assert po([(0, 10, "a"), (2, 4, "b")]) == [(0, 2, "a"), (2, 4, "b"), (4, 10, "a")]
    assert po([(2, 4, "b"), (0, 10, "a")]) == [(0, 10, "a")]
    assert po([(0, 5, "a"), (5, 10, "b")]) == [(0, 5, "a"), (5, 10, "b")]
    assert po([(0, 5, "a"), (4, 10, "b"), (3, 4.5, "c")]) == \
        [(0, 3, "a"), (3, 4.5, "c"), (4.5, 10, "b")]
    assert po([(0, 5.0005, "a"), (5.0, 10, "b")]) == [(0, 5.0005, "a"), (5.0, 10, "b")]
    assert po([(1, 1.001, "a")]) == []                       # rounds to no position


# --- measured -----------------------------------------------------------------------------
@pytest.mark.vboard
def test_push_to_playing_time_of_a_brush_scene(lab):
    """Measured, not asserted (tests never assert on time): POST
    /api/editor/scene of a scene with a new brush region (a new seed each
    time: nothing cached) - until the board plays it (owner.push returns:
    the board answered the push with the new scene in place), until the
    reply (which then renders the strip on the host), and the board's own
    build of the scene (status last_push); then edits beside the brush."""
    owner = lab.lab.owner
    push, playing_at = owner.push, []

    def timed_push(scene):
        out = push(scene)
        playing_at.append(time.perf_counter())
        return out
    owner.push = timed_push
    try:
        playing, reply, builds = [], [], []
        for seed in range(7):
            t0 = time.perf_counter()
            a = paint(lab, [region(0, 40, {"kind": "constant", "level": 0.3}),
                            region(40, 101.76, {"kind": "brush", "design": PINK, "seed": seed})])
            reply.append(time.perf_counter() - t0)
            playing.append(playing_at[-1] - t0)
            builds.append(a["status"]["last_push"]["build_us"] / 1000)
        # the next edits leave the brush as it is (the constant changes): its
        # rendering is kept, the board builds it again
        again = []
        for level in (0.1, 0.2, 0.3, 0.4, 0.5):
            t0 = time.perf_counter()
            paint(lab, [region(0, 40, {"kind": "constant", "level": level}),
                        region(40, 101.76, {"kind": "brush", "design": PINK, "seed": 6})])
            again.append(time.perf_counter() - t0)
    finally:
        del owner.push
    ms = lambda xs: "%.0f ms (min %.0f, max %.0f)" % (                  # noqa: E731
        1e3 * statistics.median(xs), 1e3 * min(xs), 1e3 * max(xs))
    print("\nbrush scene (61.76 mm of brush + a constant), median of %d: request -> playing "
          "on the board %s; -> the reply with the strip %s; the board's build %.1f ms"
          % (len(reply), ms(playing), ms(reply), statistics.median(builds)))
    print("an edit beside it (the brush's rendering kept): the reply in %s" % ms(again))


# --- in Chromium ----------------------------------------------------------------------------
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def _get(url: str) -> Any:
    import urllib.request
    with urllib.request.urlopen(url, timeout=30) as r:
        return json.loads(r.read())


@pytest.mark.slow
@pytest.mark.vboard
def test_a_drag_on_the_strip_and_a_designed_brush_play_on_the_board(tmp_path):
    """/editor in Chromium: drag a span on the strip, pick a designed brush,
    paint; the board plays a brush region of that design where the drag was.
    Then a brush file and a constant (the screenshot of docs: set
    TEXELPAD_EDITOR_SCREENSHOT=docs/img/brush-editor.png to write it)."""
    sync_api = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (.ci/run installs it)")
    data = tmp_path / "lab"
    (data / "brushes").mkdir(parents=True)
    D.save(D.design("brown", 0.12, 0.55, name="rough"), data / "brushes" / "rough.json")
    with lab_process(data) as (url, _):
        with sync_api.sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS,
                                         chromium_sandbox=False)
            page = browser.new_page(viewport={"width": 1150, "height": 1000})
            errors: list[str] = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(url + "editor")
            page.wait_for_selector("body[data-ready='1']")
            box = page.locator("#strip").bounding_box()
            y = box["y"] + box["height"] / 2
            mm_per_px = LENGTH / box["width"]

            def drag(f0: float, f1: float) -> None:
                page.mouse.move(box["x"] + f0 * box["width"], y)
                page.mouse.down()
                for i in range(1, 13):
                    page.mouse.move(box["x"] + (f0 + (f1 - f0) * i / 12) * box["width"], y)
                page.mouse.up()

            def pushed(n: int) -> None:
                page.wait_for_function("document.body.dataset.pushes === '%d'" % n)
                assert page.inner_text("#error") == "", page.inner_text("#error")

            drag(0.12, 0.37)
            sel = page.evaluate("editor.strip.selection")
            assert abs(sel["start_mm"] - 0.12 * LENGTH) <= 2 * mm_per_px, sel
            assert abs(sel["end_mm"] - 0.37 * LENGTH) <= 2 * mm_per_px, sel
            assert float(page.input_value("#start")) == pytest.approx(sel["start_mm"], abs=1e-4)
            page.select_option("#kind", "brush")
            page.check("input[name=brush-source][value=design]")
            page.select_option("#shape", "pink")
            page.fill("#level", "0.03")
            page.fill("#mean", "0.55")
            page.fill("#brush-seed", "21")
            page.click("#paint")
            pushed(1)
            played = _get(url + "api/scene")["scene"]["regions"]
            brush = [r for r in played if r["texture"]["kind"] == "brush"]
            assert len(brush) == 1, played
            r = brush[0]
            assert (r["start_mm"], r["end_mm"]) == (sel["start_mm"], sel["end_mm"])
            d = D.design("pink", 0.03, 0.55)
            assert r["texture"]["seed"] == 21
            assert r["texture"]["brush"] == {"k": d["k"], "lam": d["lam"], "range": d["range"]}
            rows = page.locator("#regions tbody tr")
            assert "brush pink 0.03/0.55, seed 21" in rows.all_inner_texts()[1]

            # a brush file and a constant over the rest; then undo and redo the last
            drag(0.55, 0.9)
            page.check("input[name=brush-source][value=file]")
            page.select_option("#brush-file", "rough.json")
            page.fill("#brush-seed", "4")
            page.click("#paint")
            pushed(2)
            two = _get(url + "api/scene")["scene"]
            drag(0.8, 1.0)
            page.select_option("#kind", "constant")
            page.locator("#const-level").evaluate(
                "(e) => { e.value = '0.85'; e.dispatchEvent(new Event('input')); }")
            page.click("#paint")
            pushed(3)
            kinds = [x["texture"]["kind"] for x in _get(url + "api/scene")["scene"]["regions"]]
            assert kinds.count("brush") == 2 and kinds[-1] == "constant", kinds
            page.click("#undo")
            pushed(4)
            assert _get(url + "api/scene")["scene"] == two
            page.click("#paint")
            pushed(5)
            # a kind whose form the page built from its module's FIELDS (kinds/bump.py)
            drag(0.1, 0.3)
            page.select_option("#kind", "bump")
            page.select_option("#g-bump-shape", "edge")
            page.fill("#g-bump-width_mm", "3")
            page.click("#paint")
            pushed(6)
            bumps = [x for x in _get(url + "api/scene")["scene"]["regions"]
                     if x["texture"]["kind"] == "bump"]
            assert len(bumps) == 1 and bumps[0]["texture"]["shape"] == "edge" \
                and bumps[0]["texture"]["width_mm"] == 3.0, bumps
            assert any("bump edge 3 mm, height 1" in t
                       for t in page.locator("#regions tbody tr").all_inner_texts())
            assert errors == []
            shot = os.environ.get("TEXELPAD_EDITOR_SCREENSHOT")
            page.screenshot(path=shot or str(tmp_path / "editor.png"), full_page=True)
            browser.close()
