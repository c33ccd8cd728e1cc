"""The study protocols as pure logic (texelpad.study, texelpad.search), driven
by hand and by the simulated participant: the pursuit vector against a worked
example, the staircase's reversal and stop rules, CMA-ES reaching a target
with a noiseless participant, and sessions that resume after a kill at every
step (../shared/SPEC.md §5, §7)."""
from __future__ import annotations

import math

import pytest

import texel
from texelpad.search.preference import PreferenceSearch, candidate_params
from texelpad.study import protocols
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.pursuit import STEP, Pursuit
from texelpad.study.quant import NINE
from texelpad.study.session import Session, SessionError, check_name
from texelpad.study.space import Point, irregularity_db, pitch_db, texel_params, to_point
from texelpad.study.staircase import Staircase

R2 = 1 / math.sqrt(2)


def _pick(q, r: int) -> str:
    """The A/B answer that means r_k = r for comparison q."""
    if r == 0:
        return "unsure"
    return "A" if (r == 1) == q.a_is_plus else "B"


# --- the space ---------------------------------------------------------------------------

def test_space_is_the_papers_and_its_textures_are_valid():
    assert pitch_db(0) == -15 and pitch_db(1) == 25 and irregularity_db(0) == -25
    assert irregularity_db(1) == 5
    # P = 10^(4u - 1.5) c/mm, sigma = 10^(3v - 2.5) decades
    u, v = 0.3, 0.6
    assert math.isclose(10 ** (pitch_db(u) / 10), 10 ** (4 * u - 1.5))
    assert math.isclose(10 ** (irregularity_db(v) / 10), 10 ** (3 * v - 2.5))
    back = to_point(pitch_db(u), irregularity_db(v))
    assert (back.u, back.v) == (pytest.approx(u), pytest.approx(v))
    # beyond Nyquist (u > 0.8687) the texture is clamped to the display's limit
    p = texel_params(Point(1.0, 1.0), v=2)
    assert p["pitch_db"] == 19.747 and texel.validate(p)["v"] == 2


# --- the pursuit vector ------------------------------------------------------------------

def test_pursuit_worked_example_by_hand():
    """Trial 1 from (0.5, 0.5), edge 1: N +1, NE +1, E -1, SE unsure.
    p = (0, 1) + (1/sqrt2, 1/sqrt2) - (1, 0) = (1/sqrt2 - 1, 1 + 1/sqrt2);
    step 0.1 / (1 + sqrt2): u moves -0.0121320, v +0.0707107 (= 0.1/sqrt2)."""
    pv = Pursuit(seed=1)
    pts = {name: (plus, minus) for name, plus, minus in pv.points()}
    assert pts["N"] == (Point(0.5, 0.75), Point(0.5, 0.25))             # radius edge/4
    assert pts["NE"][0] == Point(0.5 + 0.25 * R2, 0.5 + 0.25 * R2)
    want = {"N": 1, "NE": 1, "E": -1, "SE": 0}
    seen = []
    for i in range(4):
        q = pv.next_comparison()
        seen.append(q.direction)
        assert {q.a, q.b} == set(pts[q.direction])
        out = pv.answer(_pick(q, want[q.direction]))
        assert (out == {}) == (i < 3)
    assert sorted(seen) == sorted(want)
    assert out["r"] == want
    assert out["pursuit"] == [pytest.approx(R2 - 1), pytest.approx(1 + R2)]
    assert math.isclose(STEP, 0.1 / (1 + math.sqrt(2)))
    assert pv.centre.u == pytest.approx(0.5 - 0.0121320, abs=1e-7)
    assert pv.centre.v == pytest.approx(0.5 + 0.0707107, abs=1e-7)
    assert pv.edge == pytest.approx(0.8) and pv.trial == 1


def test_pursuit_stops_after_5_trials_of_4_comparisons_in_random_order_and_sides():
    pv = Pursuit(seed=3)
    orders, sides, n = [], [], 0
    while not pv.done:
        trial = []
        for _ in range(4):
            q = pv.next_comparison()
            trial.append(q.direction)
            sides.append(q.a_is_plus)
            pv.answer("A")
            n += 1
        orders.append(tuple(trial))
    assert n == 20 and len(pv.history) == 5 and pv.next_comparison() is None
    assert [h["edge"] for h in pv.history] == pytest.approx([1.0, 0.8, 0.6, 0.4, 0.2])
    assert len(set(orders)) > 1 and 0 < sum(sides) < 20            # drawn, not fixed
    with pytest.raises(ValueError, match="finished"):
        pv.answer("A")
    # the same seed asks the same questions
    again = Pursuit(seed=3)
    assert again.next_comparison() == Pursuit(seed=3).next_comparison()


def test_pursuit_moves_towards_a_noiseless_participants_target():
    target = Point(0.3, 0.7)
    sim = SimulatedParticipant(target)
    pv = Pursuit(seed=5)
    d0 = pv.centre.distance(target)
    while not pv.done:
        q = pv.next_comparison()
        pv.answer(sim.compare(q.a, q.b))
    assert pv.centre.distance(target) < d0 - 0.2
    with pytest.raises(ValueError, match="answer: expected"):
        Pursuit(seed=1).answer("left")


# --- the staircase ---------------------------------------------------------------------

def test_staircase_reversals_step_change_and_stop_by_hand():
    """CCC W repeated: reversals alternate between 23.5 and 26 mm; after the
    7th (at 23.5) the step is 1.25 mm; the 10th ends it."""
    sc = Staircase()
    assert sc.length_mm == 26.0 and sc.texel_samples() == round(26 / 0.0053)
    pattern = [True, True, True, False]
    i = 0
    while not sc.done:
        sc.answer(pattern[i % 4])
        i += 1
    assert sc.reversals == [23.5, 26.0, 23.5, 26.0, 23.5, 26.0, 23.5, 24.75, 23.5, 24.75]
    assert sc.threshold_mm() == pytest.approx((24.75 + 23.5 + 24.75) / 3)
    steps = [t["step_mm"] for t in sc.track]
    assert steps[0] == 2.5 and steps[-1] == 1.25
    with pytest.raises(ValueError, match="finished"):
        sc.answer(True)
    with pytest.raises(ValueError, match="True or False"):
        Staircase().answer(1)


def test_staircase_converges_near_a_simulated_threshold():
    """1-up-3-down tracks 79.4 % correct: with P(correct) = 1/3 + 2/3 *
    logistic((L - 6 mm) / 1 mm), that is L = 6 + ln(0.691/0.309) = 6.8 mm."""
    ends = []
    for seed in range(20):
        sim = SimulatedParticipant(Point(0, 0), seed=seed, threshold_mm=6.0, slope_mm=1.0)
        sc = Staircase()
        while not sc.done:
            sc.answer(sim.odd_one_out(sc.length_mm))
        ends.append(sc.threshold_mm())
    mean = sum(ends) / len(ends)
    print("\nstaircase thresholds over 20 simulated runs: mean %.2f mm" % mean)
    assert 4.0 < mean < 10.0


# --- the preference search ----------------------------------------------------------------

@pytest.mark.parametrize("target", [Point(0.3, 0.7), Point(0.75, 0.2), Point(0.5, 0.5)])
def test_search_reaches_a_noiseless_participants_target(target):
    # (cma's active update; seed 003's rank-one update, the default, is measured beside it in
    # docs/lab-benchmark.md: bench/results/study_compare_rank_one.txt)
    s = PreferenceSearch(seed=11, cma_update="active")
    sim = SimulatedParticipant(target)
    for _ in range(60):
        xs = s.ask()
        assert len(xs) == 3 and all(0 <= v <= 1 for x in xs for v in x)
        s.choose(sim.pick(xs))
        if Point(*s.mean).distance(target) < 0.025:          # 1 dB of pitch
            break
    print("\nsearch to %s: %d iterations, %d choices, mean %s"
          % (target, s.iteration, s.iteration, [round(v, 3) for v in s.mean]))
    assert Point(*s.mean).distance(target) < 0.025


def test_the_searchs_update_is_the_one_its_config_names():
    # seed 003's Algorithm 1 adapts C "by rank-one update": no negative weights, no rank-mu
    for update, negative, rank_mu in (("rank_one", False, False), ("positive", False, True),
                                      ("active", True, True)):
        sp = PreferenceSearch(seed=3, cma_update=update)._es.sp
        assert (min(sp.weights) < 0) == negative and (sp.cmu > 0) == rank_mu, update
    assert PreferenceSearch(seed=3).cma_update == "rank_one"
    with pytest.raises(ValueError, match="cma_update: expected"):
        PreferenceSearch(seed=3, cma_update="fast")


def test_the_friction_slider_sets_every_candidates_level_and_counts_its_tunings():
    s = PreferenceSearch(seed=4)
    assert s.level_slider and s.level == 1.0
    assert all(c["gain"] == 1.0 for c in s.candidates())
    s.choose(0)                                 # no level: unchanged, no tuning
    s.choose(1, level=0.6)
    assert s.level == 0.6 and s.tunings == 1
    assert all(c["gain"] == 0.6 for c in s.candidates())
    s.save(2, level=0.6)                        # the same level: no tuning
    s.choose(2, level=0.45)
    assert s.tunings == 2 and s.history[-1]["level"] == 0.45 and s.saved[0]["params"]["gain"] == 0.6
    for bad in (0.1, 1.5, True, "0.5", float("nan")):
        with pytest.raises(ValueError, match="level: expected"):
            s.choose(0, level=bad)
    assert s.iteration == 3 and s.level == 0.45        # a refused answer changed nothing
    s.save(0, level=0.7)                        # moved twice in one iteration: one tuning
    s.choose(0, level=0.8)
    assert s.tunings == 3
    with pytest.raises(ValueError, match="no friction slider"):
        PreferenceSearch(seed=4, level_slider=False).choose(0, level=0.5)
    with pytest.raises(ValueError, match="not both"):
        PreferenceSearch(seed=4, dims=("pitch", "irregularity", "level"))


def test_search_is_mirrored_ranked_and_deterministic():
    s = PreferenceSearch(seed=2)
    xs = s.ask()
    m = s.mean
    # two of the three mirror each other about the mean (CMA_mirrors = 1)
    assert any(all(math.isclose(a + b, 2 * c, abs_tol=1e-9) for a, b, c in zip(xs[i], xs[j], m))
               for i in range(3) for j in range(i + 1, 3))
    rec = s.choose(1)
    assert rec["ranking"][0] == 1 and sorted(rec["ranking"]) == [0, 1, 2]
    t = PreferenceSearch(seed=2)
    t.ask()
    assert t.choose(1)["ranking"] == rec["ranking"] and t.mean == s.mean
    saved = s.save(0)
    assert texel.validate(saved["params"])["v"] == 2
    with pytest.raises(ValueError, match="choice"):
        s.choose(3)
    p = candidate_params([0.5, 0.5, 0.0, 1.0], ("pitch", "irregularity", "texel_length", "level"))
    assert p["texel_samples"] == round(0.05 / 0.0053) and p["gain"] == 1.0


# --- sessions ----------------------------------------------------------------------------

@pytest.mark.parametrize("bad", ["", "../x", "a/b", "x" * 41, "nul\0", "é", None, 7])
def test_names_cannot_escape_the_data_folder(bad, tmp_path):
    with pytest.raises(SessionError):
        Session.create(tmp_path, "pursuit", bad, {}, 1)
    assert list(tmp_path.iterdir()) == []


def _run_pursuit(sess: Session, state: Pursuit, sim: SimulatedParticipant, stop_after=None):
    k = 0
    while not state.done and (stop_after is None or k < stop_after):
        q = state.next_comparison()
        a = sim.compare(q.a, q.b)
        sess.append({"question": [q.direction, q.a_is_plus], "answer": a,
                     "scene": {"regions": []}, "state": {"centre": [state.centre.u,
                                                                    state.centre.v]}})
        state.answer(a)
        k += 1


# the paper's 27 (study/quant.py): the participant's own matches of the nine, as
# a free exploration's felt textures give them (seed, texel length, format)
GIVEN = {"matches": {r: {"pitch_db": 6.0, "irregularity_db": -12.0, "seed": 11 + k,
                         "texel_samples": 50, "v": 2} for k, r in enumerate(NINE)}}
EVALUATE = {"textures": [{"name": "VTp a", "reference": "4sin", "texture": {
    "pitch_db": 7.0, "irregularity_db": -6.0, "seed": 7, "v": 2, "gain": 0.6}},
    {"name": "VTp b", "reference": "pink", "texture": {"pitch_db": 8.0,
                                                       "irregularity_db": -1.0, "seed": 7}}]}
CONFIGS = {"free": {}, "quant": GIVEN, "pursuit": {}, "staircase": {},
           "search": {"dims": ["pitch", "irregularity"]}, "mapping": {}, "evaluate": EVALUATE}


def _end(protocol, state):
    return {"free": lambda: state.matches, "quant": lambda: state.ratings,
            "evaluate": lambda: state.ratings,
            "staircase": lambda: state.track,
            "mapping": lambda: (state.matches, state.ratings)}.get(
                protocol, lambda: state.history)()


@pytest.mark.parametrize("protocol", ["free", "quant", "pursuit", "staircase", "search",
                                      "mapping", "evaluate"])
def test_a_session_resumes_after_a_kill_at_every_step(protocol, tmp_path):
    """The uninterrupted run, then for every answer k a copy of the file as a
    crash would leave it after k answers (and with a torn half record after
    it): replaying the copy and going on gives the same end state."""
    target = Point(0.35, 0.65)
    config = CONFIGS[protocol]
    full = Session.create(tmp_path / "full", protocol, "p01", config, 9)
    state = protocols.start(protocol, config, 9)
    sim = SimulatedParticipant(target, noise=0.02, seed=3)
    answers = []
    for _ in range(20 if protocol != "search" else 12):
        if state.done:
            break
        a = sim.answer(protocol, state)
        full.append({"answer": a})
        protocols.apply(protocol, state, a)
        answers.append(a)
    end = _end(protocol, state)
    lines = full.path.read_bytes().splitlines(keepends=True)
    for k in range(len(answers) + 1):
        for torn in (False, True):
            copy = tmp_path / ("crash-%d-%d.jsonl" % (k, torn))
            data = b"".join(lines[: k + 1])
            if torn and k < len(answers):
                data += lines[k + 1][: len(lines[k + 1]) // 2]        # cut mid-record
            copy.write_bytes(data)
            s = Session.open(copy)
            assert s.torn is (torn and k < len(answers)) and len(s.records) == k
            st = protocols.replay(s)
            for a in answers[k:]:                                     # the participant goes on
                s.append({"answer": a})
                protocols.apply(protocol, st, a)
            assert _end(protocol, st) == end, (k, torn)
            assert [r["answer"] for r in Session.open(copy).answers()] == answers


def test_a_damaged_record_in_the_middle_is_an_error_not_skipped(tmp_path):
    s = Session.create(tmp_path, "staircase", "p02", {}, 1)
    for a in (True, False, True):
        s.append({"answer": a})
    lines = s.path.read_bytes().splitlines(keepends=True)
    lines[2] = b'{"broken\n'
    s.path.write_bytes(b"".join(lines))
    with pytest.raises(SessionError, match="line 3 is damaged"):
        Session.open(s.path)


def test_sessions_are_numbered_never_overwritten(tmp_path):
    a = Session.create(tmp_path, "search", "p03", {}, 1)
    b = Session.create(tmp_path, "search", "p03", {}, 1)
    assert a.path != b.path and a.path.name == "search-1.jsonl" and b.path.name == "search-2.jsonl"
    assert check_name("participant", "P-07_b") == "P-07_b"


def test_export_writes_tidy_csv_and_a_figure_per_session(tmp_path, capsys):
    import csv as _csv
    from texelpad import cli
    data = tmp_path / "data"
    sim = SimulatedParticipant(Point(0.3, 0.7), seed=1)
    # the mapping (seed 001): nine slider matches, then 25 ratings 0..10
    mapping = [{"pitch": 10.0 * k, "irregularity": 50.0} for k in range(9)] + \
        [k % 11 for k in range(25)]
    for proto, n in (("pursuit", 20), ("staircase", 12), ("search", 6), ("free", 9),
                     ("quant", 27), ("mapping", 34), ("evaluate", 22)):
        config = {"quant": GIVEN, "evaluate": EVALUATE}.get(proto, {})
        s = Session.create(data, proto, "p01", config, 5)
        st = protocols.start(proto, config, 5)
        for k in range(n):
            a = mapping[k] if proto == "mapping" else sim.answer(proto, st)
            protocols.apply(proto, st, a)
            s.append({"answer": a, "scene": {"regions": [
                {"start_mm": 0, "end_mm": 1, "texture": {"kind": "texel", "pitch_db": 1.0,
                                                         "irregularity_db": -3.0}}]}})
    out = tmp_path / "out"
    assert cli.main(["lab", "export", "--data", str(data), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "(130 answers) and 7 figures" in printed
    rows = list(_csv.DictReader(open(out / "sessions.csv")))
    assert len(rows) == 130 and {r["protocol"] for r in rows} == set(protocols.PROTOCOLS)
    assert rows[0]["played_pitch_db"] == "1.0"
    by = {}
    for r in rows:
        by.setdefault(r["protocol"], []).append(r)
    assert {r["confidence"] for r in by["free"]} == {"4"} and by["free"][0]["reference"]
    assert by["free"][0]["match_pitch_db"] == "-3.0"            # the target u = 0.3: -3 dB
    assert [r["quant_db"] for r in by["quant"]][:1] and all(r["similarity"] for r in by["quant"])
    assert {r["correct"] for r in by["staircase"]} <= {"True", "False"}
    assert by["search"][0]["chosen"] in ("0", "1", "2")
    # seed 003's Phase 2: 2 RT, 2 VTd, 2 VTp x 3 adjectives, then or first 4 similarity pairs
    ev = by["evaluate"]
    assert sum(1 for r in ev if r["adjective"]) == 18 and sum(1 for r in ev if r["similarity"]) == 4
    assert {r["source"] for r in ev if r["similarity"]} == {"data", "preference"}
    assert {r["source"] for r in by["quant"]} == {"own", "rater"}
    assert [r["pitch_slider"] for r in by["mapping"][:9]] == ["%.1f" % (10.0 * k)
                                                             for k in range(9)]
    assert [r["similarity"] for r in by["mapping"][9:]] == [str(k % 11) for k in range(25)]
    pngs = sorted(p.name for p in out.glob("*.png"))
    # one per session, and the papers' figures these sessions make (no matrix design: no 14c;
    # a staircase without a finger record: no Fig. 3; a search not stopped: no Table I)
    paper = ["seed000_fig10_matches.png", "seed000_fig11_guided.png", "seed000_fig12_plane.png",
             "seed000_fig13_confidence.png", "seed000_fig14ab_similarity.png",
             "seed000_fig15_quantization.png", "seed001_fig2_staircase.png",
             "seed001_fig4_mapping.png", "seed001_fig5_ratings.png"]
    assert len(pngs) == 16 and set(paper) < set(pngs) and ", ".join(sorted(paper)) in printed
    assert all((out / p).stat().st_size > 5000 for p in pngs)
