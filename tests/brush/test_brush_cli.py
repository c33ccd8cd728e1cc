"""`texelpad brush` end to end: fit a recording (a tribometer-like CSV at its
own uneven step), design, paint to a map and to a scene the virtual board
plays, show, compare; bad input is one line naming it and changes nothing."""
from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from texel.gen import brush as B
from texelpad.brush import document as D

from support.cli import run_cli
from support.vboard import virtual_board

TPB_BYTES = 4 + 2 + 8 + 8 * B.K         # the binary brush (document.to_bytes): 790


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
    # the 4 c/mm line stands out at wavenumber 4 (3.93 c/mm: 4 cycles of a 1.0176 mm
    # window; 4 c/mm is wavenumber 4.07)
    lam = np.array(doc["lam"])
    assert np.argmax(lam[1:]) + 1 == 4 and abs(lam[4] - 0.08) < 0.02
    d2 = tmp_path / "d.tpb"
    code, o, e = run_cli(capsys, "brush", "design", "--shape", "pink", "--level", "0.03",
                         "--out", str(d2))
    assert code == 0, e
    assert len(d2.read_bytes()) == TPB_BYTES
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
    assert png.stat().st_size > 20000 and "%d binary" % TPB_BYTES in o
    assert "wavenumbers 1..%d:" % B.NYQ in o
    code, o, e = run_cli(capsys, "brush", "compare", str(out), str(d2))
    assert code == 0 and "braycurtis distance" in o and "ranges differ" in e
    assert "felt distance" in o and "dB" in o
    code, o, e = run_cli(capsys, "brush", "compare", str(out), str(out))
    assert code == 0 and "felt distance %s .. %s: 0.00 dB (the same" % (out, out) in o


@pytest.mark.parametrize("argv, fragment", [
    (["brush", "fit", "NOPE.csv", "--out", "OUT/b.json"], "cannot read NOPE.csv"),
    (["brush", "fit", "BAD.csv", "--out", "OUT/b.json"], "line 3"),
    (["brush", "fit", "--reference", "nope", "--out", "OUT/b.json"], "--reference"),
    (["brush", "fit", "--reference", "pink", "--out", "OUT/b.txt"], "unsupported file type"),
    (["brush", "paint", "BROKEN.json", "--out", "OUT/m.csv"], "brush.lam[3]: nan"),
    (["brush", "paint", "OUT/none.json", "--out", "OUT/m.csv"], "cannot read"),
    (["brush", "design", "--shape", "green", "--out", "OUT/b.json"], "--shape"),
    (["brush"], "say what to do"),
    # issue 24: no position column by name is an error, not a sample number read as mm
    (["brush", "fit", "NOPOS.csv", "--out", "OUT/b.json"], "no position column"),
    (["brush", "fit", "FAR.csv", "--out", "OUT/b.json"], "= 3.77e+302 samples"),
    (["brush", "show", "DEEP.json", "--out", "OUT/b.png"], "nested too deeply"),
    (["brush", "paint", "DEEP.json", "--out", "OUT/m.csv"], "not a brush"),
    (["brush", "paint", "GOOD.json", "--length-mm", "nan", "--out", "OUT/m.csv"],
     "--length-mm: must be a finite number"),
    (["brush", "paint", "GOOD.json", "--length-mm", "inf", "--out", "OUT/m.csv"],
     "--length-mm: must be a finite number"),
    (["brush", "paint", "GOOD.json", "--start-mm", "nan", "--scene", "OUT/s.json"],
     "--start-mm: must be a finite number"),
    (["brush", "design", "--level", "nan", "--out", "OUT/b.json"], "--level: must be a finite number"),
    (["brush", "design", "--level", "-1", "--out", "OUT/b.json"], "--level: brush.lam[1]"),
    (["brush", "design", "--shape", "pink", "--level", "600", "--out", "OUT/b.json"],
     "--level: brush.lam[1]"),
    (["brush", "design", "--mean", "nan", "--out", "OUT/b.json"], "--mean: must be a finite number"),
    (["brush", "design", "--mean", "-2", "--out", "OUT/b.json"], "--mean: brush.lam[0]"),
    (["brush", "design", "--k", "0.001", "--out", "OUT/b.json"], "--k: brush.k[1]"),
    (["brush", "design", "--shape", "nan", "--out", "OUT/b.json"], "--shape: a slope"),
    (["brush", "design", "--shape", "400", "--out", "OUT/b.json"], "--shape: brush.lam[5]"),
    (["brush", "design", "--band", "0", "3", "--out", "OUT/b.json"], "--band: band"),
    (["brush", "design", "--band", "1", str(B.K), "--out", "OUT/b.json"], "--band: band"),
    # a brush of the old geometry (texelpad-brush/1: 188-sample windows, 95 wavenumbers)
    (["brush", "paint", "OLD.json", "--out", "OUT/m.csv"],
     "'texelpad-brush/1' brushes (188-sample windows) are not painted any more"),
    (["brush", "paint", "OLD.tpb", "--out", "OUT/m.csv"],
     "95 wavenumbers; this display paints %d" % B.K),
])
def test_bad_input_is_one_line_and_writes_nothing(capsys, tmp_path, argv, fragment):
    (tmp_path / "BAD.csv").write_text("position_mm,friction\n0,0.5\n0.1,abc\n")
    (tmp_path / "NOPOS.csv").write_text("sample,friction\n" + "".join(
        "%d,%.3f\n" % (i, 0.5 + 0.1 * (i % 7)) for i in range(400)))
    (tmp_path / "DEEP.json").write_text("[" * 50000 + "]" * 50000)
    (tmp_path / "FAR.csv").write_text("x_mm,friction\n1e300,0.5\n-1e300,0.6\n")
    D.save(D.design("white"), tmp_path / "GOOD.json")
    good = D.design("white")
    broken = dict(good, lam=good["lam"][:3] + [float("nan")] + good["lam"][4:])
    (tmp_path / "BROKEN.json").write_text(json.dumps(broken))
    (tmp_path / "OLD.json").write_text(json.dumps({
        "format": "texelpad-brush/1", "window": 188, "hop": 47, "wavenumbers": 95,
        "dx_um": 5.3, "range": [0.0, 1.0], "k": [2.0] * 95, "lam": [0.01] * 95}))
    (tmp_path / "OLD.tpb").write_bytes(D.MAGIC + struct.pack("<H2f95f95f", 95, 0.0, 1.0,
                                                             *[2.0] * 95, *[0.01] * 95))
    (tmp_path / "OUT").mkdir()
    argv = [a.replace("OUT/", str(tmp_path / "OUT") + "/") for a in argv]
    argv = [str(tmp_path / a) if a in ("BAD.csv", "BROKEN.json", "NOPOS.csv", "DEEP.json",
                                       "GOOD.json", "FAR.csv", "OLD.json", "OLD.tpb") else a
            for a in argv]
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


def test_fit_reads_texelpad_render_csv_by_column_name(capsys, tmp_path):
    """issue 24: `texelpad render --out m.csv` writes sample,x_mm,friction; brush
    fit read the sample number as mm (a map 1/0.0053 times too long, garbage,
    exit 0). Now the columns are found by name: the brush is the map's own."""
    args = ["render", "--pitch-db", "6.3", "--irregularity-db", "-12.9", "--length-samples",
            "3000"]
    assert run_cli(capsys, *args, "--out", str(tmp_path / "m.csv"))[0] == 0
    assert run_cli(capsys, *args, "--out", str(tmp_path / "m.npy"))[0] == 0
    assert (tmp_path / "m.csv").read_text().startswith("sample,x_mm,friction\n")
    code, o, e = run_cli(capsys, "brush", "fit", str(tmp_path / "m.csv"), "--out",
                         str(tmp_path / "b.json"))
    assert code == 0, e
    got = D.load(tmp_path / "b.json")
    want = D.fit([np.load(tmp_path / "m.npy")], "friction")
    # 3000 samples (59 windows), not 565,000
    assert got["fit"]["windows"] == want["fit"]["windows"] == 1 + (3000 - B.WINDOW) // B.HOP
    assert np.allclose(got["lam"], want["lam"], rtol=1e-4, atol=1e-7)
    assert np.allclose(got["k"], want["k"], rtol=1e-3)
    # brush paint's own CSV (position_mm,friction) reads back by name too, and a
    # column order of the reader's choosing does not matter
    m = tmp_path / "p.csv"
    assert run_cli(capsys, "brush", "paint", str(tmp_path / "b.json"), "--length-mm", "5",
                   "--out", str(m))[0] == 0
    rows = [r.split(",") for r in m.read_text().splitlines()]
    (tmp_path / "swapped.csv").write_text("\n".join("%s;%s" % (f, p) for p, f in rows) + "\n")
    from texelpad.brush.transform import read_recording
    p1, f1 = read_recording(m)
    p2, f2 = read_recording(tmp_path / "swapped.csv")
    assert np.array_equal(p1, p2) and np.array_equal(f1, f2) and p1[1] == 0.0053
