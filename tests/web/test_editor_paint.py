"""The scene editor's painting alone (host/texelpad/web/editor.py,
Editor.paint: a request -> the scene to play; no HTTP, no board; issue 23
items 2 and 3):

- each kind painted: the pieces, the answer's regions (a texel, reference or
  constant in its canonical form, a brush by its design or file) and the
  scene checked once (link.board.check_scene: plain, canonical, display,
  spans) - the canonical form the board's own validation gives;
- overlaps: a later region wins, earlier ones trimmed, split or covered;
  nothing left: no scene (the blank one needs the board's idle level);
- refusals as the request reads: the first region whose own check fails
  (its texture over its own span, the request's paths) before anything found
  after it - a later region's bad file, a covered region, a region of no
  position, seventeen pieces;
- how often a scene is validated on the host (texel.runtime.scene's one
  check, which validate, check and build go through): once per painting, and
  once more for each region the painting has no piece of.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import pytest

import texel.runtime.scene as S
from texelpad.brush import document as D
from texelpad.link.board import CheckedScene
from texelpad.web import editor as E
from texelpad.web.api import Refused

DISPLAY = {"positions": 19200, "dx_um": 5.3}
LENGTH = 101.76
PINK = {"shape": "pink", "level": 0.05, "mean": 0.5}
CONST = {"kind": "constant", "level": 0.3}
REF = {"kind": "reference", "name": "4sin"}
TEXEL = {"kind": "texel", "pitch_db": 6.0, "irregularity_db": -20.0, "seed": 3}
BAD_TEXEL = {"kind": "texel", "pitch_db": 30, "irregularity_db": -10}
BAD_CONST = {"kind": "constant", "level": 1.5}


def region(s: float, e: float, tex: Any) -> dict[str, Any]:
    return {"start_mm": s, "end_mm": e, "texture": tex}


@pytest.fixture
def editor(tmp_path):
    return E.Editor(SimpleNamespace(brushes=tmp_path / "brushes"))


class Validations:
    """Counts the host's validations of a scene: texel.runtime.scene._check,
    which validate(), check() and build() (unless handed check()'s result)
    all go through."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.n = 0
        real = S._check

        def counted(scene: Any, display: Any) -> Any:
            self.n += 1
            return real(scene, display)
        monkeypatch.setattr(S, "_check", counted)


def own_words(i: int, reg: dict[str, Any]) -> str:
    """What the board's validation says of region i alone over its own span,
    named as the request's region i."""
    with pytest.raises(ValueError) as e:
        S.validate({"regions": [dict(reg, start_mm=float(reg["start_mm"]),
                                     end_mm=float(reg["end_mm"]))]}, DISPLAY)
    msg = str(e.value)
    assert msg.startswith("regions[0]"), msg
    return "regions[%d]" % i + msg[len("regions[0]"):]


def test_each_kind_is_painted_and_checked_once(editor, monkeypatch):
    regs = [region(0, 20, TEXEL), region(20, 40, REF), region(40, 60, CONST),
            region(60, LENGTH, {"kind": "brush", "design": PINK, "seed": 9})]
    count = Validations(monkeypatch)
    p = editor.paint({"regions": regs, "name": "four kinds"}, DISPLAY)
    assert count.n == 1                                 # the scene's one check
    assert isinstance(p.scene, CheckedScene) and p.name == "four kinds"
    assert p.scene.display == DISPLAY
    # what is sent: the pieces, each texture as the request resolved it (a
    # texel without "v" is format 2), named
    sent = p.scene.plain
    assert sent["name"] == "four kinds"
    assert [(r["start_mm"], r["end_mm"]) for r in sent["regions"]] == \
        [(s, e) for s, e, _ in p.pieces] == [(0, 20), (20, 40), (40, 60), (60, LENGTH)]
    assert [r["texture"] for r in sent["regions"][:3]] == [dict(TEXEL, v=2), REF, CONST]
    monkeypatch.undo()
    assert p.scene.canonical == S.validate(p.scene.plain, DISPLAY)
    assert list(p.scene.spans) == [(0, 3774), (3774, 7547), (7547, 11321), (11321, 19200)]
    tex = p.scene.canonical["regions"][0]["texture"]
    assert (tex["v"], tex["texel_samples"], tex["quant_db"]) == (2, 50, 0.0)   # format 2, filled in
    answer = p.regions()
    assert [a["from"] for a in answer] == [0, 1, 2, 3]
    assert [a["texture"] for a in answer[:3]] == \
        [r["texture"] for r in p.scene.canonical["regions"][:3]]
    assert answer[3]["texture"] == {"kind": "brush", "design": dict(PINK, k=2.0), "seed": 9}
    assert [a["label"] for a in answer] == [
        "texel 6.0/-20.0 dB, 0.265 mm, seed 3", "reference 4sin", "constant 0.30",
        "brush pink 0.05/0.5, seed 9"]
    # the brush is the design's numbers, as the board takes them
    doc = D.design("pink", 0.05, 0.5)
    assert p.scene.canonical["regions"][3]["texture"]["brush"]["lam"] == doc["lam"]


def test_a_brush_file_and_a_later_region_that_wins(editor, tmp_path):
    D.save(D.design("brown", 0.08, 0.45, name="rough"), tmp_path / "brushes" / "rough.json")
    p = editor.paint({"regions": [region(0, 60, TEXEL),          # split by the brush
                                  region(60, 80, CONST),         # trimmed by the reference
                                  region(75, 90, REF),           # ... which the next covers
                                  region(20, 40, {"kind": "brush", "file": "rough.json",
                                                  "seed": 2}),
                                  region(74, 95, {"kind": "constant", "level": 0.9})]},
                     DISPLAY)
    got = [(a["start_mm"], a["end_mm"], a["from"]) for a in p.regions()]
    assert got == [(0, 20, 0), (20, 40, 3), (40, 60, 0), (60, 74, 1), (74, 95, 4)]
    assert [(r["start_mm"], r["end_mm"]) for r in p.scene.canonical["regions"]] == \
        [g[:2] for g in got]
    assert p.regions()[1]["texture"] == {"kind": "brush", "file": "rough.json", "seed": 2}
    assert p.regions()[1]["label"] == "brush rough.json, seed 2"
    assert p.regions()[0]["texture"] == p.regions()[2]["texture"]   # one texture, two pieces


def test_nothing_left_is_no_scene(editor, monkeypatch):
    count = Validations(monkeypatch)
    p = editor.paint({"regions": []}, DISPLAY)
    assert (p.pieces, p.scene, p.regions(), count.n) == ([], None, [], 0)


def test_a_region_without_a_piece_is_checked_on_its_own(editor, monkeypatch):
    count = Validations(monkeypatch)
    p = editor.paint({"regions": [region(0, 10, CONST), region(0, 20, REF)]}, DISPLAY)
    assert [a["from"] for a in p.regions()] == [1]
    assert count.n == 2             # the scene, and region 0 (covered) alone


REFUSED = [
    # (the request's regions, the region whose own words answer, or a message)
    ([region(0, 10, BAD_TEXEL), region(20, 30, {"kind": "brush", "file": "missing.json"})], 0),
    ([region(0, 10, BAD_CONST), region(0, 20, CONST)], 0),                  # covered
    ([region(1, 1.001, CONST)], 0),                                         # no position
    ([region(1, 1.001, BAD_CONST)], 0),
    ([region(0, 50, BAD_TEXEL), region(20, 30, CONST)], 0),                 # split
    ([region(50, 60, BAD_CONST), region(0, 10, CONST)], 0),                 # first in request
    ([region(50, 60, BAD_CONST), region(0, 10, BAD_TEXEL)], 0),
    ([region(0, 10, CONST), region(50, 60, BAD_TEXEL)], 1),
    ([region(0, 10, BAD_CONST), region(20, 10, CONST)], 0),
    ([region(0, 10, BAD_CONST), region(20, 30, {"kind": "paint"})], 0),
    ([region(i * 5, i * 5 + 4, BAD_CONST if i == 2 else CONST) for i in range(17)], 2),
    ([region(0, 100, BAD_CONST)] + [region(i * 5 + 1, i * 5 + 3, CONST) for i in range(16)], 0),
    ([region(i * 5, i * 5 + 4, CONST) for i in range(17)],
     "regions: painting these gives 17 regions; a board plays at most 16 (remove some, or "
     "paint over several at once)"),
    ([region(0, 10, CONST), region(20, 10, BAD_CONST)],
     "regions[1].end_mm: 10 is not after start_mm 20"),
    ([region(0, 10, CONST), region(20, 30, {"kind": "brush", "file": "missing.json"})],
     "regions[1].texture.file: no brush \"missing.json\" in the brush folder"),
]


@pytest.mark.parametrize("regs, first", REFUSED)
def test_refusals_come_as_the_request_reads(editor, regs, first):
    with pytest.raises(Refused) as e:
        editor.paint({"regions": regs}, DISPLAY)
    want = first if isinstance(first, str) else own_words(first, regs[first])
    assert str(e.value) == want


def test_the_body_is_read_first(editor):
    for body, msg in [([], "expected a JSON object"),
                      ({"regions": [], "idle_amplitude": 3}, "unknown key 'idle_amplitude'"),
                      ({"regions": {}}, "regions: expected a list"),
                      ({"regions": [], "name": ""}, "name: expected a string of 1 .. "),
                      ({"regions": [], "base": 3}, "base: expected the scene_id")]:
        with pytest.raises(Refused, match=msg):
            editor.paint(body, DISPLAY)
    order = E.read_order({"regions": [region(0, 10, CONST)], "name": "n", "base": "b"})
    assert (order.name, order.base) == ("n", "b")
    assert editor.paint(order, DISPLAY).scene.canonical["name"] == "n"
