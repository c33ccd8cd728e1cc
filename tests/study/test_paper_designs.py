"""Each protocol's design against the paper's numbers, by hand (issue 20): the
quantization test's 27 trials and the sequences they play, the free
exploration's sliders as the lab's app's, the pursuit's fresh rendering per
comparison, seed 001's staircase stimulus, and every protocol's session
replayed from its file."""
from __future__ import annotations

import math
import random
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import texel
from texel.gen.lognormal import to_db
from texel.gen.params import DX_MM
from texelpad.analysis.calibration import rater_matches, rater_pitches
from texelpad.study import protocols, questions, rater
from texelpad.study import scenes as S
from texelpad.study.free import Config as FreeConfig
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.pursuit import Config as PursuitConfig
from texelpad.study.quant import LAB_EXEMPLARS, LAB_ORDER, NINE, Config, Quant, lab_exemplars, \
    lab_order
from texelpad.study.session import Session
from texelpad.study.space import Point
from texelpad.study.staircase import Config as StairConfig

DISPLAY = {"positions": 19200, "dx_um": 5.3}
OWN = {r: {"pitch_db": 2.0 + k, "irregularity_db": -12.0 + k, "seed": 100 + k,
           "texel_samples": 50, "v": 2} for k, r in enumerate(NINE)}


# --- the quantization test: 27 trials (seed 000; the app's compareOrder) ------------------

def test_the_paper_design_is_27_trials_18_unquantized_and_9_quantized_exemplars():
    st = Quant(4, Config(matches=OWN))
    plan = st.plan
    assert len(plan) == 27
    c = Counter((t["source"], t["quant_db"]) for t in plan)
    assert c == {("own", 0.0): 9, ("rater", 0.0): 9, ("rater", 1.0): 3, ("rater", 3.0): 3,
                 ("rater", 5.0): 3}
    assert {t["reference"] for t in plan if t["source"] == "own"} == set(NINE)
    assert {t["reference"] for t in plan if t["source"] == "rater" and not t["quant_db"]} \
        == set(NINE)
    assert sorted(t["reference"] for t in plan if t["quant_db"]) == \
        sorted(["4sin", "pink", "sawtooth"] * 3)             # the family exemplars
    assert plan != Quant(5, Config(matches=OWN)).plan        # a seeded order
    own = Quant(4, Config(matches=OWN, quantized_source="own")).plan
    assert {t["source"] for t in own if t["quant_db"]} == {"own"}


def test_order_lab_is_the_apps_compare_order_row_by_row():
    # the app: compareOrder = [0 3 0; 0 1 0; 1 5 0.1; ...; 1 2 0.5] (source, row, decades); its
    # rows in the lab's test order [8 3 5 2 6 4 7 1 9] (1-based, family order): row 3 is pink,
    # row 1 triangle, row 5 blue, row 2 4sin
    assert rater.TEST_ORDER_NAMES == ("triangle", "4sin", "pink", "3sin", "blue", "white",
                                      "square", "2sin", "sawtooth")
    assert LAB_ORDER[0] == ("pink", "own", 0.0) and LAB_ORDER[1] == ("triangle", "own", 0.0)
    assert LAB_ORDER[2] == ("blue", "rater", 1.0) and LAB_ORDER[-1] == ("4sin", "rater", 5.0)
    assert LAB_EXEMPLARS == ("4sin", "blue", "sawtooth")
    st = Quant(1, Config(matches=OWN, order="lab", exemplars=LAB_EXEMPLARS))
    assert [(t["reference"], t["source"], t["quant_db"]) for t in st.plan] == list(LAB_ORDER)
    # each of the nine once beside the own match and once beside the rater's, unquantized
    for src in ("own", "rater"):
        assert sorted(r for r, s_, q in LAB_ORDER if s_ == src and q == 0) == sorted(NINE)
    with pytest.raises(ValueError, match="order 'lab' plays the app's 27"):
        Config(matches=OWN, order="lab")                     # the paper's exemplars: not the app's
    # the other reading: the rows in the published family order
    fam = lab_order("family_order")
    assert fam[0] == ("4sin", "own", 0.0) and fam[-1] == ("3sin", "rater", 5.0)
    assert lab_exemplars("family_order") == ("3sin", "pink", "sawtooth")
    st = Quant(1, Config(matches=OWN, order="lab", lab_rows="family_order",
                         exemplars=lab_exemplars("family_order")))
    assert [(t["reference"], t["source"], t["quant_db"]) for t in st.plan] == list(fam)
    with pytest.raises(ValueError, match="lab_rows"):
        Config(matches=OWN, lab_rows="alphabetical")
    with pytest.raises(ValueError, match="repeats"):
        Config(matches=OWN, order="lab", exemplars=LAB_EXEMPLARS, repeats=2)


def test_the_rater_data_shipped_is_the_published_data():
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))
    import gen_rater_data
    assert rater.data() == gen_rater_data.build()
    pitches = rater_pitches()
    for name in NINE:
        assert np.array_equal(rater.pitches(name), pitches[name])
        assert rater.match(name) == dict(zip(("pitch_db", "irregularity_db"),
                                             rater_matches()[name]))


def test_each_reference_plays_beside_the_raters_rendering_of_it():
    import csv
    from texelpad.analysis.calibration import rater_dir
    with open(rater_dir() / "trained_rater_texel_pitches.csv", newline="") as f:
        rows = {r[0]: np.array([float(v) for v in r[1:]]) for r in list(csv.reader(f))[1:]}
    for name in NINE:                           # by the file's labels
        assert np.array_equal(rater.pitches(name), rows[name])
    # what older sessions played (study/legacy.py): by statistics, square's and triangle's
    # swapped; the old 'app' mode, data row k (texture TEST_ORDER[k]) beside reference k
    assert np.array_equal(rater.pitches("square", "statistics-2026"), rows["triangle"])
    assert np.array_equal(rater.pitches("pink", "statistics-2026"), rows["pink"])
    assert np.array_equal(rater.pitches("2sin", "index-2026"), rows["triangle"])
    assert np.array_equal(rater.pitches("sawtooth", "index-2026"), rows["sawtooth"])
    st = Quant(1, Config(matches=OWN, order="lab", exemplars=LAB_EXEMPLARS))
    while st.current_source != "rater":
        st.answer(3)
    ref, q = st.current
    assert st.texture()["u16"] == rater.rendering(ref, q, st.phases[st.trial])
    for bad in ("app", "csv"):          # 'app' only encoded the mislabelling: gone
        with pytest.raises(ValueError, match="rater_rows"):
            Config(matches=OWN, rater_rows=bad)


def test_quantization_is_buildfine5s_rounding_of_the_logged_sequence():
    # MATLAB: pull = q*round(pull/q), halves away from zero; q = 0.1 decade at 1 dB
    f = np.array([10 ** 0.0500001, 10 ** -0.0500001, 10 ** 0.0499999, 10 ** 0.149,
                  10 ** 0.151, 3.0])
    got = np.log10(rater.quantize(f, 1.0))
    assert got == pytest.approx([0.1, -0.1, 0.0, 0.1, 0.2, 0.5], abs=1e-12)
    for name in ("4sin", "pink", "sawtooth"):
        lf = np.log10(rater.pitches(name))
        for q in (1.0, 3.0, 5.0):
            lq = np.log10(rater.quantize(rater.pitches(name), q))
            assert np.allclose(lq / (q / 10), np.round(lq / (q / 10)), atol=1e-9)
            assert np.all(np.abs(lq - lf) <= q / 20 + 1e-9)      # each texel to its nearest step
        assert np.array_equal(rater.quantize(rater.pitches(name), 0.0), rater.pitches(name))


def test_a_rater_trial_plays_the_logged_sequence_phase_continuously():
    st = Quant(2, Config(matches=OWN))
    while st.current_source != "rater" or st.current[1] != 3.0:
        st.answer(3)
    ref, q = st.current
    tex = st.texture()
    assert tex["kind"] == "samples" and tex["fit"] == "tile" and len(tex["u16"]) == 9600
    f = rater.quantize(rater.pitches(ref), q)
    u = st._phases[st.trial]
    theta = 2 * math.pi * u
    want = []
    for fi in f:                        # by hand: 50 samples per texel, 2 pi f DX per sample
        for _ in range(50):
            want.append(math.floor((math.sin(theta) + 1) / 2 * 65535 + 0.5))
            theta += 2 * math.pi * fi * DX_MM
    assert max(abs(a - b) for a, b in zip(tex["u16"], want)) <= 1
    assert S.split({"kind": "reference", "name": ref}, tex, DISPLAY)["regions"][1]["texture"] \
        is tex


def test_an_own_trial_plays_the_texture_felt_and_quantizes_that_very_sequence():
    st = Quant(3, Config(matches=OWN, quantized_source="own"))
    seen = {}
    while not st.done:
        ref, q = st.current
        t = st.texture()
        if st.current_source == "rater":
            st.answer(3)
            continue
        assert {k: t[k] for k in ("pitch_db", "irregularity_db", "seed", "texel_samples", "v")} \
            == {k: OWN[ref][k] for k in ("pitch_db", "irregularity_db", "seed", "texel_samples",
                                         "v")}
        seen[(ref, q)] = t
        st.answer(3)
    for ref in ("4sin", "pink", "sawtooth"):
        base = texel.make_plan(texel.validate(dict(seen[(ref, 0.0)], length_samples=9600)))
        f0 = np.array([base.f[i] for i in range(base.count)])
        for q in (1.0, 3.0, 5.0):
            p = texel.make_plan(texel.validate(dict(seen[(ref, q)], length_samples=9600)))
            fq = np.array([p.f[i] for i in range(p.count)])
            # the same draws, each texel's pitch moved to its nearest step of q/10 decade
            assert np.all(np.abs(np.log10(fq) - np.log10(f0)) <= q / 20 + 1e-6)
            assert len(np.unique(np.round(np.log10(fq) / (q / 10), 6))) < len(f0)


def test_the_paper_design_needs_the_participants_own_matches():
    st = Quant(1, Config())                 # a config file may leave them to matches_from
    while st.current_source != "own":
        st.answer(3)
    with pytest.raises(ValueError, match="matches_from"):
        st.texture()
    bad = dict(OWN, pink=dict(OWN["pink"], v=3))
    with pytest.raises(ValueError, match="v of 'pink'"):
        Config(matches=bad)


# --- the free exploration's sliders: the lab's app's ---------------------------------------

def test_the_free_sliders_are_the_apps():
    c = FreeConfig()
    # PitchSlider.Limits = [-1 2], Value 0.5; IrregularitySlider 0..10 * 0.1, Value 5
    assert c.pitch_db == (-10.0, 20.0) and c.start[0] == 5.0
    assert c.irregularity_slider == "sigma" and c.sigma == (0.0, 1.0)
    assert c.start[1] == round(10 * math.log10(0.5), 3) == -3.01
    assert c.texel_samples == 50
    assert c.sliders()["irregularity_scale"] == "sigma"
    with pytest.raises(ValueError, match="with the sigma slider"):
        FreeConfig(irregularity_db=(-30.0, -5.0))
    old = FreeConfig(irregularity_slider="db", start=(5.0, -15.0))
    assert old.sliders()["irregularity_scale"] == "db" and "sigma" not in old.sliders()


# --- the pursuit: one texture at a time, a fresh rendering per comparison ------------------

def test_pursuit_plays_one_texture_at_a_time_with_fresh_seeds():
    st = protocols.start("pursuit", {}, 8)
    header = {"config": {}, "seed": 8}
    seeds = []
    while not st.done:
        q = questions.ask("pursuit", st, header, DISPLAY)
        assert q.public["options"] == ["reference", "A", "B"]
        assert all(len(o["regions"]) == 1 and o["regions"][0]["end_mm"] == 101.76
                   for o in q.options)
        assert q.options[0]["regions"][0]["texture"] == {"kind": "reference", "name": "4sin"}
        a, b = (o["regions"][0]["texture"]["seed"] for o in q.options[1:])
        assert q.detail["seeds"] == [a, b] and a != b
        assert questions.ask("pursuit", st, header, DISPLAY).options == q.options   # replayable
        seeds += [a, b]
        st.answer("A")
    assert len(set(seeds)) == 40
    fixed = protocols.start("pursuit", {"fresh": False, "presentation": "split"}, 8)
    q = questions.ask("pursuit", fixed, {"config": {}, "seed": 8}, DISPLAY)
    assert q.public["options"] == ["A", "B"] and PursuitConfig(fresh=False).seeds(8, 0, 0) == (7, 7)
    with pytest.raises(ValueError, match="presentation"):
        PursuitConfig(presentation="side")


# --- seed 001's staircase stimulus ---------------------------------------------------------

@pytest.mark.parametrize("condition, sd", [("narrow", 1.2), ("wide", 4.3)])
def test_the_staircase_plays_seed_001s_lognormal(condition, sd):
    c = StairConfig(condition=condition)
    tex = c.texture()
    # a lognormal of mean 4 and SD sd c/mm: sigma_ln^2 = ln(1 + sd^2/16), mu_ln = ln 4 - s2/2
    s2 = math.log(1 + sd * sd / 16.0)
    assert tex["pitch_db"] == pytest.approx(10 * (math.log(4) - s2 / 2) / math.log(10), abs=6e-4)
    assert tex["irregularity_db"] == pytest.approx(
        10 * math.log10(math.sqrt(s2) / math.log(10)), abs=6e-4)
    assert tex["min_cpmm"] == 1.0 and tex["phase"] == "reset"
    assert (tex["pitch_db"], tex["irregularity_db"]) == to_db(4.0, sd)


def test_a_staircase_trial_fills_the_display_with_whole_texels():
    st = protocols.start("staircase", {"condition": "wide"}, 2)
    q = questions.ask("staircase", st, {"config": {"condition": "wide"}, "seed": 2}, DISPLAY)
    n = round(26.0 / DX_MM)                     # 4906 samples: 3 whole texels on 19,200
    for sc in q.options:
        texel_reg, rest = sc["regions"]
        assert texel_reg["texture"]["texel_samples"] == n
        assert texel_reg["end_mm"] == round(3 * n * 5.3 / 1000, 6)
        assert rest["texture"] == {"kind": "constant", "level": 0.0}
        assert texel_reg["texture"]["min_cpmm"] == 1.0
    seeds = [sc["regions"][0]["texture"]["seed"] for sc in q.options]
    assert sorted(Counter(seeds).values()) == [1, 2] and seeds.index(
        [s for s in seeds if seeds.count(s) == 1][0]) == q.odd
    with pytest.raises(ValueError, match="condition"):
        StairConfig(condition="medium")


# --- every protocol's session replays from its file ----------------------------------------

CONFIGS = {"free": {}, "quant": {"matches": OWN}, "pursuit": {}, "staircase": {},
           "search": {"dims": ["pitch", "irregularity"]}, "mapping": {},
           "evaluate": {"textures": [{"name": "VTp a", "reference": "4sin", "texture": {
               "pitch_db": 7.0, "irregularity_db": -6.0, "seed": 7, "v": 2}}]}}


@pytest.mark.parametrize("protocol", sorted(CONFIGS))
def test_every_protocols_session_replays_from_its_file(protocol, tmp_path):
    assert set(CONFIGS) == set(protocols.PROTOCOLS)
    config = CONFIGS[protocol]
    sess = Session.create(tmp_path, protocol, "p01", config, 12)
    st = protocols.start(protocol, config, 12)
    sim = SimulatedParticipant(Point(0.4, 0.6), noise=0.01, seed=2)
    rng = random.Random(1)
    n = 0
    while not st.done and n < 40:
        a = sim.answer(protocol, st)
        sess.append({"answer": a})
        protocols.apply(protocol, st, a)
        n += 1
        if rng.random() < 0.2:              # a restart: rebuild from the file, go on from there
            st = protocols.replay(Session.open(sess.path))
    again = protocols.replay(Session.open(sess.path))
    for attr in ("matches", "ratings", "track", "history", "order"):
        if hasattr(st, attr):
            assert getattr(again, attr) == getattr(st, attr), attr


# --- the app's rating and confidence sliders: continuous 1..5 from 3 ----------------------

def test_ratings_and_confidence_are_the_apps_continuous_sliders():
    # the app: DifferentSlider/ConfidenceSlider Limits [1 5], Value 3, read as a double
    st = Quant(2, Config(matches=OWN))
    q = questions.ask("quant", st, {"config": {}, "seed": 2}, DISPLAY)
    assert q.public["slider"] == {"range": [1, 5], "start": 3.0, "step": 0.01}
    assert q.public["answers"] is None
    assert questions.normalise("quant", q, st, 3.456) == 3.46
    for bad in (True, 0.99, 5.01, "3", None, float("nan")):
        with pytest.raises(ValueError, match="similarity"):
            questions.normalise("quant", q, st, bad)
    assert st.answer(2.5)["similarity"] == 2.5
    buttons = Quant(2, Config(matches=OWN, rating="buttons"))
    with pytest.raises(ValueError, match="similarity"):
        buttons.answer(2.5)
    free = protocols.start("free", {}, 1)
    a = free.checked_answer({"pitch_db": 1.0, "irregularity_db": -3.0, "confidence": 3.333})
    assert a["confidence"] == 3.33
    old = protocols.start("free", {"confidence_input": "buttons"}, 1)
    with pytest.raises(ValueError, match="confidence"):
        old.checked_answer({"pitch_db": 1.0, "irregularity_db": -3.0, "confidence": 3.5})
