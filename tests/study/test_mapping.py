"""Seed 001's texel parameter mapping (texelpad.study.mapping): the design
against the paper's numbers by hand, a full run and its exact replay from the
answers, refusals that change nothing, and the config's validation."""
from __future__ import annotations

import json
import math
from dataclasses import asdict

import pytest

from texel.gen import params as texel_params
from texel.runtime import scene as runtime_scene
from texelpad.study import bandpass, scenes
from texelpad.study.mapping import DEFAULT_RATINGS, NINE, Config, Mapping, slider_values, \
    summary
from texelpad.study.protocols import _tuples

DISPLAY = {"positions": 19200, "dx_um": 5.3}


def _answer(st: Mapping, k: int):
    """A deterministic participant: sliders from the trial number, ratings 0..10."""
    if st.phase == "match":
        return {"pitch": (17 * k) % 101, "irregularity": (29 * k + 5) % 101}
    return (3 * k) % 11


def _run(seed: int, config: Config | None = None) -> tuple[Mapping, list]:
    st = Mapping(seed, config or Config())
    answers = []
    while not st.done:
        a = _answer(st, len(answers))
        answers.append(a)
        st.answer(a)
    return st, answers


def test_the_design_is_the_papers():
    c = Config()
    # Table I: 1, 4, 20 c/mm x zeta 0.05, 0.5, 5, all nine, each once
    assert sorted(bandpass.params_of(r) for r in c.references) == sorted(
        (f, z) for f in (1.0, 4.0, 20.0) for z in (0.05, 0.5, 5.0))
    # sliders 0 .. 100: mu = 0.75 * 1.04**P c/mm, sigma = 3 I / 10 c/mm
    assert slider_values(0, 0) == (0.75, 0.0)
    mean, sd = slider_values(100, 100)
    assert round(mean, 1) == 37.9 and sd == 30.0           # 0.75 * 50.5049 = 37.879
    assert mean == pytest.approx(37.8787, abs=1e-4)
    assert slider_values(50, 10) == pytest.approx((5.3300, 3.0), abs=1e-4)
    # texel length 1 mm on the 5.3 um grid: 188.68 -> 189 samples
    assert c.texel_samples == round(1 / 0.0053) == 189
    assert c.min_cpmm == 1.0 and c.phase == "reset"       # "exceed 1 cycle/mm"; no continuity
    # 25 ratings of the 81 on 0 .. 10, all distinct, the 9 self-pairs among them
    assert len(c.ratings) == 25 == len(set(c.ratings)) and c.scale == (0, 10)
    assert {(r, r) for r in NINE} <= set(c.ratings)


def test_the_default_25_span_both_parameters():
    pairs = set(DEFAULT_RATINGS)
    fz = {n: bandpass.params_of(n) for n in NINE}
    same_zeta = {p for p in pairs if p[0] != p[1] and fz[p[0]][1] == fz[p[1]][1]}
    same_fc = {p for p in pairs if p[0] != p[1] and fz[p[0]][0] == fz[p[1]][0]}
    # Fig. 5a: 1 vs 20 c/mm at each zeta, both ways; Fig. 5b: zeta 0.05 vs 5 at each fc
    assert same_zeta == {(f"bp-{a}-{z}", f"bp-{b}-{z}") for z in ("0.05", "0.5", "5")
                         for a, b in (("1", "20"), ("20", "1"))}
    assert same_fc == {(f"bp-{f}-{a}", f"bp-{f}-{b}") for f in ("1", "4", "20")
                       for a, b in (("0.05", "5"), ("5", "0.05"))}
    rest = pairs - same_zeta - same_fc - {(r, r) for r in NINE}
    assert rest == {("bp-4-0.5", c) for c in ("bp-1-0.05", "bp-1-5", "bp-20-0.05", "bp-20-5")}


def test_a_slider_setting_renders_seed_001s_lognormal():
    st = Mapping(3)
    t = st.texture(50, 50, 0)
    # by hand: mean 0.75 * 1.04**50 = 5.3300, sd 15; r = sd/mean = 2.8143,
    # sigma_ln^2 = ln(1 + r^2) = 2.1883, sigma10 = 1.4793 / ln 10 = 0.64245 ->
    # 10 log10 = -1.922 dB; mu10 = (ln 5.33 - 1.0942) / ln 10 = 0.2515 -> 2.515 dB
    assert t == {"pitch_db": 2.515, "irregularity_db": -1.922, "texel_samples": 189,
                 "min_cpmm": 1.0, "phase": "reset", "seed": t["seed"], "v": 2}
    # I = 0: the generator's narrowest (-30 dB); P = 0: 10 log10 0.75 = -1.249 dB
    assert (st.texture(0, 0, 0)["pitch_db"], st.texture(0, 0, 0)["irregularity_db"]) == \
        (-1.249, -30.0)
    # every change re-draws; the same change replays
    assert st.texture(50, 50, 1)["seed"] != t["seed"] and st.texture(50, 50, 0) == t
    assert st.texture(50, 50, 0, v=1)["v"] == 1
    # the slider's grid: steps of 1, halves up
    assert st.check(49.5, 0.49) == (50.0, 0.0) and st.check(100, 0) == (100.0, 0.0)
    assert Mapping(3, Config(step=0.1)).check(33.333, 0.25) == (33.3, 0.3)


def test_every_texture_is_one_the_board_takes():
    st = Mapping(4)
    for p, i in ((0, 0), (0, 100), (100, 0), (100, 100), (50, 50)):
        tex = st.texture(p, i, 0)
        canon = texel_params.validate(dict(tex, length_samples=9600))
        assert canon["min_cpmm"] == 1.0 and canon["phase"] == "reset"
    scene = scenes.split(st.reference_texture(), st.texture(50, 50, 0), DISPLAY)
    canon = runtime_scene.validate(scene, DISPLAY)
    assert canon["regions"][0]["texture"]["u16"] == bandpass.reference_u16(st.reference)


def test_a_full_run_and_its_exact_replay():
    st, answers = _run(11)
    assert len(st.matches) == 9 and len(st.ratings) == 25 and st.done and st.phase == "done"
    assert [m["reference"] for m in st.matches] == st.order and sorted(st.order) == sorted(NINE)
    assert st.order != Mapping(12).order                    # a seeded shuffle
    m0 = st.matches[0]
    fc, zeta = bandpass.params_of(m0["reference"])
    assert m0 == {"trial": 0, "reference": m0["reference"], "fc_cpmm": fc, "zeta": zeta,
                  "pitch": 0.0, "irregularity": 5.0, "mean_cpmm": 0.75, "sd_cpmm": 1.5,
                  "pitch_db": m0["pitch_db"], "irregularity_db": m0["irregularity_db"]}
    assert sorted((r["reference"], r["match_of"]) for r in st.ratings) == sorted(DEFAULT_RATINGS)
    for r in st.ratings:        # the rendering rated is the participant's match
        m = st.match_of(r["match_of"])
        assert (r["pitch"], r["irregularity"], r["pitch_db"]) == \
            (m["pitch"], m["irregularity"], m["pitch_db"])
        assert r["seed"] == st.rating_seeds[r["match_of"]] and r["self"] == (
            r["reference"] == r["match_of"])
    # the replay: the config through JSON (lists, as a session header holds
    # it; protocols._tuples as the lab reads it), the seed and the answers
    header = json.loads(json.dumps(asdict(st.config)))
    again = Mapping(11, Config(**_tuples(header)))
    assert again.config == st.config
    for a in json.loads(json.dumps(answers)):
        again.answer(a)
    assert (again.order, again.pairs, again.matches, again.ratings) == \
        (st.order, st.pairs, st.matches, st.ratings)
    with pytest.raises(ValueError, match="finished"):
        again.answer(5)
    with pytest.raises(ValueError, match="finished"):
        again.reference


def test_the_rating_phase_plays_the_pair():
    st = Mapping(5)
    with pytest.raises(ValueError, match="only in phase 'rate'"):
        st.current
    with pytest.raises(ValueError, match="only in phase 'rate'"):
        st.rating_texture()
    while st.phase == "match":
        st.answer(_answer(st, st.trial))
    with pytest.raises(ValueError, match="only in phase 'match'"):
        st.texture(50, 50, 0)
    seen = {}
    while not st.done:
        ref, of = st.current
        assert st.reference == ref
        tex = st.rating_texture()
        m = st.match_of(of)
        want = Mapping(5).texture(m["pitch"], m["irregularity"], 0)
        assert (tex["pitch_db"], tex["irregularity_db"], tex["texel_samples"]) == \
            (want["pitch_db"], want["irregularity_db"], 189)
        assert seen.setdefault(of, tex["seed"]) == tex["seed"]   # one rendering per match
        st.answer(7)


@pytest.mark.parametrize("answer, fragment", [
    (5, "phase 'match' expects {pitch, irregularity}"),
    ({"pitch": 50}, "phase 'match' expects"),
    ({"pitch": 50, "irregularity": 50, "confidence": 3}, "phase 'match' expects"),
    ({"pitch": 101, "irregularity": 50}, r"pitch: 101 is outside the slider's 0 \.\. 100"),
    ({"pitch": 50, "irregularity": -1}, "irregularity: -1 is outside"),
    ({"pitch": float("nan"), "irregularity": 50}, "pitch: expected a number"),
    ({"pitch": "50", "irregularity": 50}, "pitch: expected a number"),
    ({"pitch": True, "irregularity": 50}, "pitch: expected a number"),
])
def test_a_bad_match_answer_changes_nothing(answer, fragment):
    st = Mapping(6)
    before = (st.phase, st.trial, st.reference, list(st.matches))
    with pytest.raises(ValueError, match=fragment):
        st.answer(answer)
    assert (st.phase, st.trial, st.reference, st.matches) == before


@pytest.mark.parametrize("answer, fragment", [
    ({"pitch": 50, "irregularity": 50}, r"phase 'rate' expects an int 0 \.\. 10"),
    (11, "similarity"), (-1, "similarity"), (5.0, "similarity"), (True, "similarity"),
    ("7", "similarity"),
])
def test_a_bad_rating_changes_nothing(answer, fragment):
    st = Mapping(6)
    while st.phase == "match":
        st.answer(_answer(st, st.trial))
    st.answer(0)
    before = (st.trial, st.current, list(st.ratings))
    with pytest.raises(ValueError, match=fragment):
        st.answer(answer)
    assert (st.trial, st.current, st.ratings) == before
    assert st.checked_answer(10) == 10 and st.trial == 1       # checking moves nothing


@pytest.mark.parametrize("config, fragment", [
    ({"references": ()}, "references: expected distinct names"),
    ({"references": ("bp-1-0.05", "bp-1-0.05")}, "references"),
    ({"references": ("4sin",)}, "references"),
    ({"references": ("bp-1-0.05",)}, r"ratings\[1\]: expected \[reference, match_of\]"),
    ({"ratings": (("bp-1-0.05",),)}, r"ratings\[0\]"),
    ({"ratings": "bp-1-0.05"}, "ratings: expected up to 81"),
    ({"ratings": (("bp-1-0.05", "bp-1-5"), ["bp-1-0.05", "bp-1-5"])}, "listed twice"),
    ({"step": 0}, r"step: expected a number in \(0, 100\]"),
    ({"step": True}, "step"),
    ({"start": (50.0, 101.0)}, r"start: expected \(P, I\), each 0 \.\. 100"),
    ({"start": (50.0,)}, "start"),
    ({"texel_samples": 0}, "texel_samples: expected an int in 1"),
    ({"min_cpmm": 0.0}, "min_cpmm: expected None or a number in 0.01 .. 94.34"),
    ({"min_cpmm": 95.0}, "min_cpmm"),
    ({"phase": "random"}, "phase: expected one of continuous, reset"),
    ({"scale": (10, 0)}, "scale: expected"),
    ({"scale": (0.0, 10.0)}, "scale"),
    ({"shuffle": 1}, "shuffle: expected true or false"),
    ({"reference_seed": -1}, "reference_seed: expected an int in 0 .. 4294967295"),
    ({"reference_play": "upload"}, "reference_play: expected one of samples, board"),
    ({"reference_play": "board", "reference_seed": 3}, "seed-0 reference only"),
])
def test_config_validation(config, fragment):
    with pytest.raises(ValueError, match=fragment):
        Config(**config)


def test_a_lab_gives_its_own_design():
    refs = ("bp-4-0.05", "bp-4-0.5")
    c = Config(**_tuples({"references": list(refs), "ratings": [["bp-4-0.05", "bp-4-0.5"]],
                          "shuffle": False, "min_cpmm": None, "phase": "continuous",
                          "reference_play": "board"}))
    assert c.ratings == (("bp-4-0.05", "bp-4-0.5"),)
    st = Mapping(1, c)
    assert st.order == list(refs)                               # no shuffle: as given
    assert st.reference_texture() == {"kind": "reference", "name": "bp-4-0.05"}
    t = st.texture(50, 50, 0)
    assert "min_cpmm" not in t and "phase" not in t             # the generator's defaults
    st.answer({"pitch": 10, "irregularity": 0})
    st.answer({"pitch": 20, "irregularity": 0})
    assert st.current == ("bp-4-0.05", "bp-4-0.5")
    st.answer(4)
    assert st.done and Mapping(1, Config(ratings=())).pairs == []


def test_the_summary_is_fig_4_and_5_and_the_matrix():
    st, _ = _run(8)
    s = summary(st)
    assert s["references"] == list(NINE)
    m = s["similarity"]
    assert len(m) == 9 and all(len(row) == 9 for row in m)
    assert sum(x is None for row in m for x in row) == 81 - 25
    for r in st.ratings:
        assert m[NINE.index(r["reference"])][NINE.index(r["match_of"])] == r["similarity"]
    diag = [m[k][k] for k in range(9)]
    assert s["self"]["n"] == 9 and s["self"]["mean"] == round(sum(diag) / 9, 4)
    mean = sum(diag) / 9
    assert s["self"]["sd"] == round(math.sqrt(sum((x - mean) ** 2 for x in diag) / 8), 4)
    by_ref = {x["reference"]: x for x in st.matches}
    for row in s["fig4a"]:           # P per central frequency, one line per zeta
        assert row["fc_cpmm"] == [1.0, 4.0, 20.0]
        assert row["pitch"] == [by_ref["bp-%g-%g" % (f, row["zeta"])]["pitch"]
                                for f in (1, 4, 20)]
    irr = [x["irregularity"] for x in st.matches]
    for row in s["fig4b"]:           # I per zeta, one line per central frequency
        assert row["zeta"] == [0.05, 0.5, 5.0]
        for i, n in zip(row["irregularity"], row["irregularity_normalised"]):
            assert n == round((i - min(irr)) / (max(irr) - min(irr)), 6)
    assert [len(x["ratings"]) for x in s["fig5a"] + s["fig5b"]] == [2] * 6
    paper = {p["what"]: p for p in s["paper"]}
    assert paper["self_similarity_mean"]["value"] == 8.11
    assert paper["self_similarity_sd"]["value"] == 2.76
    assert "8.11 (standard deviation: 2.76)" in paper["self_similarity_mean"]["source"]
    json.dumps(s)                    # the export writes it as it is
    empty = summary(Mapping(8))
    assert empty["self"] == {"n": 0, "mean": None, "sd": None, "ratings": []}
    assert empty["fig4a"][0]["pitch"] == [None, None, None]
