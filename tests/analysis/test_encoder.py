"""The texel encoder (texelpad.analysis.encoder) and its perceptual model
(texelpad.analysis.perception): issue 13, docs/encoder.md.

- the model: the threshold curve, the analytic expected spectrum against
  rendered maps, the distance's properties;
- round trip: maps rendered from known parameters encoded back within the
  bounds docs/encoder.md states (from `python -m bench.encode`),
  and never farther from the map than the truth is;
- robustness: noisy, short, clipped, constant, NaN-bearing and malformed maps
  get an answer or an EncodeError, never a crash;
- the command line (exit codes, --json, --figure, files, scenes) and the API.
Tests never assert on time (docs/architecture.md).
"""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import texel
from texel.runtime import scene as tscene

from support.cli import run_cli
from texelpad.analysis import encoder as E
from texelpad.analysis import perception as P

HALF = 9600


def render(pitch: float, irr: float, q: float = 0.0, seed: int = 1, n: int = HALF,
           **kw) -> np.ndarray:
    return np.asarray(texel.render(dict(pitch_db=pitch, irregularity_db=irr, quant_db=q,
                                        seed=seed, length_samples=n, **kw)))


# --- the model ----------------------------------------------------------------------

def test_threshold_curve_is_the_documented_u():
    t = P.threshold_db([10.0, 40.0, 125.0, 250.0, 500.0, 1000.0])
    flat = 12.0 * math.log2(250.0 / 40.0)
    assert t == pytest.approx([flat, flat, 12.0, 0.0, 12.0, 24.0])


@pytest.mark.parametrize("params", [
    dict(pitch_db=6.0, irregularity_db=-12.0),
    dict(pitch_db=0.0, irregularity_db=-5.0),
    dict(pitch_db=15.0, irregularity_db=-3.0),
    dict(pitch_db=19.0, irregularity_db=-10.0),         # a quarter of the texels alias
    dict(pitch_db=6.0, irregularity_db=-5.0, quant_db=3.0),
    dict(pitch_db=12.0, irregularity_db=-2.0, band_limit_cpmm=30.0),
    dict(pitch_db=5.0, irregularity_db=-8.0, texel_samples=7000),   # a texel > the map
])
def test_expected_spectrum_is_the_mean_of_rendered_ones(params):
    n, seeds = HALF, 40
    _, S = P.expected_periodogram(params, n)
    mean = sum(P.periodogram(texel.render(dict(params, seed=s, length_samples=n)))[1]
               for s in range(seeds)) / seeds
    assert S.sum() == pytest.approx(mean.sum(), rel=0.03)      # ~ 1/8, a full-scale texel
    # felt patterns of the expectation and of 40 renderings' mean spectrum, seen
    # without the fingertip's viscous fall above 100 Hz: this checks the spectrum,
    # and that lens keeps the 19 dB texture's main lobe (7 kHz at 86 mm/s) in view
    # - with the fall, what is felt of it is its texel borders near DC, where the
    # expectation leaves out the mean's removal
    lens = P.Model(fingertip_corner_hz=None)
    d = P.w2_db(P.pattern_of_spectrum(S, n, lens), P.pattern_of_spectrum(mean, n, lens))
    assert d < 0.3, d


def test_distance_is_a_distance_in_db():
    a, b = render(5.0, -30.0), render(8.0, -30.0)        # two pure pitches 3 dB apart
    assert P.distance(a, a) == 0.0
    assert P.distance(a, b) == pytest.approx(3.0, abs=0.15)
    assert P.distance(a, b) == pytest.approx(P.distance(b, a), abs=1e-9)
    # a texture dict is its expected pattern, at the map's length
    tex = {"pitch_db": 5.0, "irregularity_db": -30.0}
    assert P.distance(a, tex) < 0.05
    assert P.distance(tex, {"pitch_db": 8.0, "irregularity_db": -30.0}) == \
        pytest.approx(3.0, abs=0.1)
    # a wider spread is farther, in proportion
    assert P.distance(tex, {"pitch_db": 5.0, "irregularity_db": -3.0}) > \
        P.distance(tex, {"pitch_db": 5.0, "irregularity_db": -8.0}) > 0.3


def test_model_refuses_nonsense():
    for kw in ({"speed_mm_s": 0.0}, {"speed_mm_s": math.nan}, {"masking_db": -1.0},
               {"resolution_decades": 0.0}, {"full_scale_sl_db": math.inf}):
        with pytest.raises(ValueError):
            P.Model(**kw)


def test_expected_aliased_fraction_matches_the_drawn_one():
    p = {"pitch_db": 18.0, "irregularity_db": -6.0, "length_samples": 200000, "seed": 3}
    drawn = texel.make_plan(p).fraction_above_nyquist()
    assert P.expected_aliased_fraction(p) == pytest.approx(drawn, abs=0.02)
    assert P.expected_aliased_fraction({"pitch_db": 0.0, "irregularity_db": -20.0}) < 1e-12
    assert P.expected_aliased_fraction({"pitch_db": 19.0, "irregularity_db": 0.0,
                                        "band_limit_cpmm": 90.0}) == 0.0


# --- round trip -----------------------------------------------------------------------
# Bounds stated in docs/encoder.md ("Against itself"), measured by
# `python -m bench.encode` (4 seeds) with a margin; the grid here is a
# subset of the bench's, 2 seeds.

PITCHES = (-10.0, 0.0, 10.0, 19.0)
IRREGS = (-30.0, -15.0, -10.0, -5.0, 0.0)
QUANTS = (0.0, 1.0, 3.0)


SKIN_TOP_DB = 10.0 * math.log10(P.skin_band_hz()[1] / P.SPEED_MM_S)    # 11.3 dB


def _bound(pitch: float, irr: float, q: float) -> tuple[float | None, float | None]:
    """(max |pitch error|, max |irregularity error|; None: not identifiable),
    as docs/encoder.md states them (method "w2")."""
    if pitch > SKIN_TOP_DB and irr >= -5.0:
        # above the skin's band (7 kHz at 86 mm/s) a wide texture is felt by its
        # low tail and its texel borders only: the pitch is not identifiable by
        # feel (test_the_encoder_is_never_farther_than_the_truth still holds)
        return None, None
    if irr == 0.0:                  # a decade of spread: one half screen is a loose sample
        return 15.0, 5.5
    if q > 0.0 and irr <= -15.0:    # texels collapse onto one or two grid values
        return q / 2.0 + 0.3, None
    if pitch <= -10.0 and irr <= -10.0:
        return 0.3, None            # 5 cycles in the map: its spectrum cannot resolve the spread
    if q == 0.0:
        if irr <= -20.0:
            return 0.1, None        # below the resolution: any tiny irregularity feels alike
        return 1.0, 2.5
    return 1.5, 4.0 if q >= 3.0 else 2.5


@pytest.fixture(scope="module")
def trips() -> list[tuple]:
    out = []
    for q in QUANTS:
        for irr in IRREGS:
            for pitch in PITCHES:
                for seed in (1, 2):
                    m = render(pitch, irr, q, seed)
                    r = E.encode(m, quant_db=q, intervals=False, method="w2")
                    out.append((pitch, irr, q, seed, m, r))
    return out


def test_round_trip_within_the_stated_bounds(trips):
    bad = []
    for pitch, irr, q, seed, _, r in trips:
        bp, bi = _bound(pitch, irr, q)
        dp = abs(r["pitch_db"] - pitch)
        di = abs(r["irregularity_db"] - irr)
        if (bp is not None and dp > bp) or (bi is not None and di > bi):
            bad.append((pitch, irr, q, seed, round(dp, 2), round(di, 2)))
    assert bad == [], bad


def test_the_encoder_is_never_farther_than_the_truth(trips):
    """The optimiser's check: the texture chosen is at least as near the map
    (felt) as the one that made it (up to the 0.01 dB parameter rounding)."""
    worse = []
    for pitch, irr, q, seed, m, r in trips:
        truth = P.distance(m, {"pitch_db": pitch, "irregularity_db": irr, "quant_db": q,
                               "gain": r["gain"]})
        if r["distance_db"] > truth + 0.02:
            worse.append((pitch, irr, q, seed, r["distance_db"], round(truth, 4)))
    assert worse == []


@pytest.mark.parametrize("pitch", [-10.0, 5.0, 19.0])
def test_tiny_irregularity_is_reported_as_not_identifiable(pitch):
    r = E.encode(render(pitch, -30.0), intervals=True)
    lo, hi = r["ranges"]["irregularity_db"]
    assert lo == E.BOUNDS[1][0] and hi > -20.0       # anything from -30 to beyond -20 feels alike
    plo, phi = r["ranges"]["pitch_db"]
    # the felt method's same-feel range: within one difference threshold either side
    assert plo <= pitch <= phi and phi - plo < 2 * P.JND_DB + 0.3


def test_quantized_pitch_is_known_to_its_cell():
    # q = 3 dB, a tiny spread: every texel is at the grid value 6 dB, whatever the pitch
    # within [4.5, 7.5) - the encoder cannot know which, and says so
    r = E.encode(render(5.0, -30.0, 3.0), quant_db=3.0)
    assert 4.5 <= r["pitch_db"] < 7.5
    lo, hi = r["ranges"]["pitch_db"]
    assert hi - lo >= 1.0


def test_gain_and_aliasing_and_compression_are_reported():
    m = 0.5 + 0.5 * (render(19.0, -5.0, seed=4) - 0.5)     # half-scale, aliasing
    # W2 with a lens that feels 7 kHz (no fingertip fall): the spectrum's own
    # texture, half its texels aliased (the felt method stays in the skin's band)
    r = E.encode(m, intervals=False, method="w2", model=P.Model(fingertip_corner_hz=None))
    assert r["gain"] == pytest.approx(0.5, abs=0.02)
    a = r["aliasing"]
    assert 0.3 < a["expected_fraction"] < 0.7 and a["texels"] == HALF // 50
    assert abs(a["drawn_fraction"] - a["expected_fraction"]) < 0.15
    c = r["compression"]
    assert c["map_bytes"] == 2 * HALF and c["texture_bytes"] == len(repr(r["texture"]))
    assert c["ratio"] > 100


# --- robustness ---------------------------------------------------------------------------

_BASE = None


def _base() -> np.ndarray:
    global _BASE
    if _BASE is None:
        _BASE = render(6.0, -10.0, seed=3)
    return _BASE


def _cases() -> dict:
    rng = np.random.default_rng(0)
    b = _base()
    return {
        "noisy": b + rng.normal(0.0, 0.1, b.size),
        "very noisy": b + rng.normal(0.0, 0.5, b.size),
        "clipped": np.clip((b - 0.5) * 3 + 0.5, 0, 1),
        "binary": (b > 0.5).astype(float),
        "short": b[:200],
        "shortest": b[:P.MIN_SAMPLES],
        "a few NaN": np.where(np.arange(b.size) % 500 == 0, np.nan, b),
        "an inf": np.where(np.arange(b.size) == 7, np.inf, b),
        "uint16": (b * 65535).astype(np.uint16),
        "a column": b.reshape(-1, 1),
        "a list": list(b[:300]),
        "out of range": b * 10 - 3,
        "faint": 0.5 + 1e-7 * (b - 0.5),
        "a step": np.r_[np.zeros(500), np.ones(500)],
        "an impulse": np.r_[np.zeros(500), 1.0, np.zeros(499)],
        "a ramp": np.linspace(0.0, 1.0, 2000),
        "uniform noise": rng.random(4000),
    }


@pytest.mark.parametrize("name", list(_cases()))
def test_awkward_maps_get_a_sensible_answer(name):
    m = _cases()[name]
    r = E.encode(m, intervals=False)
    assert E.BOUNDS[0][0] <= r["pitch_db"] <= E.BOUNDS[0][1]
    assert E.BOUNDS[1][0] <= r["irregularity_db"] <= E.BOUNDS[1][1]
    assert 0.0 < r["gain"] <= 1.0 and math.isfinite(r["distance_db"])
    texel.validate(r["texture"])
    json.dumps(r, allow_nan=False)                         # JSON-ready, no NaN/inf


@pytest.mark.parametrize("name", ["noisy", "a few NaN", "an inf", "uint16", "a column", "clipped"])
def test_damaged_maps_keep_their_pitch(name):
    r = E.encode(_cases()[name], intervals=False)
    assert abs(r["pitch_db"] - 6.0) < 1.0


def test_filled_samples_are_reported():
    r = E.encode(_cases()["a few NaN"], intervals=False)
    assert any("filled" in n for n in r["notes"])


@pytest.mark.parametrize("bad, words", [
    (np.full(HALF, 0.3), "constant"),
    (np.zeros(100), "constant"),
    (np.where(np.arange(HALF) % 10 == 0, np.nan, 0.5), "not finite"),
    (np.full(50, np.nan), "not finite"),
    (np.zeros(P.MIN_SAMPLES - 1), "too short"),
    (np.array([]), "too short"),
    (np.zeros((20, 20)), "1-D"),
    (["a", "b"], "numbers"),
    (None, "1-D"),
    (3.0, "1-D"),
    ([[1, 2], [3]], "numbers"),
])
def test_unencodable_maps_are_a_clear_error(bad, words):
    with pytest.raises(E.EncodeError, match=words):
        E.encode(bad)


@pytest.mark.parametrize("kw, key", [({"texel_samples": 0}, "texel_samples"),
                                     ({"quant_db": -1.0}, "quant_db"),
                                     ({"seed": -1}, "seed"), ({"v": 3}, "v"),
                                     ({"quant_db": math.nan}, "quant_db")])
def test_bad_texture_keys_are_named(kw, key):
    with pytest.raises(E.EncodeError, match="^" + key):
        E.encode(_base(), **kw)


# --- decoding, the figure, the API -------------------------------------------------------------

def test_decoding_is_the_generator():
    m = render(7.0, -9.0, seed=5)
    r = E.encode(m, seed=11, intervals=False)
    y = E.decode(r)
    assert y.size == m.size
    np.testing.assert_array_equal(y, np.asarray(texel.render(dict(r["texture"],
                                                                  length_samples=m.size))))
    assert P.distance(m, y) < 0.5                     # one rendering against another


def test_texture_is_what_a_board_takes():
    r = E.encode(render(4.0, -7.0), quant_db=1.0, v=2, seed=9, texel_samples=60,
                 intervals=False)
    tex = r["texture"]
    assert tex["quant_db"] == 1.0 and tex["v"] == 2 and tex["seed"] == 9
    assert tex["texel_samples"] == 60
    region = {"start_mm": 0, "end_mm": 50.88, "texture": dict(tex, kind="texel")}
    tscene.validate({"regions": [region]}, {"positions": 19200, "dx_um": 5.3})


def test_the_figure(tmp_path):
    from texelpad.analysis.figures import encode_figure
    m = E.reference_map("sawtooth")
    r = E.encode(m, source="reference sawtooth")
    out = tmp_path / "enc.png"
    encode_figure(out, m, r)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_api_is_exported_lazily():
    code = ("import sys, texelpad; lazy = 'texelpad.analysis.encoder' not in sys.modules; "
            "import numpy as np, texel; "
            "r = texelpad.encode(np.asarray(texel.render({'pitch_db': 5, 'irregularity_db': -9})),"
            " intervals=False); print(lazy, r['pitch_db'], r['irregularity_db'])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out[0] == "True"
    assert abs(float(out[1]) - 5.0) < 1.0 and abs(float(out[2]) + 9.0) < 2.5


def test_references_and_scene_regions():
    assert E.reference_map("4sin").size == HALF
    assert E.reference_map("pink", 19200).size == 19200
    with pytest.raises(E.EncodeError, match="^reference"):
        E.reference_map("5sin")
    scene = json.loads((Path(texel.__file__).parents[2] / "host" / "texelpad" / "scenes"
                        / "split-4sin.json").read_text())
    m = E.scene_region_map(scene, 1)                  # the texel half: 6.3 dB, -12.9 dB
    r = E.encode(m, intervals=False)
    assert abs(r["pitch_db"] - 6.3) < 0.5
    assert np.allclose(E.scene_region_map(scene, 0), E.reference_map("4sin"), atol=1e-4)
    with pytest.raises(E.EncodeError, match="^region"):
        E.scene_region_map(scene, 2)
    with pytest.raises(E.EncodeError, match="^scene"):
        E.scene_region_map({"regions": "no"}, 0)


# --- files ------------------------------------------------------------------------------

def test_read_map_formats(tmp_path):
    m = render(6.0, -10.0, n=400)
    (tmp_path / "one.csv").write_text("\n".join("%.9f" % v for v in m))
    (tmp_path / "render.csv").write_text(
        "sample,x_mm,friction\n" + "\n".join("%d,%.4f,%.9f" % (k, k * 0.0053, v)
                                             for k, v in enumerate(m)))
    np.save(tmp_path / "f.npy", m)
    np.save(tmp_path / "u.npy", (m * 65535 + 0.5).astype(np.uint16))
    (tmp_path / "counts.csv").write_text("\n".join(str(int(v * 65535 + 0.5)) for v in m))
    for name in ("one.csv", "render.csv", "f.npy"):
        got, _ = E.read_map(tmp_path / name)
        np.testing.assert_allclose(got, m, atol=1e-8)
    for name in ("u.npy", "counts.csv"):
        got, notes = E.read_map(tmp_path / name)
        np.testing.assert_allclose(got, m, atol=1e-5)
        assert notes


@pytest.mark.parametrize("content, words", [
    ("", "no numbers"), ("a,b\n1,x\n", "not a number"), ("1,2\n3\n", "columns"),
    (b"\xff\xfe\x00", "UTF-8")])
def test_read_map_refuses_bad_files(tmp_path, content, words):
    f = tmp_path / "bad.csv"
    f.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(E.EncodeError, match=words):
        E.read_map(f)


# --- the command line ---------------------------------------------------------------------

def test_cli_reference_json(capsys):
    code, out, err = run_cli(capsys, "encode", "--reference", "4sin", "--json", "--no-ranges")
    assert code == 0, err
    r = json.loads(out)
    assert set(r) >= {"pitch_db", "irregularity_db", "texture", "distance_db", "spectrum",
                      "compression", "aliasing", "seconds"}
    assert r["source"] == "reference 4sin" and r["ranges"] is None
    texel.validate(r["texture"])


def test_cli_summary_names_the_report(capsys):
    code, out, err = run_cli(capsys, "encode", "--reference", "sawtooth")
    assert code == 0, err
    for word in ("texture", "distance", "same feel", "compressed", "aliasing", "spectrum",
                 "encoded in"):
        assert word in out


def test_cli_file_and_figure(tmp_path, capsys):
    m = render(3.0, -8.0, n=3000)
    f = tmp_path / "m.npy"
    np.save(f, m)
    fig = tmp_path / "e.png"
    code, out, err = run_cli(capsys, "encode", str(f), "--figure", str(fig), "--json",
                             "--no-ranges", "--texel-samples", "40", "--seed", "3")
    assert code == 0, err
    r = json.loads(out)
    assert r["texture"]["texel_samples"] == 40 and r["texture"]["seed"] == 3
    assert r["figure"] == str(fig) and fig.stat().st_size > 10000


def test_cli_scene_region(capsys):
    code, out, err = run_cli(capsys, "encode", "--scene", "split-4sin", "--region", "2",
                             "--json", "--no-ranges")
    assert code == 0, err
    assert abs(json.loads(out)["pitch_db"] - 6.3) < 0.5


@pytest.mark.parametrize("argv, code, flag", [
    ((), 2, "FILE"),
    (("--reference", "4sin", "--scene", "split-4sin"), 2, "one of"),
    (("--reference", "nope"), 2, "--reference"),
    (("--length", "100"), 2, None),
    (("x.npy", "--length", "100"), 2, "--length"),
    (("--reference", "4sin", "--region", "2"), 2, "--region"),
    (("--scene", "split-4sin", "--region", "3"), 2, "--region"),
    (("--scene", "no-such-scene"), 2, "--scene"),
    (("--reference", "4sin", "--texel-samples", "0"), 2, "--texel-samples"),
    (("--reference", "4sin", "--quant-db", "nan"), 2, "--quant-db"),
    (("--reference", "4sin", "--quant-db", "-2"), 2, "--quant-db"),
    (("--reference", "4sin", "--seed", "-1"), 2, "--seed"),
    (("--reference", "4sin", "--speed", "0"), 2, "--speed"),
    (("--reference", "4sin", "--figure", "out.gif"), 2, "--figure"),
    (("--reference", "4sin", "--figure", "/no/such/dir/e.png"), 1, "--figure"),
    (("/no/such/file.csv",), 2, "cannot read"),
])
def test_cli_errors_are_one_line(capsys, argv, code, flag):
    got, out, err = run_cli(capsys, "encode", *argv)
    assert got == code
    assert "Traceback" not in err and err.count("\n") <= 1
    if flag:
        assert flag in err


@pytest.mark.parametrize("content, words", [
    ("0.5\n" * 100, "constant"), ("nan\n" * 100, "not finite"), ("1\n2\n", "too short"),
    ("x\ny\n", "not a number")])
def test_cli_bad_maps(tmp_path, capsys, content, words):
    f = tmp_path / "m.csv"
    f.write_text(content)
    code, out, err = run_cli(capsys, "encode", str(f))
    assert code == 2 and words in err and "Traceback" not in err
