"""`texelpad lab export`'s figures that follow the papers (study/export.py
PAPER_FIGURES): seed 000 Fig. 10, 15, 14c and seed 001 Fig. 2, 4, 5 over
every session of a data folder. A synthetic folder of sessions (made as the
lab makes them: Session.create, protocols.start/apply, each answer with the
scene its question played); each figure is written when its sessions exist
and not otherwise, and the numbers it plots are the ones worked out here by
hand (issue 20 item 4)."""
from __future__ import annotations

import csv

import pytest

from texelpad import cli
from texelpad.study import configs as C
from texelpad.study import finger as F
from texelpad.study import protocols
from texelpad.study import questions as Q
from texelpad.study.describe import TPAD_DISPLAY
from texelpad.study.export import export
from texelpad.study.mapping import MEAN_BASE_CPMM, MEAN_RATIO
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.space import Point
from texelpad.study.quant import NINE
from texelpad.study.rater import match
from texelpad.study.session import Session

EXEMPLARS = ("4sin", "pink", "sawtooth")
GIVEN = {"matches": {r: {"pitch_db": 6.0, "irregularity_db": -12.0, "seed": 11 + k,
                         "texel_samples": 50, "v": 2} for k, r in enumerate(NINE)}}
BP = ("bp-1-0.05", "bp-1-0.5", "bp-1-5", "bp-4-0.05", "bp-4-0.5", "bp-4-5", "bp-20-0.05",
      "bp-20-0.5", "bp-20-5")


def _run(data, proto, participant, config, seed, answer, n=None, finger=None):
    """A session answered by answer(state) until done (or n answers); each
    record holds the scene its question played; with finger (a simulated
    participant), each question's 4 s of finger at 100 Hz as the lab writes
    it (study/finger.py) before its answer."""
    s = Session.create(data, proto, participant, dict(config), seed)
    st = protocols.start(proto, config, seed)
    k = 0
    while not st.done and (n is None or k < n):
        if finger is not None:
            s.append(F.record(k, k, 0, finger.finger(4.0, 100, TPAD_DISPLAY), 0, 100,
                              TPAD_DISPLAY["dx_um"]))
        if Q.sliding(proto, st):
            sc, _ = Q.slider_scene(st, s.header, TPAD_DISPLAY, *st.config.start, 0)
        else:
            sc = Q.ask(proto, st, s.header, TPAD_DISPLAY).options[0]
        a = answer(st)
        s.append({"answer": a, "scene": sc, "playing": 0})
        protocols.apply(proto, st, a)
        k += 1
    return s, st


def _free(shift):
    # the match of the reference in row i: pitch i + shift dB, irregularity -i - 1 dB
    def answer(st):
        i = NINE.index(st.reference)
        return {"pitch_db": i + shift, "irregularity_db": -i - 1.0, "confidence": 3}
    return answer


def _quant(base, quantized):
    # unquantized trials rate `base`, quantized ones quantized[q]
    def answer(st):
        return quantized[st.current[1]] if st.current[1] else base
    return answer


def _staircase_pattern():
    pattern = [True, True, True, False]
    return lambda st: pattern[len(st.track) % 4]


def _mapping_answer(st):
    if st.phase == "match":
        i = BP.index(st.reference)
        return {"pitch": 10.0 * i, "irregularity": 5.0 * i + 10.0}
    ref, of = st.current
    return 10 if ref == of else (len(ref) + len(of)) % 11


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("lab")
    data, out = root / "data", root / "out"
    _run(data, "free", "p1", {}, 1, _free(0.0))
    _run(data, "free", "p2", {}, 2, _free(0.5))
    _run(data, "quant", "p1", GIVEN, 3, _quant(5, {1.0: 4, 3.0: 3, 5.0: 1}))
    _run(data, "quant", "p2", GIVEN, 4, _quant(4, {1.0: 4, 3.0: 4, 5.0: 4}))
    matrix = C.load("similarity-matrix")["config"]
    _run(data, "quant", "p1", matrix, 5, lambda st: 5 if st.current_match == st.current[0]
         else 2)
    _run(data, "quant", "p2", matrix, 6, lambda st: 4 if st.current_match == st.current[0]
         else 1)
    # the finger: p1 swipes rightward only (lifted back), p2 both ways, 91.76 mm/s - one
    # 91.76-mm span (5 mm from each end of the 101.76-mm display) a second
    one_way = SimulatedParticipant(Point(0.5, 0.5), swipe_mm_s=91.76, one_way=True)
    both = SimulatedParticipant(Point(0.5, 0.5), swipe_mm_s=91.76)
    _run(data, "staircase", "p1", {}, 7, _staircase_pattern(), finger=one_way)
    _run(data, "staircase", "p2", {"condition": "wide"}, 8, lambda st: True, n=5, finger=both)
    _, mapping_state = _run(data, "mapping", "p1", {}, 9, _mapping_answer)
    # the guided explorations: three of each exemplar (always A; always B; A, unsure in turn)
    for e in EXEMPLARS:
        for j, pick in enumerate((lambda k: "A", lambda k: "B",
                                  lambda k: "A" if k % 2 else "unsure")):
            ks = iter(range(20))
            _run(data, "pursuit", "g%d" % j, {"reference": {"kind": "reference", "name": e}},
                 20 + j, lambda st, pick=pick, ks=ks: pick(next(ks)))
    # two searches of 4sin: 2 picks, the friction slider moved once, one save; 3 picks, never
    search = dict(C.load("search-4sin")["config"], reference={"kind": "reference",
                                                                "name": "4sin"})
    for who, answers in (("p1", [{"choose": 0, "level": 1.0}, {"choose": 1, "level": 0.6},
                                 {"save": 0, "level": 0.6}, {"stop": True}]),
                         ("p2", [{"choose": 2}, {"choose": 0}, {"choose": 1}, {"stop": True}])):
        it = iter(answers)
        _run(data, "search", who, search, 12, lambda st: next(it))
    res = export(data, out)
    return res, out, mapping_state


def test_every_paper_figure_is_written_from_its_sessions(exported):
    res, out, _ = exported
    assert res["broken"] == [] and len(res["figures"]) == 20
    assert sorted(res["study_figures"]) == sorted([
        "seed000_fig10_matches.png", "seed000_fig11_guided.png", "seed000_fig12_plane.png",
        "seed000_fig13_confidence.png", "seed000_fig14ab_similarity.png",
        "seed000_fig15_quantization.png",
        "seed000_fig14c_similarity.png", "seed001_fig2_staircase.png",
        "seed001_fig3_direction.png", "seed003_table1_search.png",
        "seed001_fig4_mapping.png", "seed001_fig5_ratings.png"])
    for name, (path, _) in res["study_figures"].items():
        assert path == out / name and path.stat().st_size > 5000


def test_fig10_plots_every_match_per_reference_and_the_raters_choice(exported):
    d = exported[0]["study_figures"]["seed000_fig10_matches.png"][1]
    assert d["references"] == list(NINE)
    assert d["pitch_db"] == [[float(i), i + 0.5] for i in range(9)]   # p1, then p2
    assert d["irregularity_db"] == [[-i - 1.0, -i - 1.0] for i in range(9)]
    assert d["rater"] == [match(r) for r in NINE]
    assert d["families"][:3] == ["sums of sinusoids"] * 3


def test_fig15_plots_the_change_from_the_unquantized_rating(exported):
    """p1 rates unquantized 5 and quantized 4, 3, 1 at q = 1, 3, 5: changes
    -1, -2, -4; p2 rates everything 4: changes 0 (same exemplar, same
    source: the rater's, whose renderings the paper's design quantizes)."""
    d = exported[0]["study_figures"]["seed000_fig15_quantization.png"][1]
    assert d["exemplars"] == list(EXEMPLARS) and d["levels_db"] == [1.0, 3.0, 5.0]
    assert d["changes"] == [[[-1.0, 0.0], [-2.0, 0.0], [-4.0, 0.0]]] * 3


def test_fig14c_is_the_mean_matrix_of_the_matrix_sessions(exported):
    d = exported[0]["study_figures"]["seed000_fig14c_similarity.png"][1]
    assert d["references"] == list(EXEMPLARS)
    assert d["mean"] == [[4.5 if i == j else 1.5 for j in range(3)] for i in range(3)]
    assert d["n"] == [[2] * 3] * 3


def test_fig2_plots_the_tracks_and_the_convergent_lengths(exported):
    """p1: C C C W repeated (tests/study/test_protocols.py works it out):
    reversals at 23.5, 26, ..., 24.75, 23.5, 24.75, threshold their mean from
    the 8th; p2 (wide) answered 5 right: 26 mm three times, then 23.5 - no
    reversal, no convergent length."""
    d = exported[0]["study_figures"]["seed001_fig2_staircase.png"][1]
    p1, p2 = d["tracks"]
    assert (p1["condition"], p2["condition"]) == ("narrow", "wide")
    assert [p1["length_mm"][i] for i in p1["reversals"]] == \
        [23.5, 26.0, 23.5, 26.0, 23.5, 26.0, 23.5, 24.75, 23.5, 24.75]
    assert p1["threshold_mm"] == pytest.approx((24.75 + 23.5 + 24.75) / 3)
    assert p2["length_mm"] == [26.0, 26.0, 26.0, 23.5, 23.5] and p2["reversals"] == []
    assert d["conditions"] == ["narrow"] and d["convergent_mm"] == [[p1["threshold_mm"]]]


def test_fig4_plots_the_chosen_pitch_and_irregularity(exported):
    """Reference i of Table I (fc outer, zeta inner) matched at P = 10 i:
    mean 0.75 * 1.04^(10 i) c/mm; I = 5 i + 10, normalised over the nine
    (10 .. 50): i / 8."""
    d = exported[0]["study_figures"]["seed001_fig4_mapping.png"][1]
    fcs, zetas = d["fc_cpmm"], d["zetas"]
    assert (fcs, zetas) == ([1.0, 4.0, 20.0], [0.05, 0.5, 5.0])
    for iz in range(3):
        for jf in range(3):
            i = 3 * jf + iz
            want = MEAN_BASE_CPMM * MEAN_RATIO ** (10 * i)
            assert d["fig4a_mean_cpmm"][iz][jf] == [pytest.approx(want, abs=1e-6)]
            assert d["fig4b_irregularity_normalised"][jf][iz] == [pytest.approx(i / 8)]


def test_fig5_plots_the_ratings_of_the_papers_pairs(exported):
    d = exported[0]["study_figures"]["seed001_fig5_ratings.png"][1]

    def r(a, b):                        # the rating _mapping_answer gave the pair
        return 10 if a == b else (len(a) + len(b)) % 11
    assert d["fig5a"] == [[r("bp-1-%s" % z, "bp-20-%s" % z)] * 2 for z in ("0.05", "0.5", "5")]
    assert d["fig5b"] == [[r("bp-%s-0.05" % f, "bp-%s-5" % f)] * 2 for f in ("1", "4", "20")]
    assert d["self"] == [10] * 9 and d["paper_self_mean"] == 8.11


def test_the_csv_has_the_mapping_and_the_sources(exported):
    _, out, st = exported
    rows = list(csv.DictReader(open(out / "sessions.csv")))
    mapping = [r for r in rows if r["protocol"] == "mapping"]
    assert len(mapping) == 34
    first = mapping[0]
    m = st.matches[0]
    assert (first["reference"], float(first["pitch_slider"]),
            float(first["irregularity_slider"]), float(first["match_pitch_db"])) == \
        (m["reference"], m["pitch"], m["irregularity"], m["pitch_db"])
    rated = mapping[9]
    assert (rated["reference"], rated["match_of"]) == tuple(st.pairs[0])
    assert rated["similarity"] == str(st.ratings[0]["similarity"])
    quant = [r for r in rows if r["protocol"] == "quant" and r["config_file"] == ""]
    assert {r["source"] for r in quant} == {"own", "rater"}


def test_a_figure_is_written_only_when_its_sessions_exist(tmp_path, capsys):
    data, out = tmp_path / "data", tmp_path / "out"
    _run(data, "staircase", "p1", {}, 1, lambda st: True, n=3)
    _run(data, "free", "p1", {}, 1, _free(0.0), n=0)          # started, no match yet
    _run(data, "mapping", "p1", {}, 1, _mapping_answer, n=3)  # matches, no rating yet
    res = export(data, out)
    assert sorted(res["study_figures"]) == ["seed001_fig2_staircase.png",
                                            "seed001_fig4_mapping.png"]
    assert sorted(p.name for p in out.glob("seed*.png")) == sorted(res["study_figures"])
    only = tmp_path / "pursuit"
    _run(only, "pursuit", "p1", {}, 1, lambda st: "A", n=4)
    assert cli.main(["lab", "export", "--data", str(only), "--out", str(tmp_path / "o2")]) == 0
    printed = capsys.readouterr().out
    assert "and 1 figures" in printed and "papers' figures" not in printed
    assert list((tmp_path / "o2").glob("seed*.png")) == []


def test_fig3_plots_each_subjects_directional_proportion_against_its_convergent_length(exported):
    """Each trial: 4 s at 100 Hz = 400 samples, 1-s swipes. p1 (rightward, lifted back):
    samples 1..99 and 201..299 swipe right (0 and 200 follow a lift) = 198, none left:
    proportion 198/400 = 0.495 every trial. p2 (both ways): right 1..100 and 201..300 =
    200, left 101..200 and 301..399 = 199: 1/400 = 0.0025. Every swiping sample moves
    0.9176 mm in 10 ms: 91.76 mm/s, to the position's rounding (5.3 um in 0.92 mm)."""
    res, out, _ = exported
    d = res["study_figures"]["seed001_fig3_direction.png"][1]
    p1, p2 = d["subjects"]
    assert (p1["participant"], p2["participant"]) == ("p1", "p2")
    assert p1["per_trial"] == [0.495] * p1["trials"]
    assert p1["directional_proportion"] == pytest.approx(0.495, abs=1e-12)
    assert p2["per_trial"] == [0.0025] * 5
    assert p2["directional_proportion"] == pytest.approx(0.0025, abs=1e-12)
    assert abs(p1["speed_mm_s"] - 91.76) < 0.05 and p1["speed_sd_mm_s"] < 0.3
    assert p1["convergent_mm"] is not None and p2["convergent_mm"] is None
    assert d["r"] == {"speed_mm_s": None, "speed_sd_mm_s": None,       # (one subject plotted)
                      "directional_proportion": None}
    with open(out / "sessions.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["protocol"] == "staircase"]
    assert {r["finger_samples"] for r in rows} == {"400"}
    assert {r["directional_proportion"] for r in rows} == {"0.495", "0.0025"}


def test_fig3_r_is_pearsons_over_the_subjects_with_both(tmp_path):
    # three subjects with convergent lengths: DP 0.495 (one way) at three speeds against
    # lengths from three answer patterns; R of the speeds worked out with numpy here
    import numpy as np
    from texelpad.study.export import fig3_data
    loaded = []
    # (each pattern ends its staircase: thresholds 24.33, 33.5 and 13.5 mm)
    for k, (pattern, speed, one_way) in enumerate((([True] * 3 + [False], 60.0, True),
                                                   ([True] * 3 + [False] * 2, 90.0, False),
                                                   ([True] * 6 + [False], 120.0, True))):
        sim = SimulatedParticipant(Point(0.5, 0.5), swipe_mm_s=speed, one_way=one_way)
        s, st = _run(tmp_path, "staircase", "s%d" % k, {}, 3,
                     (lambda pat: lambda st: pat[len(st.track) % len(pat)])(pattern),
                     n=60, finger=sim)
        assert st.done
        loaded.append((Session.open(s.path), st))
    d = fig3_data(loaded)
    xs = [x["convergent_mm"] for x in d["subjects"]]
    assert None not in xs and len(set(xs)) == 3
    for key in ("speed_mm_s", "directional_proportion"):
        ys = [x[key] for x in d["subjects"]]
        assert d["r"][key] == round(float(np.corrcoef(xs, ys)[0, 1]), 4)


def test_table1_counts_each_searchs_iterations_tunings_and_time(exported):
    """p1: two picks, the slider moved once (1.0 -> 0.6; the save at 0.6 moves nothing), one
    save; p2: three picks, the slider never moved. Mean and SD (n - 1) over the two."""
    res, out, _ = exported
    d = res["study_figures"]["seed003_table1_search.png"][1]
    (row,) = d["rows"]
    assert row["reference"] == "4sin" and row["sessions"] == 2 and row["slider"]
    assert row["iterations"] == [2.5, round(0.5 ** 0.5, 4)]
    assert row["tunings"] == [0.5, round(0.5 ** 0.5, 4)]
    assert row["saved"] == [0.5, round(0.5 ** 0.5, 4)]
    assert 0 <= row["minutes"][0] < 1                  # (written in a moment here)
    assert [r["reference"] for r in d["paper"]] == ["ABS", "Wood", "Fiberglass", "Canvas",
                                                    "Stone"]
    with open(out / "seed003_table1_search.csv") as f:
        (r,) = list(csv.DictReader(f))
    assert r["reference"] == "4sin" and float(r["iterations_mean"]) == 2.5


def _pursuit_ends():
    """The guided explorations' end points, replayed here from their files."""
    from texelpad.study.session import sessions
    ends = {}
    for path in sessions(_pursuit_ends.data):
        s = Session.open(path)
        if s.header["protocol"] == "pursuit":
            st = protocols.replay(s)
            ends.setdefault(s.header["config"]["reference"]["name"], []).append(
                protocols.get("pursuit").estimate(st))
    return ends


def test_fig11_and_fig12_plot_the_guided_end_points_beside_the_free_matches(exported):
    res, out, _ = exported
    _pursuit_ends.data = out.parent / "data"
    ends = _pursuit_ends()
    d = res["study_figures"]["seed000_fig11_guided.png"][1]
    assert d["references"] == list(EXEMPLARS)
    assert d["guided_pitch_db"] == [[m["pitch_db"] for m in ends[e]] for e in EXEMPLARS]
    assert d["guided_irregularity_db"] == [[m["irregularity_db"] for m in ends[e]]
                                           for e in EXEMPLARS]
    assert all(len(x) == 3 for x in d["guided_pitch_db"])
    # the free matches of row i: pitch i + 0 (p1) and i + 0.5 (p2), irregularity -i - 1
    rows = [NINE.index(e) for e in EXEMPLARS]
    assert d["free_pitch_db"] == [[float(i), i + 0.5] for i in rows]
    assert d["free_irregularity_db"] == [[-i - 1.0, -i - 1.0] for i in rows]
    d12 = res["study_figures"]["seed000_fig12_plane.png"][1]
    assert [x["points"] for x in d12["guided"]] == [
        [[m["pitch_db"], m["irregularity_db"]] for m in ends[e]] for e in EXEMPLARS]
    # two free matches per exemplar: too few for an ellipse; three guided: one each
    assert all(x["ellipse"] is None for x in d12["free"])
    assert all(x["ellipse"]["n"] == 3 for x in d12["guided"])


def test_the_confidence_ellipse_of_the_mean_by_hand():
    from texelpad.study.export import confidence_ellipse
    # (+-1, 0), (0, +-1): mean 0, S = diag(2/3, 2/3); k = 2 (n-1) / (n (n-2)) F(.95; 2, 2)
    # = 6/8 * 19 = 14.25 (F(.95; 2, 2) = 19 exactly: 1/(1-.95)^(2/2) - 1): semi-axes
    # sqrt(14.25 * 2/3) = sqrt(9.5)
    e = confidence_ellipse([[1, 0], [-1, 0], [0, 1], [0, -1]])
    assert e["centre"] == [0.0, 0.0]
    assert e["semi_axes"] == pytest.approx([9.5 ** 0.5] * 2)
    # stretched along x by 3: the first axis 3 times the second, at 0 degrees
    e = confidence_ellipse([[3, 0], [-3, 0], [0, 1], [0, -1]])
    assert e["semi_axes"][0] == pytest.approx(3 * e["semi_axes"][1])
    assert e["angle_deg"] % 180 == pytest.approx(0.0)
    assert confidence_ellipse([[0, 0], [1, 1]]) is None                 # n < 3
    assert confidence_ellipse([[0, 0], [1, 1], [2, 2]]) is None         # on a line


def test_fig13_and_fig14ab_plot_confidence_and_own_similarity(exported):
    import math
    res = exported[0]
    d = res["study_figures"]["seed000_fig13_confidence.png"][1]
    assert len(d["points"]) == 18 and {p["confidence"] for p in d["points"]} == {3}
    for p in d["points"]:
        i, r = NINE.index(p["reference"]), match(p["reference"])
        assert p["distance_db"] in [round(math.hypot(i + shift - r["pitch_db"],
                                                     -i - 1.0 - r["irregularity_db"]), 6)
                                    for shift in (0.0, 0.5)]
    d = res["study_figures"]["seed000_fig14ab_similarity.png"][1]
    # own unquantized ratings: p1 5, p2 4 (the paper design's 'base'); the matrix's
    # diagonal: p1 5, p2 4
    assert d["free"]["references"] == list(NINE)
    assert d["free"]["similarity"] == [[5, 4]] * 9
    assert d["guided"] == {"references": list(EXEMPLARS), "similarity": [[5, 4]] * 3}


def test_simulated_sessions_of_every_protocol_make_every_papers_figure(tmp_path):
    # issue 31: `texelpad lab export` on simulated sessions of every protocol (the simulated
    # participant answering; its finger on the staircase; searches saved and stopped, then
    # evaluated) makes every figure and table PAPER_FIGURES lists
    from texelpad.study.export import PAPER_FIGURES
    from texelpad.study.references import target_point
    data = tmp_path / "data"
    saved = []
    for k in range(3):
        who = "sim%d" % k
        sim = SimulatedParticipant(target_point("pink"), noise=0.01, seed=k, threshold_mm=3.0 + k,
                                   swipe_mm_s=60.0 + 20 * k, one_way=k == 0)

        def ans(proto):
            return lambda st: sim.answer(proto, st)
        free, fst = _run(data, "free", who, {}, k, ans("free"))
        from texelpad.study.matches import from_free
        _run(data, "quant", who, {"matches": from_free(Session.open(free.path), fst)}, k,
             ans("quant"))
        for e in EXEMPLARS:
            sim.target = target_point(e)
            _run(data, "pursuit", who, {"reference": {"kind": "reference", "name": e}}, k,
                 ans("pursuit"))
        _run(data, "quant", who, dict(C.load("similarity-matrix")["config"]), k, ans("quant"))
        _run(data, "staircase", who, {}, k, ans("staircase"), n=200, finger=sim)
        search = {"reference": {"kind": "reference", "name": "4sin"}}
        picks = iter([{"choose": 0}] * 3 + [{"save": 1}, {"stop": True}])
        srch, sst = _run(data, "search", who, search, k, lambda st: next(picks))
        _run(data, "mapping", who, {}, k, ans("mapping"))
        from texelpad.study.matches import from_saved
        saved.append(from_saved(Session.open(srch.path), sst))
    # seed 003's Phase 2: another simulated participant rates the three saved textures
    _, ev = _run(data, "evaluate", "sim9", {"textures": saved}, 9,
                 lambda st: protocols.get("evaluate").simulate(None, st))
    assert ev.done and len(ev.ratings) == (1 + 1 + 3) * 3 + 4   # RT, VTd, 3 VTp; 4 pairs
    res = export(data, tmp_path / "out")
    assert res["broken"] == []
    assert sorted(res["study_figures"]) == sorted(name for name, _, _ in PAPER_FIGURES)
