"""`texelpad brush` end to end: fit a recording (a tribometer-like CSV at its
own uneven step), design, paint to a map and to a scene the virtual board
plays, show, compare; bad input is one line naming it and changes nothing."""
from __future__ import annotations

import json

import numpy as np
import pytest

from texel.gen import brush as B
from texelpad.brush import document as D

from support.cli import run_cli
from support.vboard import virtual_board


def _recording(path, seed=0):
    """A friction recording as the paper's rig gives one: position (mm,
    3.86 um steps with jitter), friction ~0.6 +- texture + noise."""
    rng = np.random.default_rng(seed)
    pos = np.cumsum(rng.uniform(0.002, 0.0057, 12000))
    fr = 0.6 + 0.08 * np.sin(2 * np.pi * 4.0 * pos) + rng.normal(0, 0.02, pos.size)
    with open(path, "w") as f:
        f.write("position_mm,friction\n")
        for p, v in zip(pos, fr):
            f.write("%.5f,%.5f\n" % (p, v))
    return pos, fr


def test_fit_design_paint_show_compare(capsys, tmp_path):
    rec = tmp_path / "rec.csv"
    _recording(rec)
    out = tmp_path / "b.json"
    code, o, e = run_cli(capsys, "brush", "fit", str(rec), "--out", str(out))
    assert code == 0, e
    assert "fitted" in o and "range" in o
    doc = D.load(out)
    assert doc["range"][0] > doc["range"][1]            # high friction plays low amplitude
    assert doc["fit"]["windows"] > 100 and len(doc["k"]) == B.K
    # the 4 c/mm line (wavenumber 4 of a 0.9964 mm window) stands out
    lam = np.array(doc["lam"])
    assert np.argmax(lam[1:]) + 1 == 4 and abs(lam[4] - 0.08) < 0.02
    d2 = tmp_path / "d.tpb"
    code, o, e = run_cli(capsys, "brush", "design", "--shape", "pink", "--level", "0.03",
                         "--out", str(d2))
    assert code == 0, e and len(d2.read_bytes()) == 774
    m, s = tmp_path / "m.csv", tmp_path / "s.json"
    code, o, e = run_cli(capsys, "brush", "paint", str(out), "--seed", "5", "--length-mm",
                         "20", "--out", str(m), "--scene", str(s))
    assert code == 0, e
    rows = m.read_text().splitlines()
    assert rows[0] == "position_mm,friction" and len(rows) == 1 + round(20 / 0.0053)
    vals = np.array([float(r.split(",")[1]) for r in rows[1:]])
    u16 = D.paint(doc, 5, len(vals))
    assert np.allclose(vals, D.to_values(doc, u16), atol=1e-5)
    scene = json.loads(s.read_text())
    assert scene["regions"][0]["texture"]["kind"] == "brush"
    png = tmp_path / "b.png"
    code, o, e = run_cli(capsys, "brush", "show", str(out), "--out", str(png), "--original",
                         str(rec))
    assert code == 0, e
    assert png.stat().st_size > 20000 and "774 binary" in o
    code, o, e = run_cli(capsys, "brush", "compare", str(out), str(d2))
    assert code == 0 and "braycurtis distance" in o and "ranges differ" in e


@pytest.mark.parametrize("argv, fragment", [
    (["brush", "fit", "NOPE.csv", "--out", "OUT/b.json"], "cannot read NOPE.csv"),
    (["brush", "fit", "BAD.csv", "--out", "OUT/b.json"], "line 3"),
    (["brush", "fit", "--reference", "nope", "--out", "OUT/b.json"], "--reference"),
    (["brush", "fit", "--reference", "pink", "--out", "OUT/b.txt"], "unsupported file type"),
    (["brush", "paint", "BROKEN.json", "--out", "OUT/m.csv"], "brush.lam[3]: nan"),
    (["brush", "paint", "OUT/none.json", "--out", "OUT/m.csv"], "cannot read"),
    (["brush", "design", "--shape", "green", "--out", "OUT/b.json"], "--shape"),
    (["brush"], "say what to do"),
])
def test_bad_input_is_one_line_and_writes_nothing(capsys, tmp_path, argv, fragment):
    (tmp_path / "BAD.csv").write_text("position_mm,friction\n0,0.5\n0.1,abc\n")
    good = D.design("white")
    broken = dict(good, lam=good["lam"][:3] + [float("nan")] + good["lam"][4:])
    (tmp_path / "BROKEN.json").write_text(json.dumps(broken))
    (tmp_path / "OUT").mkdir()
    argv = [a.replace("OUT/", str(tmp_path / "OUT") + "/") for a in argv]
    argv = [str(tmp_path / a) if a in ("BAD.csv", "BROKEN.json") else a for a in argv]
    code, o, e = run_cli(capsys, *argv)
    assert code == 2 and fragment in e and len(e.strip().splitlines()) == 1, (code, e)
    assert not list((tmp_path / "OUT").iterdir())


@pytest.mark.vboard
def test_a_painted_scene_plays_on_the_virtual_board(capsys, tmp_path):
    doc = D.design("brown", 0.05)
    D.save(doc, tmp_path / "b.json")
    s = tmp_path / "s.json"
    assert run_cli(capsys, "brush", "paint", str(tmp_path / "b.json"), "--seed", "9",
                   "--length-mm", "50.88", "--scene", str(s))[0] == 0
    with virtual_board() as port:
        code, o, e = run_cli(capsys, "push", "--port", port, "--board", "virtual",
                             "--scene", str(s))
        assert code == 0, e
        import texelpad
        with texelpad.connect(port) as b:
            st = b.status()
            src = b.scene_source()
    assert st["scene"]["regions"][0]["kind"] == "brush" and st["faults"] == 0
    assert src["regions"][0]["texture"]["seed"] == 9
