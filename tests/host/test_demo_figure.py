"""texelpad.analysis.figures.demo_figure and scene_map: the one-PNG figure of `texelpad demo`.

- scene_map is what a board plays: the study's split screen equals
  texel.reference_u16("4sin", 9600) then the int engine's rendering of the
  texel region's 9,600 samples; a full-screen texel scene equals
  texel.render_u16(..., engine="int") of 19,200 samples (plan-backed and
  map-backed regions); gaps play the idle amplitude;
- the figures it returns: telemetry synthesised from the exact map gives a
  largest played-vs-map difference of 0 steps, one corrupted sample gives
  exactly its corruption; the sensed-vs-true finger error is the offset put in;
- the title says them in plain words (played_words, finger_words): "the
  board played exactly the map (0 of 180 samples differ)", "... differed
  from the map by at most 7 steps of 65,535 at 1 of 180 samples";
- the PNG is a PNG of the figure's size;
- empty telemetry, finger lifted throughout, a constant-only scene, one
  region with gaps, 16 regions of every kind: no crash, the figures they imply;
- malformed telemetry / truth raise ValueError naming the problem.
"""
from __future__ import annotations

import struct

import numpy as np
import pytest

import texel
from texelpad.analysis.figures import demo_figure, finger_words, played_words, scene_map

DISPLAY = {"positions": 19200, "dx_um": 5.3}
TEXEL = {"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}
SPLIT = {"regions": [
    {"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "4sin"}},
    {"start_mm": 50.88, "end_mm": 101.76, "texture": dict(kind="texel", **TEXEL)}]}


def _u16(scene, display=None):
    m = scene_map(scene, display)
    q = np.rint(m * 65535).astype(np.int64)
    assert np.array_equal(q / 65535.0, m)          # scene_map is exactly uint16 / 65535
    return q


def _sweep(u16, n=200, dt_us=8000, lift=10, t0=1000):
    """Telemetry of a finger swept over the whole display, lifted for `lift`
    samples at both ends, playing exactly the map: rows (t_us, position, amp)."""
    t = t0 + np.arange(n) * dt_us
    pos = np.linspace(0, u16.size - 1, n).astype(np.int64)
    pos[:lift] = -1
    pos[-lift:] = -1
    amp = np.where(pos >= 0, u16[np.maximum(pos, 0)], 0)
    return np.column_stack([t, pos, amp])


def _png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    assert data[12:16] == b"IHDR"
    return struct.unpack(">II", data[16:24]), len(data)


# --- scene_map ---------------------------------------------------------------------

def test_scene_map_split_screen_is_reference_then_int_engine_texel():
    q = _u16(SPLIT)
    assert q.shape == (19200,)
    ref = np.asarray(texel.reference_u16("4sin", 9600), dtype=np.int64)
    tex = np.asarray(texel.render_u16(dict(TEXEL, length_samples=9600), engine="int"),
                     dtype=np.int64)
    assert np.array_equal(q[:9600], ref)
    assert np.array_equal(q[9600:], tex)
    # and not trivially: the texel region is not the reference continued
    assert not np.array_equal(q[9600:], np.asarray(texel.reference_u16("4sin", 19200))[9600:])


@pytest.mark.parametrize("texel_samples", [50, 3])    # 50: played from the plan; 3: a map buffer
def test_scene_map_full_screen_texel_is_int_engine(texel_samples):
    p = dict(TEXEL, texel_samples=texel_samples)
    scene = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": dict(kind="texel", **p)}]}
    q = _u16(scene, DISPLAY)
    want = np.asarray(texel.render_u16(dict(p, length_samples=19200), engine="int"),
                      dtype=np.int64)
    assert np.array_equal(q, want)


def test_scene_map_gaps_play_idle_and_constants_their_level():
    scene = {"regions": [{"start_mm": 10.6, "end_mm": 21.2,          # positions 2000..4000
                          "texture": {"kind": "constant", "level": 0.25}}],
             "idle_amplitude": 1234}
    q = _u16(scene)
    assert (q[2000:4000] == round(0.25 * 65535)).all()
    assert (q[:2000] == 1234).all() and (q[4000:] == 1234).all()


def test_scene_map_small_display_and_bad_scene():
    small = {"regions": [{"start_mm": 0, "end_mm": 5.3,
                          "texture": {"kind": "reference", "name": "2sin"}}]}
    m = scene_map(small, {"positions": 1000, "dx_um": 5.3})
    assert m.shape == (1000,) and m.dtype == np.float64 and 0 <= m.min() and m.max() <= 1
    with pytest.raises(ValueError, match=r"regions\[0\]\.end_mm"):
        scene_map({"regions": [{"start_mm": 0, "end_mm": 200,
                                "texture": {"kind": "constant", "level": 0}}]})


# --- demo_figure -----------------------------------------------------------------------

def test_exact_telemetry_zero_error_png_and_finger_error(tmp_path):
    u16 = _u16(SPLIT)
    tel = _sweep(u16)
    truth = tel[:, :2].copy()
    truth[:, 0] -= 1500                          # the simulation's clock is 1.5 ms off ...
    truth[truth[:, 1] >= 0, 1] += 4              # ... and the sensor reads 4 positions short
    truth[50, 1] = -1                            # one sample: the true finger is lifted
    out = demo_figure(tmp_path / "demo.png", SPLIT, tel.tolist(), title="split", truth=truth)
    (w, h), nbytes = _png_size(tmp_path / "demo.png")
    assert (w, h) == (1200, 1450) and nbytes > 50_000
    assert out["path"] == str(tmp_path / "demo.png")
    assert out["samples"] == 200 and out["down"] == 180
    assert out["amp_err_max"] == 0 and out["amp_mismatches"] == 0
    assert out["pos_err_max"] == 4
    assert out["lift_mismatches"] == 1


def test_one_corrupted_sample_is_measured(tmp_path):
    u16 = _u16(SPLIT)
    tel = _sweep(u16)
    k = 120                                      # finger down, in the texel region
    assert tel[k, 1] >= 9600
    tel[k, 2] = tel[k, 2] + 7 if tel[k, 2] < 60000 else tel[k, 2] - 7
    out = demo_figure(tmp_path / "bad.png", SPLIT, tel)
    assert out["amp_err_max"] == 7 and out["amp_mismatches"] == 1
    assert "pos_err_max" not in out                # no truth given


def test_title_words_exact_and_differing():
    assert played_words(0, 0, 180) == "the board played exactly the map (0 of 180 samples differ)"
    assert played_words(0, 0, 1800) == "the board played exactly the map (0 of 1,800 samples differ)"
    assert played_words(7, 1, 180) == ("the board's played friction differed from the map by at "
                                       "most 7 steps of 65,535 at 1 of 180 samples")
    assert played_words(1, 3, 1) == ("the board's played friction differed from the map by at "
                                     "most 1 step of 65,535 at 3 of 1 sample")
    assert played_words(None, 0, 0) is None                  # the finger never down
    assert finger_words(4, 5.3) == ("the board sensed the finger at most 4 positions (21.2 \u00b5m) "
                                     "from where it truly was")
    assert finger_words(1, 5.3).startswith("the board sensed the finger at most 1 position (5.3 ")
    assert finger_words(0, 5.3) == "the board sensed the finger exactly where it truly was"
    assert finger_words(None, 5.3) is None


def test_title_uses_the_words(tmp_path, monkeypatch):
    """The figure's title carries the figures returned, in those words (no
    "max |played - map| = N counts")."""
    from matplotlib.figure import Figure
    titles = []
    real = Figure.suptitle

    def keep(self, t, *a, **k):
        titles.append(t)
        return real(self, t, *a, **k)
    monkeypatch.setattr(Figure, "suptitle", keep)
    u16 = _u16(SPLIT)
    tel = _sweep(u16)
    tel[120, 2] = tel[120, 2] + 7 if tel[120, 2] < 60000 else tel[120, 2] - 7
    truth = tel[:, :2].copy()
    truth[truth[:, 1] >= 0, 1] += 4
    demo_figure(tmp_path / "t.png", SPLIT, tel, truth=truth, title="split")
    (title,) = titles
    assert all(len(line) <= 130 for line in title.splitlines())    # wrapped to the figure
    title = " ".join(title.split())
    assert "200 telemetry samples, 180 with the finger down; the board's played friction " \
           "differed from the map by at most 7 steps of 65,535 at 1 of 180 samples" in title
    assert "the board sensed the finger at most 4 positions (21.2 \u00b5m) from where it truly was" \
        in title
    assert "counts" not in title and "|" not in title


def _sixteen():
    kinds = [{"kind": "reference", "name": "pink"}, dict(kind="texel", **TEXEL),
             {"kind": "constant", "level": 0.8},
             {"kind": "samples", "values": [0, 0.5, 1, 0.5]}]
    w = 101.76 / 16
    return {"regions": [{"start_mm": round(k * w, 3), "end_mm": round((k + 1) * w - 0.3 * (k % 2), 3),
                         "texture": kinds[k % 4]} for k in range(16)]}


# Each drawing costs ~0.8 s: three figures cover the five edge cases.
@pytest.mark.parametrize("case", ["empty telemetry, one region with gaps",
                                  "finger lifted throughout, constant-only scene",
                                  "16 regions of every kind, with gaps"])
def test_edge_cases_draw(tmp_path, case):
    if case.startswith("empty"):
        scene = {"regions": [{"start_mm": 30, "end_mm": 40, "texture": dict(kind="texel", **TEXEL)}]}
    elif case.startswith("finger lifted"):
        scene = {"regions": [{"start_mm": 0, "end_mm": 101.76,
                              "texture": {"kind": "constant", "level": 0.4}}]}
    else:
        scene = _sixteen()
    u16 = _u16(scene)
    tel = _sweep(u16)
    truth = tel[:, :2].copy()                   # the finger as swept (down in the middle)
    if case.startswith("empty"):
        assert (u16[:5660] == 0).all() and np.ptp(u16[5660:7547]) > 60000   # gap, then texture
        tel = []
    elif case.startswith("finger lifted"):
        assert (u16 == round(0.4 * 65535)).all()
        tel[:, 1] = -1
    if case.startswith("empty"):
        truth = None
    out = demo_figure(tmp_path / "f.png", scene, tel, truth=truth, title=case)
    _png_size(tmp_path / "f.png")
    if case.startswith("empty"):
        assert out == {"path": str(tmp_path / "f.png"), "samples": 0, "down": 0,
                       "amp_err_max": None, "amp_mismatches": 0}
    elif case.startswith("finger lifted"):
        assert out["samples"] == 200 and out["down"] == 0 and out["amp_err_max"] is None
        assert out["pos_err_max"] is None and out["lift_mismatches"] == 180
    else:
        assert out["down"] == 180 and out["amp_err_max"] == 0 and out["pos_err_max"] == 0


@pytest.mark.parametrize("telemetry, message", [
    ([1, 2, 3], r"telemetry: expected shape \(n, 3\)"),
    ([[1, 2]], r"telemetry: expected shape \(n, 3\)"),
    ([[1, 2, 3], [4, 5]], r"telemetry: expected a sequence"),
    ("abc", r"telemetry: expected a sequence"),
    (None, r"telemetry: expected shape"),
    ([[0, 1, 2], [1, 19200, 3]], r"telemetry\[1\]: position 19200 outside -1 \(lifted\) \.\. 19199"),
    ([[0, -2, 3]], r"telemetry\[0\]: position -2"),
    ([[0, 5, 65536]], r"telemetry\[0\]: amplitude 65536 outside 0 \.\. 65535"),
    ([[0, 5.5, 3]], r"telemetry\[0\]\[1\]: 5.5 is not a finite integer"),
    ([[0, 5, float("nan")]], r"telemetry\[0\]\[2\]: nan is not a finite integer"),
])
def test_malformed_telemetry_raises(tmp_path, telemetry, message):
    with pytest.raises(ValueError, match=message):
        demo_figure(tmp_path / "x.png", SPLIT, telemetry)
    assert not (tmp_path / "x.png").exists()


def test_malformed_truth_raises(tmp_path):
    with pytest.raises(ValueError, match=r"truth: expected shape \(n, 2\)"):
        demo_figure(tmp_path / "x.png", SPLIT, [[0, 5, 0]], truth=[[0, 5, 0]])
    with pytest.raises(ValueError, match=r"regions\[0\]\.texture\.kind"):
        demo_figure(tmp_path / "x.png", {"regions": [{"start_mm": 0, "end_mm": 1,
                                                      "texture": {"kind": "x"}}]}, [])


def test_the_zoom_draws_what_the_plate_plays(tmp_path, monkeypatch):
    """plate={...}: the zoom also draws the map through the tank's envelope
    (texelpad.plate.tank.plate_plays), the line the figure shows, with the
    swipe speed and Q in its label."""
    from texelpad.analysis import figures
    from texelpad.plate import tank
    drawn = []
    real = figures._plate_line

    def spy(ax, d, a, b, plate):
        real(ax, d, a, b, plate)
        line = ax.get_lines()[-1]
        drawn.append((line.get_label(), line.get_ydata(), d.fmap[max(0, a - 200):b], a, b))
    monkeypatch.setattr(figures, "_plate_line", spy)
    plate = {"f0_hz": 34000.0, "q": 20.0, "speed_mm_s": 100.0}
    demo_figure(tmp_path / "demo.png", SPLIT, _sweep(_u16(SPLIT)).tolist(), plate=plate)
    (label, y, fmap, a, b), = drawn
    assert "100 mm/s (Q 20: tau 187" in label
    want = tank.plate_plays(fmap, 5.3e-6, 0.1, 34000.0, 20.0)[min(a, 200):]
    assert len(y) == b - a and max(abs(p - q) for p, q in zip(y, want)) < 1e-12
    assert max(abs(p - q) for p, q in zip(y, fmap[min(a, 200):])) > 0.01   # it does filter
