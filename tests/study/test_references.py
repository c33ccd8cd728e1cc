"""The nine references' positions on the pitch - irregularity plane
(texelpad.study.references: a spectral model, documented there) and the
pursuit-vs-search benchmark's run() on a tiny setting
(bench.study_compare). Fast; nothing here asserts on time."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from texel.gen.params import DX_MM, IRREG_DB_MAX, IRREG_DB_MIN, PITCH_DB_MAX, PITCH_DB_MIN
from bench import study_compare as SC
from texelpad.study import references as R
from texelpad.analysis import perception as P
from texelpad.study.space import Point, irregularity_db, pitch_db, texel_params

SINES = ("2sin", "3sin", "4sin")
NOISES = ("white", "pink", "blue")
SHAPED = ("square", "triangle", "sawtooth")


def test_the_nine_in_the_csv_order():
    assert R.REFERENCES == SINES + NOISES + SHAPED
    assert set(R.FAMILIES) == set(R.REFERENCES)
    with pytest.raises(ValueError, match="unknown"):
        R.position("bp-1-0.05")       # a texel reference, but not one of the study's nine


def test_the_model_on_a_pure_sine():
    """Units: a sine of 4 c/mm (9,434 samples of 5.3 um = 50.0002 mm: 200.0
    cycles, on a bin) -> pitch 10*log10 4 = 6.02 dB, and a narrow spread (the
    Hann window's main lobe only)."""
    n = 9434
    x = np.arange(n) * DX_MM
    p, irr = R.spectral_position(0.5 + 0.5 * np.sin(2 * math.pi * 4.0 * x))
    assert p == pytest.approx(10 * math.log10(4.0), abs=0.01)
    assert irr < -25.0                 # < 0.003 decade
    with pytest.raises(ValueError, match="flat"):
        R.spectral_position(np.full(100, 0.5))
    with pytest.raises(ValueError, match="weighting"):
        R.spectral_position(np.zeros(100), weighting="loudness")


def test_positions_behave_as_the_model_says():
    pos = R.positions()
    assert list(pos) == list(R.REFERENCES)
    for name, (p, irr) in pos.items():
        assert PITCH_DB_MIN <= p <= PITCH_DB_MAX and IRREG_DB_MIN <= irr <= IRREG_DB_MAX, name
    # sums of sines: the pitch rises as higher lines are added (seed 000), each near the
    # subjects' quoted mean Central Pitch (2sin is 1.1 dB above it: the docstring's table)
    assert pos["2sin"][0] < pos["3sin"][0] < pos["4sin"][0]
    for name in SINES:
        assert pos[name][0] == pytest.approx(R.PAPER_PITCH_DB[name], abs=1.2), name
    # shaped waveforms: near their 1 c/mm fundamental (0 dB) and below every sum of sines
    for name in SHAPED:
        assert abs(pos[name][0]) < 2.5 and pos[name][0] < pos["2sin"][0], name
    assert abs(pos["triangle"][0]) < 0.5            # harmonics 1/n^2: power 1/n^4
    # noise: pink (1/f) lower than white and blue, blue (high-passed) the highest pitch of all
    assert pos["pink"][0] < pos["white"][0] < pos["blue"][0]
    assert max(p for p, _ in pos.values()) == pos["blue"][0]
    # irregularity: white and pink more irregular than every sum of sines and every shaped
    # waveform, pink the most; blue is the documented exception (its power sits in the top
    # octaves: narrower in log f than the sums of sines)
    others = [pos[n][1] for n in SINES + SHAPED]
    assert pos["white"][1] > max(others) and pos["pink"][1] > max(others)
    assert max(irr for _, irr in pos.values()) == pos["pink"][1]
    assert pos["blue"][1] < pos["white"][1] and pos["blue"][1] < min(pos[n][1] for n in SINES)
    assert min(irr for _, irr in pos.values()) == pos["triangle"][1]


def test_power_is_closer_to_the_papers_pitches_than_magnitude():
    """Why the model weights by power (the docstring's table)."""
    def err(weighting):
        return [abs(R.position(n, weighting)[0] - q) for n, q in R.PAPER_PITCH_DB.items()]
    power, mag = err("power"), err("magnitude")
    assert np.mean(power) < 1.1 and max(power) < 2.5
    assert np.mean(mag) > 3 * np.mean(power)


def test_positions_agree_with_the_golden_rows(golden_dir):
    """texel's generator rows give the same points as the study's own data file."""
    rows = np.loadtxt(golden_dir / "reference_textures.csv", delimiter=",")
    assert rows.shape == (9, 9600)
    for name, row in zip(R.REFERENCES, rows):
        p, irr = R.clamp_to_generator(*R.spectral_position(row))
        assert (p, irr) == pytest.approx(R.position(name), abs=1e-3), name


def test_targets_are_inside_the_unit_square():
    for name in R.REFERENCES:
        t = R.target_point(name)
        assert 0.0 <= t.u <= 1.0 and 0.0 <= t.v <= 1.0, name
        # every one of the nine lies inside the square: the target is its position exactly
        p, irr = R.position(name)
        assert (pitch_db(t.u), irregularity_db(t.v)) == (pytest.approx(p), pytest.approx(irr))


@pytest.mark.parametrize("feel", ["plane", "felt"])
def test_benchmark_run_on_a_tiny_setting(feel):
    res = SC.run(references=("2sin",), seeds=1, noise_db=(0.0,), max_answers=8, feel=feel)
    assert res["config"]["pursuit_answers"] == 20 and res["config"]["feel"] == feel
    runs = {r["method"]: r for r in res["results"]}
    assert set(runs) == {"pursuit", "search"} and len(res["results"]) == 2
    pv, se = runs["pursuit"], runs["search"]
    assert len(pv["curve_db"]) == 21 and len(se["curve_db"]) == 9
    # both start at the centre (0.5, 0.5): the same distance to the target, the
    # participant's own (felt: on the felt plane of texelpad.analysis.perception)
    t = R.target_point("2sin")
    start = (math.hypot(pitch_db(0.5) - pitch_db(t.u), irregularity_db(0.5) - irregularity_db(t.v))
             if feel == "plane" else
             P.felt_distance(texel_params(Point(0.5, 0.5), texel_samples=50, gain=1.0),
                             texel_params(t, texel_samples=50, gain=1.0), n=9600))
    assert pv["curve_db"][0] == se["curve_db"][0] == pytest.approx(start, abs=0.02)
    # a noiseless participant: the pursuit gets nearer the target than it started
    # (its fixed 20 answers can overshoot again at the end: the figure in
    # docs/lab-benchmark.md shows the oscillation)
    assert min(pv["curve_db"][1:]) < pv["curve_db"][0]
    for r in (pv, se):
        assert r["final_db"] == r["curve_db"][-1]
        a = r["answers_to_1db"]
        assert a is None or (r["curve_db"][a] <= 1.0 and min(r["curve_db"][:a] or [9]) > 1.0)
    # the pursuit's centre moves only after every 4th answer
    c = pv["curve_db"]
    assert all(c[k] == c[k - 1] for k in range(1, 21) if k % 4)
    names = [row["reference"] for row in res["summary"]]
    assert names == ["2sin", "all"]
    for row in res["summary"]:
        for method in SC.METHODS:
            s = row[method]
            assert s["runs"] == 1 and 0.0 <= s["reached"] <= 1.0 and s["median_final_db"] >= 0
    table = SC.format_table(res)
    assert "2sin" in table and "pursuit (20 answers)" in table and "search (8 answers)" in table
    json.dumps(res, allow_nan=False)          # --json writes it as it stands


def test_benchmark_at_equal_textures_felt():
    """Issue 20: the two read at equal effort - 15 textures (5 picks of 3; the
    pursuit's 7 comparisons of 2) and 40 (its 20; 13 picks = 39)."""
    res = SC.run(references=("2sin",), seeds=2, noise_db=(1.0,), max_answers=14, feel="plane")
    cfg = res["config"]
    assert cfg["picks"] == 5 and cfg["budgets_textures"] == [15, 40]
    assert cfg["textures_per_answer"] == {"pursuit": 2, "search": 3}
    runs = [r for r in res["results"] if r["method"] == "pursuit"]
    for r in runs:
        c, p = r["curve_db"], r["partial_db"]
        # after a trial's 4th answer "so far" is the centre; inside a trial it has moved
        assert len(p) == len(c) == 21 and all(p[k] == c[k] for k in range(0, 21, 4))
        assert any(p[k] != c[k] for k in range(21) if k % 4)
    row = res["summary"][0]
    e15, e40 = row["effort"]
    assert (e15["textures"], e40["textures"]) == (15, 40)
    assert (e15["search"]["answers"], e15["search"]["textures"]) == (5, 15)
    assert (e15["pursuit"]["answers"], e15["pursuit"]["textures"]) == (7, 14)
    assert (e40["pursuit"]["answers"], e40["search"]["answers"], e40["search"]["textures"]) \
        == (20, 13, 39)
    search = [r for r in res["results"] if r["method"] == "search"]
    assert e15["search"]["median"] == pytest.approx(np.median([r["curve_db"][5] for r in search]))
    assert e15["pursuit"]["median"] == pytest.approx(np.median([r["curve_db"][7] for r in runs]))
    assert e15["pursuit"]["so_far"]["median"] == pytest.approx(
        np.median([r["partial_db"][7] for r in runs]))
    for e in (e15["search"], e15["pursuit"], e40["pursuit"], e40["search"]):
        assert e["q1"] <= e["median"] <= e["q3"] and 0.0 <= e["within"] <= 1.0
    table = SC.format_effort(res)
    for head in ("search 5 picks", "pursuit 7: centre", "pursuit 7: so far", "search 13 picks"):
        assert head in table
    # a search shorter than the budget is not read there: "-", no number made up
    short = SC.run(references=("2sin",), seeds=1, noise_db=(0.0,), max_answers=8, feel="plane")
    assert short["summary"][0]["effort"][1]["search"]["median"] is None
    json.dumps(short, allow_nan=False)
    with pytest.raises(ValueError, match="picks"):
        SC.run(references=("2sin",), seeds=1, noise_db=(0.0,), max_answers=4, picks=5)
