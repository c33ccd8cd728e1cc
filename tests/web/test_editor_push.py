"""One push, one validation on the host (issue 23 item 2), against a real
virtual board (tests/web/conftest.py's `lab`):

- POST /api/editor/scene: the painted scene is validated once on the host
  (link.board.check_scene) and that checked value goes through the owner and
  Board.push to the board, its canonical form answered and drawn - before,
  the editor checked each region, then the scene, Board.push checked it
  again, the owner again for the canonical form and the strip once more
  (N + 4). A region the painting covers whole is checked on its own (it is
  not in the scene), so a bad texture is refused wherever it lies.
- The owner's push of a plain scene (the classroom, the studies): once.
- Board.push of a CheckedScene: not checked again for the display it was
  checked for; checked again (the board's display) for another.
- A refused request changes nothing: the board's scene and push count, the
  brush files.

Counted: texel.runtime.scene._check (validate, check and build without
check()'s result all go through it), except inside web/strip.py's render:
the strip's drawing of a region (a scene of its own, built with the board's
code) is not a check of the pushed scene.
"""
from __future__ import annotations

import traceback
from pathlib import Path
from typing import Any

import pytest

import texel.runtime.scene as S
from texelpad.link.board import CheckedScene, check_scene

pytestmark = [pytest.mark.vboard]

LENGTH = 101.76
PINK = {"shape": "pink", "level": 0.05, "mean": 0.5}
CONST = {"kind": "constant", "level": 0.3}
REF = {"kind": "reference", "name": "4sin"}
TEXEL = {"kind": "texel", "pitch_db": 6.0, "irregularity_db": -20.0, "seed": 3}
BRUSH = {"kind": "brush", "design": PINK, "seed": 4}


def region(s: float, e: float, tex: Any) -> dict[str, Any]:
    return {"start_mm": s, "end_mm": e, "texture": tex}


class Validations:
    """Who validated a scene on the host since the last reset: [file:function]."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.calls: list[str] = []
        real = S._check

        def counted(scene: Any, display: Any) -> Any:
            stack = traceback.extract_stack()[:-1]
            if not any(f.name == "render" and f.filename.endswith("web/strip.py")
                       for f in stack):
                who = [f for f in stack if not f.filename.endswith("runtime/scene.py")][-1]
                self.calls.append("%s:%s" % (Path(who.filename).name, who.name))
            return real(scene, display)
        monkeypatch.setattr(S, "_check", counted)

    def take(self) -> list[str]:
        out, self.calls = self.calls, []
        return out


PUSHES = [
    ("one region", [region(0, 50, CONST)], 1),
    ("four kinds", [region(0, 20, TEXEL), region(20, 40, REF), region(40, 60, CONST),
                    region(60, 90, BRUSH)], 1),
    ("split and trimmed", [region(0, 60, TEXEL), region(50, 80, CONST), region(20, 30, REF)], 1),
    ("one covered", [region(0, 10, CONST), region(0, 20, REF)], 2),
    ("cleared", [], 1),
]


def test_one_validation_per_push_from_the_editor(lab, monkeypatch):
    owner = lab.lab.owner
    lab.get("/api/editor/scene")                    # the board started, its display known
    count = Validations(monkeypatch)
    for what, regs, n in PUSHES:
        count.take()
        r = lab.post("/api/editor/scene", json={"regions": regs})
        assert r.status_code == 200, (what, r.text)
        calls = count.take()
        print("%-18s %d: %s" % (what, len(calls), ", ".join(calls)))
        assert calls.count("board.py:check_scene") == 1, (what, calls)
        assert len(calls) == n, (what, calls)       # + a covered region alone
        # ... and what was answered is what the board plays
        assert owner.scene_source() == r.json()["scene"], what
        assert lab.get("/api/editor/scene").json()["scene_id"] == r.json()["scene_id"], what


def test_one_validation_per_owner_push(lab, monkeypatch):
    owner = lab.lab.owner
    display = owner.display()
    count = Validations(monkeypatch)
    st, canonical = owner.push({"regions": [region(0, 50, REF)]})
    assert count.take() == ["board.py:check_scene"]
    assert canonical == owner.scene_source()
    r = lab.post("/api/strip/texel", json={"pitch_db": 6.0, "irregularity_db": -20.0})
    assert r.status_code == 200, r.text
    assert count.take() == ["board.py:check_scene"]
    # checked before: not again
    checked = check_scene({"regions": [region(0, 30, CONST)]}, display)
    count.take()
    st, sent = owner.push_checked(checked)
    assert count.take() == [] and sent is checked
    assert owner.scene_source() == checked.canonical


def test_board_push_takes_a_checked_scene(lab, monkeypatch):
    owner = lab.lab.owner
    display = owner.display()
    count = Validations(monkeypatch)
    checked = check_scene({"regions": [region(0, 40, REF)]}, display)
    count.take()
    st = owner._call(lambda b: b.push(checked))     # the owner's Board, as the CLI's
    assert count.take() == [] and st["scene"]["regions"][0]["end"] == 7547
    assert owner.scene_source() == checked.canonical
    # checked for another display: the board's display checks it again
    small = {"positions": 1000, "dx_um": 5.3}
    other = check_scene({"regions": [region(0, 5.3, CONST)]}, small)
    count.take()
    st, sent = owner._call(lambda b: b.push_checked(other))
    assert count.take() == ["board.py:check_scene"]
    assert isinstance(sent, CheckedScene) and sent is not other and sent.display == display
    assert sent.canonical == owner.scene_source()
    wide = check_scene({"regions": [region(0, 120, CONST)]}, {"positions": 30000, "dx_um": 5.3})
    pushes = owner.status()["pushes"]
    with pytest.raises(ValueError, match=r"regions\[0\]\.end_mm: 120 is out of range"):
        owner.push(wide)
    assert owner.status()["pushes"] == pushes and owner.scene_source() == sent.canonical


def test_a_refused_push_changes_nothing(lab):
    owner = lab.lab.owner
    base = lab.post("/api/editor/scene", json={"regions": [region(0, 50, TEXEL)]}).json()
    folder = Path(lab.lab.data) / "brushes"
    saved = lab.post("/api/editor/brushes", json={"name": "mine", "design": PINK})
    assert saved.status_code == 200, saved.text
    files = {p.name: p.read_bytes() for p in folder.iterdir()}
    before, pushes = owner.scene_source(), owner.status()["pushes"]
    bad = {"kind": "constant", "level": 1.5}
    for body, status, fragment in [
            ({"regions": [region(0, 10, bad), region(0, 20, CONST)]}, 400,
             "regions[0].texture.level: 1.5 is out of range"),
            ({"regions": [region(50, 60, bad), region(0, 10, TEXEL)]}, 400,
             "regions[0].texture.level"),
            ({"regions": [region(0, 10, bad)], "base": "0" * 16}, 400, "regions[0].texture.level"),
            ({"regions": [region(0, 10, CONST)], "base": "0" * 16}, 400, "changed since"),
            ({"regions": [region(0, 10, {"kind": "brush", "file": "mine.json"}),
                          region(5, 8, {"kind": "brush", "file": "gone.json"})]}, 400,
             "no brush"),
            ({"regions": [region(i * 5, i * 5 + 4, CONST) for i in range(17)]}, 400,
             "17 regions")]:
        r = lab.post("/api/editor/scene", json=body)
        assert r.status_code == status and fragment in r.json()["error"], (body, r.text)
    assert owner.status()["pushes"] == pushes
    assert owner.scene_source() == before
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == files
    assert lab.get("/api/editor/scene").json()["scene_id"] == base["scene_id"]
