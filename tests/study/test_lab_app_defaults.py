"""Issue 31 items 2 and 3: where the lab's apps (NU-Haptics-Lab/SinglePitchTexel,
their code read from the .mlapp archives) differed from texelpad, the app's way
is the default and the other a recorded config field.

- the guided app's nine rating trials (the similarity matrix): one texture at a
  time on the whole display, its fixed ratingorder, 50-sample texels;
- the pursuit's points above the display's Nyquist pitch play aliased, as the
  app's buildFine5 rendered them (space.aliased_samples)."""
from __future__ import annotations

import numpy as np
import pytest

import texel
from texelpad.space import Point, aliased_samples, is_above_nyquist, pitch_db, texel_params
from texelpad.study import configs, protocols, questions

DISPLAY = {"positions": 19200, "dx_um": 5.3}
EX = ("4sin", "pink", "sawtooth")
MATCHES = {r: {"pitch_db": 2.0 + i, "irregularity_db": -10.0 - i} for i, r in enumerate(EX)}
# guided_exploration_test_app: ratingorder = [3,1;2,1;1,1;3,2;2,2;1,2;3,3;2,3;1,3], rows
# [match, reference] (ratingsLog(match, reference) = the slider), written out by hand
APP_RATINGORDER = [(3, 1), (2, 1), (1, 1), (3, 2), (2, 2), (1, 2), (3, 3), (2, 3), (1, 3)]


def _header(proto, config, seed=4):
    st = protocols.start(proto, config, seed)
    return st, {"protocol": proto, "seed": seed,
                "config": protocols.resolved(proto, st, dict(config, texture_format=2))}


def test_the_similarity_matrix_runs_as_the_guided_app_rated():
    shipped = configs.load("similarity-matrix")["config"]
    assert shipped["texel_samples"] == 50          # the app's texelLength (was 47)
    st, h = _header("quant", dict(shipped, matches=MATCHES))
    c = h["config"]
    assert (c["order"], c["presentation"], c["texel_samples"]) == ("lab", "whole", 50)
    seen = []
    while not st.done:
        q = questions.ask("quant", st, h, DISPLAY)
        ref, match = st.current[0], st.current_match
        seen.append((EX.index(match) + 1, EX.index(ref) + 1))
        assert q.public["options"] == ["reference", "rendering"]
        assert q.public["presentation"] == "whole"
        # each on the whole display (101.76 mm), alone
        assert q.options[0]["regions"] == [{"start_mm": 0, "end_mm": 101.76, "texture": {
            "kind": "reference", "name": ref}}]
        (region,) = q.options[1]["regions"]
        assert (region["start_mm"], region["end_mm"]) == (0, 101.76)
        tex = region["texture"]
        assert tex["kind"] == "texel" and tex["texel_samples"] == 50
        assert tex["pitch_db"] == MATCHES[match]["pitch_db"]
        protocols.apply("quant", st, 3)
    assert seen == APP_RATINGORDER


def test_the_similarity_matrix_keeps_the_earlier_design_as_fields():
    st, h = _header("quant", {"design": "matrix", "references": list(EX), "matches": MATCHES,
                              "order": "seeded", "presentation": "split"}, seed=11)
    pairs = []
    while not st.done:
        q = questions.ask("quant", st, h, DISPLAY)
        assert q.public["options"] == ["rendering"]
        left, right = q.options[0]["regions"]
        assert (left["end_mm"], right["start_mm"]) == (50.88, 50.88)
        pairs.append((st.current_match, st.current[0]))
        protocols.apply("quant", st, 2)
    assert sorted(pairs) == sorted((m, r) for m in EX for r in EX)
    assert pairs != [(EX[m - 1], EX[r - 1]) for m, r in APP_RATINGORDER]
    for bad, what in (({"presentation": "left"}, "presentation: expected 'whole'"),
                      ({"order": "lab", "references": ["4sin", "pink"]}, "three references"),
                      ({"order": "lab", "repeats": 2}, "the app's 9 trials once")):
        with pytest.raises(ValueError, match=what):
            protocols.start("quant", dict({"design": "matrix", "references": list(EX)}, **bad), 1)
    # the other designs keep the quantization app's layout (reference left, rendering right)
    st = protocols.start("quant", {"design": "levels", "matches": MATCHES}, 1)
    assert (st.config.presentation, st.config.order) == ("split", "seeded")


def test_aliased_samples_below_nyquist_are_the_texel_texture_the_board_plays():
    for u, v, fmt in ((0.3, 0.4, 2), (0.8, 0.1, 2), (0.86, 0.9, 2), (0.5, 0.5, 1)):
        p = Point(u, v)
        assert not is_above_nyquist(p)
        t = texel_params(p, seed=5, v=fmt)
        want = list(texel.render_u16(dict(t, length_samples=9600), engine="int"))
        got = aliased_samples(p, 9600, seed=5, v=fmt)
        assert got == {"kind": "samples", "fit": "tile", "u16": want}, (u, v, fmt)


@pytest.mark.parametrize("u", [0.90, 0.95, 1.0])
def test_a_point_above_nyquist_aliases_where_sampling_folds_it(u):
    # the app's buildFine5 accumulates the phase of any pitch: at P above the sample rate's
    # half, the most regular texture of the space (v = 0: irregularity -25 dB, 10^-2.5 decade,
    # the texels' pitches spread by SD ~0.73 % of P) shows its alias |P - k * 188.68 c/mm| -
    # computed here by hand, found by the spectrum's peak within that spread
    p = Point(u, 0.0)
    assert is_above_nyquist(p)
    P = 10 ** (pitch_db(u) / 10)                   # c/mm: 20.6 .. 25 dB = 114 .. 316 c/mm
    fs = 1 / 0.0053                                # samples per mm
    alias = abs(P - round(P / fs) * fs)
    x = np.array(aliased_samples(p, 19200, seed=3)["u16"], float)
    spec = np.abs(np.fft.rfft(x - x.mean()))
    peak = np.argmax(spec) * fs / len(x)
    spread = P * (10 ** (10 ** (-25 / 10)) - 1)    # c/mm: one SD of the texels' pitches
    assert abs(peak - alias) < spread, (u, P, alias, peak, spread)
    assert abs(peak - 94.34) > 10                  # not the texture at Nyquist
    # clamped, the same point is the texture at Nyquist
    assert texel_params(p)["pitch_db"] == 19.747


def test_the_pursuit_plays_points_above_nyquist_aliased_unless_clamped():
    # a pursuit whose answers always take the higher pitch reaches above 19.747 dB
    for field, kind in (("alias", "samples"), ("clamp", "texel")):
        st, h = _header("pursuit", {"above_nyquist": field}, seed=29)
        assert h["config"]["above_nyquist"] == field
        kinds = set()
        while not st.done:
            q = questions.ask("pursuit", st, h, DISPLAY)
            for name, sc in zip(q.public["options"], q.options):
                if name == "reference":
                    continue
                point = q.detail[name]
                tex = sc["regions"][-1]["texture"]
                if point["pitch_db"] > 19.747:
                    kinds.add(tex["kind"])
                    assert q.detail["aliased"][name == "B"] == (field == "alias")
                    if field == "alias":
                        assert len(tex["u16"]) == 19200 and tex["fit"] == "tile"
                    else:
                        assert tex["pitch_db"] == 19.747
                else:
                    assert tex["kind"] == "texel"
            a, b = q.detail["A"]["pitch_db"], q.detail["B"]["pitch_db"]
            protocols.apply("pursuit", st, "A" if a > b else "B" if b > a else "unsure")
        assert kinds == {kind}
    with pytest.raises(ValueError, match="above_nyquist: expected 'alias'"):
        protocols.start("pursuit", {"above_nyquist": "fold"}, 1)
    # the split layout renders the right half's 9,600 samples
    st, h = _header("pursuit", {"presentation": "split"}, seed=29)
    st.centre = Point(0.95, 0.5)
    q = questions.ask("pursuit", st, h, DISPLAY)
    texs = [sc["regions"][1]["texture"] for sc in q.options]
    assert any(t["kind"] == "samples" and len(t["u16"]) == 9600 for t in texs)
