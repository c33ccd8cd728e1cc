"""The felt model and the encoder that lands where people land (issue 22;
docs/encoder.md, "The felt plane" and "Calibration"):

- the front end: the force threshold with the fingertip's viscous fall, the
  skin's band, spectral lines and their fusion into one felt pitch;
- the references: none encodes to a felt pitch (or a pitch) above the skin's
  band; the six pitches seed 000 quotes; pink below white and blue; no
  tonal reference's match aliases;
- the calibration on the trained rater's matches (../shared/golden/rater):
  the shipped constants are the fit's, the rater's rows are assigned as
  documented, leave-one-texture-out runs; the lab's per-subject files are
  held out and never read;
- where the model is used: the simulated participant, `brush compare`, the
  quantization test's expected similarity, and `texelpad encode`'s JSON.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from texel.runtime import scene as tscene

from support.cli import run_cli
from texelpad.analysis import calibration as C
from texelpad.analysis import encoder as E
from texelpad.analysis import perception as P
from texel.gen.params import DX_MM

HALF = 9600
NINE = C.NAMES
SKIN_TOP_HZ = P.skin_band_hz()[1]
SKIN_TOP_DB = 10.0 * math.log10(SKIN_TOP_HZ / P.SPEED_MM_S)


def sine(f_cpmm: float, n: int = HALF, amp: float = 1.0) -> np.ndarray:
    return 0.5 + 0.5 * amp * np.sin(2 * np.pi * f_cpmm * DX_MM * np.arange(n))


@pytest.fixture(scope="module")
def encoded() -> dict:
    return {n: E.encode(E.reference_map(n), intervals=False) for n in NINE}


# --- the front end -----------------------------------------------------------------------

def test_force_threshold_adds_the_fingertips_viscous_fall():
    # by hand: 1 kHz is 2 octaves above 250 Hz (+24 dB displacement threshold) and the
    # displacement per unit force is 20 log10(1000/250) = 12.04 dB lower than at 250 Hz
    t = P.force_threshold_db([40.0, 100.0, 250.0, 1000.0])
    assert t[2] == pytest.approx(0.0)
    assert t[3] == pytest.approx(24.0 + 20 * math.log10(4.0))
    # below the 100 Hz corner the skin is elastic: only the U-curve, re its value at 250 Hz
    assert t[0] - t[1] == pytest.approx(12 * math.log2(100 / 40))
    no_fall = P.Model(fingertip_corner_hz=None)
    assert P.force_threshold_db(1000.0, no_fall) == pytest.approx(24.0)


def test_the_skin_band_ends_near_a_kilohertz():
    lo, hi = P.skin_band_hz()
    # full scale 40 dB above threshold at 250 Hz: 12 dB/octave + 20 log10(f/250) = 40 dB
    # at f = 250 * 2^x with 12x + 6.02x = 40: x = 2.22, f = 1,164 Hz (the 1 % grid: 1,161)
    assert lo == pytest.approx(0.1) and hi == pytest.approx(1164, rel=0.012)
    assert P.skin_band_hz(P.Model(fingertip_corner_hz=None))[1] > 2 * hi
    # at 86 mm/s that is 13.5 c/mm, 11.3 dB
    assert SKIN_TOP_DB == pytest.approx(11.3, abs=0.05)


def test_lines_are_found_in_sines_never_in_noise():
    f, p = P.periodogram(sine(3.0))
    lines = P.line_bins(p, HALF)
    assert lines.any() and abs(f[lines][np.argmax(p[lines])] - 3.0) < 0.02
    rng = np.random.default_rng(1)
    for _ in range(20):
        _, p = P.periodogram(rng.random(HALF))
        assert not P.line_bins(p, HALF).any()
    # a narrow texel texture's expected spectrum is a line; a wide one's is not
    _, pn = P.expected_periodogram({"pitch_db": 5.0, "irregularity_db": -30.0}, HALF)
    _, pw = P.expected_periodogram({"pitch_db": 5.0, "irregularity_db": -3.0}, HALF)
    assert P.line_bins(pn, HALF).any() and not P.line_bins(pw, HALF).any()
    assert not P.line_bins(p, HALF, None).any()


@pytest.mark.parametrize("f", [1.0, 3.0, 6.0])
def test_a_sine_is_felt_at_its_frequency_as_one_pitch(f):
    fp = P.felt_point(sine(f))
    assert fp.pitch_db == pytest.approx(10 * math.log10(f), abs=0.1)
    assert fp.noisiness_db == pytest.approx(-10.0, abs=0.05) and fp.tonal > 0.99


def test_two_sines_fuse_into_one_pitch_between_them():
    """seed 000 (after Friesen et al.): discrete components are felt as one
    frequency at their weighted mean - not as a spread."""
    m = (sine(2.5) + sine(6.0)) / 2
    pat = P.map_pattern(m)
    fp = pat.felt_point()
    assert 10 * math.log10(2.5) < fp.pitch_db < 10 * math.log10(6.0)
    assert fp.noisiness_db == pytest.approx(-10.0, abs=0.05)
    assert pat.moments_db()[1] > 2.0          # unfused, the two lines spread 0.19 decade


def test_noise_is_felt_as_noisy():
    fp = P.felt_point(np.random.default_rng(3).random(HALF))
    assert fp.tonal == 0.0 and fp.noisiness_db > -7.0
    assert fp.pitch_db < SKIN_TOP_DB


def test_felt_distance_is_a_distance_in_db():
    a, b = sine(2.0), sine(4.0)
    assert P.felt_distance(a, a) == 0.0
    # two pure pitches an octave apart: 3.01 dB on the pitch axis, equal noisiness
    assert P.felt_distance(a, b) == pytest.approx(10 * math.log10(2), abs=0.15)
    assert P.felt_distance(a, b) == pytest.approx(P.felt_distance(b, a))


def test_model_refuses_nonsense_constants():
    for kw in ({"fingertip_corner_hz": 0.0}, {"line_db": math.nan},
               {"slope_above_db_per_octave": -1.0}):
        with pytest.raises(ValueError, match=list(kw)[0]):
            P.Model(**kw)


# --- the references -----------------------------------------------------------------------

def test_no_reference_encodes_above_the_skins_band(encoded):
    """The issue's test: at the model's 86 mm/s, no reference encodes to a
    felt pitch above what skin feels - nor to a texture pitch above it."""
    for n, r in encoded.items():
        assert r["skin_band"]["pitch_db_max"] == pytest.approx(SKIN_TOP_DB, abs=0.01)
        assert r["felt"]["rendering"]["pitch_db"] <= SKIN_TOP_DB, n
        assert r["pitch_db"] <= SKIN_TOP_DB, n
        # and the texture feels like the map (under one difference threshold)
        assert r["felt_distance_db"] < P.JND_DB, n


def test_the_pitches_seed_000_quotes(encoded):
    """Within 1.5 dB of the subjects' mean Central Pitch for the six seed 000
    quotes (measured: 0.06 .. 1.13 dB); pink's below white's and blue's."""
    for n, q in C.QUOTED_PITCH_DB.items():
        assert abs(encoded[n]["pitch_db"] - q) < 1.5, n
    assert encoded["pink"]["pitch_db"] < min(encoded["white"]["pitch_db"],
                                             encoded["blue"]["pitch_db"])
    # noisy references get a high irregularity, tonal ones a low one (seed 000:
    # for the noises "it seems to matter more that the Irregularity parameter is high")
    for n in ("white", "pink", "blue"):
        assert encoded[n]["irregularity_db"] > -4.0, n
    for n in ("2sin", "3sin", "4sin", "square", "triangle", "sawtooth"):
        assert encoded[n]["irregularity_db"] < -9.0, n
    # within the lab's slider: at most one decade
    assert all(r["irregularity_db"] <= E.FELT_IRREG_MAX_DB for r in encoded.values())


def test_a_match_aliases_only_where_the_map_reaches_nyquist(encoded):
    for n, r in encoded.items():
        a = r["aliasing"]
        if a["map_top_band_fraction"] < 1e-3:
            assert a["expected_fraction"] < 1e-3, n        # the tonal six
        else:
            assert a["expected_fraction"] < 0.15, n        # the noises: a tail of a wide texture


# --- the calibration ---------------------------------------------------------------------

@pytest.fixture(scope="module")
def cal() -> C.Calibration:
    return C.Calibration(C.load())


def test_the_raters_rows_are_labelled_by_their_statistics():
    # ../shared/golden/rater/trained_rater_texel_pitches.csv labels each row with its texture
    # (relabelled 2026-11-28): each row's 192 pitches have the mean and spread of the match
    # its label names (within 0.6 dB, the README's figure), and no other labelling fits the
    # statistics better. Square's and triangle's matches are identical, so the statistics
    # alone may pair those two either way.
    pitches = C.rater_pitches()
    assert sorted(pitches) == sorted(NINE)
    check = C.rater_label_check()
    for n, row in check["rows"].items():
        assert pitches[n].size == 192
        assert row["distance_db"] <= 0.6, (n, row)
    assert check["labels_cost"] == pytest.approx(check["best_cost"], abs=1e-9)
    by_stats = check["by_statistics"]
    assert {n: by_stats[n] for n in NINE if n not in ("square", "triangle")} == \
        {n: n for n in NINE if n not in ("square", "triangle")}
    assert {by_stats["square"], by_stats["triangle"]} == {"square", "triangle"}
    # the old labels (the family order over rows stored in the test order) fit far worse
    old = dict(zip(NINE, (pitches[n] for n in ("triangle", "4sin", "pink", "3sin", "blue",
                                                  "white", "square", "2sin", "sawtooth"))))
    m = C.rater_matches()
    assert sum(math.dist(C.log_stats_db(old[n]), m[n]) > 0.6 for n in NINE) == 7


def test_the_shipped_constants_are_the_calibrations(cal):
    fit = cal.fit(NINE)
    assert C.constants_of(fit.model) == C.constants_of(P.DEFAULT_MODEL)
    # the fingertip's fall and the lines' fusion earn their place: without them the
    # rater's renderings sit far from the references they match
    data = cal.data
    old = P.Model(fingertip_corner_hz=None, line_db=None)
    assert fit.loss < C.loss(data.points(old), NINE) / 4
    assert C.loss(data.points(P.Model(fingertip_corner_hz=None)), NINE) > fit.loss
    assert C.loss(data.points(P.Model(line_db=None)), NINE) > fit.loss


def test_leave_one_texture_out(cal):
    rows = C.leave_one_out(cal, encode=False)
    assert [r["texture"] for r in rows] == list(NINE)
    d = [r["felt_distance_db"] for r in rows]
    assert all(math.isfinite(x) for x in d)
    # measured: median 1.23 dB, worst 3.35 dB (blue; docs/encoder.md's table)
    assert float(np.median(d)) < 1.5 and max(d) < 4.0


def test_the_held_out_files_are_not_read():
    """The lab's per-subject result files are the encoder's held-out test: the
    calibration reads ../shared/golden/rater only (and nothing names them)."""
    import inspect
    src = inspect.getsource(C) + inspect.getsource(E) + inspect.getsource(P)
    for word in ("free_exploration_results", "subject_results", "SubjectData"):
        assert word not in src


# --- where the model is used ---------------------------------------------------------------

def test_cli_prints_json_that_pastes_into_a_scene(capsys):
    code, o, e = run_cli(capsys, "encode", "--reference", "4sin", "--no-ranges")
    assert code == 0, e
    line = next(ln for ln in o.splitlines() if ln.startswith("texture "))
    tex = json.loads(line[len("texture"):])
    assert tex["kind"] == "texel" and tex["v"] == 2
    scene = {"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": tex}]}
    tscene.validate(scene, {"positions": 19200, "dx_um": 5.3})
    assert "skin band" in o and "noisiness" in o


def test_the_participant_feels_what_the_model_feels():
    from texelpad.study.participant import SimulatedParticipant
    from texelpad.study.space import Point, to_point
    target = to_point(5.0, -8.0)
    sim = SimulatedParticipant(target)
    near, far = to_point(5.3, -8.0), to_point(9.0, -8.0)
    assert sim.compare(near, far) == "A" and sim.compare(far, near) == "B"
    # two tiny irregularities at the target's pitch feel alike: unsure; the plane
    # oracle tells them apart (they are 5 dB apart on the slider)
    a, b = to_point(5.0, -25.0), to_point(5.0, -20.0)
    assert SimulatedParticipant(to_point(5.0, -22.0)).compare(a, b) == "unsure"
    assert SimulatedParticipant(to_point(5.0, -22.0), feel="plane").compare(a, b) == "B"
    with pytest.raises(ValueError, match="feel"):
        SimulatedParticipant(Point(0.5, 0.5), feel="taste")


def test_quantization_ratings_follow_the_felt_distance():
    from texelpad.study import quant as Q
    from texelpad.study.participant import SimulatedParticipant
    from texelpad.study.space import Point
    m = {n: {"pitch_db": E.encode(E.reference_map(n), intervals=False)["pitch_db"],
             "irregularity_db": E.encode(E.reference_map(n), intervals=False)
             ["irregularity_db"]} for n in Q.EXEMPLARS}
    state = Q.Quant(seed=1, config=Q.Config(matches=m, texel_samples=50, design="levels"))
    sim = SimulatedParticipant(Point(0.5, 0.5))
    got = {}
    while not state.done:
        ref, q = state.current
        r = sim.rate(state)
        got[(ref, q)] = r
        state.answer(r)
    # each reference's own felt match at q = 0 rates 4 or 5; 4sin's (a narrow texture:
    # quantization moves its pitch) falls with q, to 1 at 5 dB (felt 3.6 dB away).
    # NOT seed 000's finding that pink is the most sensitive: the felt point of a
    # texture a decade wide hardly moves on a 0.5-decade grid (docs/encoder.md)
    for n in Q.EXEMPLARS:
        assert got[(n, 0.0)] >= 4, (n, got)
    r4 = [got[("4sin", q)] for q in (0.0, 1.0, 3.0, 5.0)]
    assert r4 == sorted(r4, reverse=True) and r4[-1] <= 2, r4


def test_brushes_that_feel_different_and_the_same():
    from texelpad.brush import document as D
    pink = D.fit([E.reference_map("pink")], name="pink")
    saw = D.fit([E.reference_map("sawtooth")], name="sawtooth")
    d, fa, fb = D.felt_distance(pink, saw)
    assert d > P.JND_DB and fa.pitch_db > fb.pitch_db
    assert D.felt_distance(pink, pink)[0] == 0.0


def test_the_calibration_bench_writes_its_report(tmp_path, capsys):
    from bench import felt_calibration as FC
    js, fig = tmp_path / "cal.json", tmp_path / "cal.png"
    assert FC.main(["--json", str(js), "--figure", str(fig)]) == 0
    out = capsys.readouterr().out
    for words in ("1. the fit over 80 combinations", "3. leave one texture out",
                  "4. three encoders", "the rater's pitch file, read by its labels"):
        assert words in out
    res = json.loads(js.read_text())
    assert res["fit"]["constants"] == C.constants_of(P.DEFAULT_MODEL)
    assert res["summary"]["felt"]["pitch_in_skin_band"] == 9
    assert len(res["leave_one_out"]) == 9 and fig.stat().st_size > 20000
    with pytest.raises(SystemExit):                      # argparse: a figure type it cannot write
        FC.main(["--figure", str(tmp_path / "x.gif")])
