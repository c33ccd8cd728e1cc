"""`texelpad lab describe` (texelpad.study.describe): a study's trial list
before anyone runs it. Checked against the protocols themselves: the fixed
designs trial by trial, the adaptive ones' seeds against what questions.ask
plays in a run driven by answers (issue 20 item 4)."""
from __future__ import annotations

import json
from collections import Counter

import pytest

from texelpad import cli
from texelpad.study import configs as C
from texelpad.study import protocols
from texelpad.study import questions as Q
from texelpad.study.describe import TPAD_DISPLAY, describe, header_config, parse_display, \
    render_text
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.quant import NINE
from texelpad.study.session import SessionError
from texelpad.study.space import Point

SHIPPED = sorted(C.available())


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_config_describes(name):
    d = describe(name, seed=3)
    text = json.dumps(d)
    assert '"u16"' not in text and len(text) < 60000     # sample arrays are named, not listed
    assert d["protocol"] == C.load(name)["protocol"] and d["trials"]
    assert d["config"]["config_file"] == name and d["config"]["texture_format"] == 2
    assert [t["question"] for t in d["trials"]] == list(range(1, len(d["trials"]) + 1))
    table = render_text(d)
    assert table.startswith(name) and "question 1" in table


def _right(t):
    return t["options"][0]["regions"][1]["texture"]


def test_quant_paper_lists_the_27_trials():
    d = describe("quant-paper", seed=5)
    assert d["trial_count"] == 27 and len(d["trials"]) == 27
    kinds = Counter((t["source"], t["quant_db"]) for t in d["trials"])
    assert kinds == {("own", 0.0): 9, ("rater", 0.0): 9, ("rater", 1.0): 3,
                     ("rater", 3.0): 3, ("rater", 5.0): 3}
    assert sorted(t["reference"] for t in d["trials"] if t["source"] == "own") == sorted(NINE)
    quantized = sorted((t["reference"], t["quant_db"]) for t in d["trials"] if t["quant_db"])
    assert quantized == sorted((e, q) for e in ("4sin", "pink", "sawtooth")
                               for q in (1.0, 3.0, 5.0))
    for t in d["trials"]:
        left, right = (r["texture"] for r in t["options"][0]["regions"])
        assert left == {"kind": "reference", "name": t["reference"]}
        assert t["options"][0]["regions"][0]["where"] == "left half"
        if t["source"] == "own":        # no matches in the config: the participant's own
            assert right["what"] == ("the participant's own match of %s (from their free "
                                     "exploration)" % t["reference"])
        else:
            assert right["kind"] == "samples" and right["values"] == 9600
            assert right["what"].startswith("the rater's logged sequence of %s quantized at "
                                            "%g dB" % (t["reference"], t["quant_db"]))
    # the order is the protocol's for that seed
    st = protocols.start("quant", {}, 5)
    assert [(t["reference"], t["source"], t["quant_db"]) for t in d["trials"]] == \
        [(p["reference"], p["source"], p["quant_db"]) for p in st.plan]


def test_quant_with_matches_lists_the_textures_that_play():
    """quant-exemplars gives its matches: each trial's rendering is the one
    questions.ask plays (12 trials = 3 exemplars x q 0, 1, 3, 5)."""
    d = describe("quant-exemplars", seed=2)
    cf = C.load("quant-exemplars")
    hc = header_config("quant-exemplars", cf)
    header = {"protocol": "quant", "config": hc, "seed": 2}
    st = protocols.start("quant", hc, 2)
    assert d["trial_count"] == 12
    for t in d["trials"]:
        q = Q.ask("quant", st, header, TPAD_DISPLAY)
        assert _right(t) == q.options[0]["regions"][1]["texture"]
        protocols.apply("quant", st, 3)
    assert describe("similarity-matrix")["trial_count"] == 9


def test_mapping_lists_9_matches_then_25_ratings():
    d = describe("mapping", seed=4)
    phases = [t["phase"] for t in d["trials"]]
    assert phases == ["match"] * 9 + ["rate"] * 25 and d["trial_count"] == 34
    st = protocols.start("mapping", {}, 4)
    assert [t["reference"] for t in d["trials"][:9]] == st.order
    assert [(t["reference"], t["match_of"]) for t in d["trials"][9:]] == \
        [tuple(p) for p in st.pairs]
    first = d["trials"][0]["options"][0]["regions"]
    assert first[0]["texture"]["what"] == "band-pass reference %s seed 0" % st.order[0]
    assert first[1]["texture"]["texel_samples"] == 189
    assert first[1]["texture"]["seed"] == st.texture(50, 50, 0)["seed"]
    for t in d["trials"][9:]:
        assert _right(t)["seed"] == st.rating_seeds[t["match_of"]]


def test_free_lists_the_nine_in_the_seeds_order_with_the_sliders_start():
    d = describe("free-nine", seed=8)
    st = protocols.start("free", C.load("free-nine")["config"], 8)
    assert [t["reference"] for t in d["trials"]] == st.order
    right = _right(d["trials"][0])
    assert (right["pitch_db"], right["irregularity_db"], right["texel_samples"]) == \
        (5.0, -3.01, 50)


def test_pursuit_seeds_order_and_sides_are_what_a_run_plays():
    """A run driven by a simulated participant's answers: every comparison's
    direction, sides and texture seeds are the described ones; the first
    trial's points exactly."""
    seed = 12
    d = describe("pursuit-pink", seed=seed)
    hc = header_config("pursuit-pink", C.load("pursuit-pink"))
    header = {"protocol": "pursuit", "config": hc, "seed": seed}
    st = protocols.start("pursuit", hc, seed)
    sim = SimulatedParticipant(Point(0.3, 0.7), feel="plane")
    played = []
    while not st.done:
        q = Q.ask("pursuit", st, header, TPAD_DISPLAY)
        seeds = [sc["regions"][0]["texture"]["seed"] for sc in q.options[1:]]
        played.append((q.detail["direction"], q.detail["A_is_plus"], seeds, q.options))
        a = sim.answer("pursuit", st)
        protocols.apply("pursuit", st, a)
    assert len(played) == len(d["trials"]) == 20 and len(st.history) == 5
    assert st.centre != Point(0.5, 0.5)         # the answers moved it
    for t, (direction, a_plus, seeds, options) in zip(d["trials"], played):
        assert (t["direction"], t["A"].startswith("+"), t["seeds"]) == (direction, a_plus, seeds)
        opt = {o["option"]: o for o in t["options"]}
        if t["trial"] == 0:             # exact: the scenes played
            assert [o["regions"][0]["texture"] for o in t["options"]] == \
                [sc["regions"][0]["texture"] for sc in options]
        else:                           # the points depend on the answers, the seeds do not
            assert (opt["A"]["seed"], opt["B"]["seed"]) == tuple(seeds)


def test_staircase_first_trial_at_26_mm_and_its_seeds_are_what_a_run_plays():
    seed = 21
    d = describe("staircase-wide", seed=seed)
    first = d["trials"][0]
    assert first["length_mm"] == 26.0 and first["texel_samples"] == 4906
    tex = first["options"][0]["regions"][0]["texture"]
    assert tex["texel_samples"] == 4906 and tex["phase"] == "reset" and tex["min_cpmm"] == 1.0
    # 3 whole texels of 4906 samples = 78.0054 mm; the rest at level 0
    assert first["options"][0]["regions"][0]["end_mm"] == pytest.approx(78.0054)
    assert first["options"][0]["regions"][1]["texture"] == {"kind": "constant", "level": 0.0}
    hc = header_config("staircase-wide", C.load("staircase-wide"))
    header = {"protocol": "staircase", "config": hc, "seed": seed}
    st = protocols.start("staircase", hc, seed)
    sim = SimulatedParticipant(Point(0.5, 0.5), seed=1, threshold_mm=15.0, slope_mm=2.0)
    n = 0
    while not st.done and n < len(d["trials"]):
        q = Q.ask("staircase", st, header, TPAD_DISPLAY)
        t = d["trials"][n]
        assert [sc["regions"][0]["texture"]["seed"] for sc in q.options] == t["seeds"]
        assert q.odd + 1 == t["odd"]
        protocols.apply("staircase", st, sim.odd_one_out(st.length_mm))
        n += 1
    assert n > 5 and any(e["length_mm"] != 26.0 for e in st.track)


def test_search_lists_its_first_question_exactly():
    d = describe("search-4sin", seed=6)
    hc = header_config("search-4sin", C.load("search-4sin"))
    st = protocols.start("search", hc, 6)
    q = Q.ask("search", st, {"protocol": "search", "config": hc, "seed": 6}, TPAD_DISPLAY)
    assert [[r["texture"] for r in o["regions"]] for o in d["trials"][0]["options"]] == \
        [[r["texture"] for r in sc["regions"]] for sc in q.options]
    assert d["design"] == "adaptive" and d["trial_count"] is None


def test_seed_defaults_to_the_configs_or_says_it_is_drawn(tmp_path):
    d = describe("staircase")
    assert d["seed"] == 0 and "drawn" in d["seed_source"]
    f = tmp_path / "mine.json"
    f.write_text(json.dumps({"protocol": "free", "seed": 77, "config": {}}))
    d = describe(str(f))
    assert (d["seed"], d["seed_source"], d["config_name"]) == (77, "the config's", "mine")
    assert d["config"]["references"] == list(NINE)       # the Config's defaults filled in


@pytest.mark.parametrize("bad, match", [
    ("no-such-config", "no 'no-such-config'"),
    ("missing.json", "no such file"),
])
def test_an_unknown_config_is_a_clear_error(bad, match):
    with pytest.raises(SessionError, match=match):
        describe(bad)


def test_a_bad_file_is_a_clear_error(tmp_path):
    f = tmp_path / "broken.json"
    f.write_text("{not json")
    with pytest.raises(SessionError, match="not a JSON config"):
        describe(str(f))
    f.write_text(json.dumps({"protocol": "staircase", "config": {"condition": "medium"}}))
    with pytest.raises(SessionError, match="condition"):
        describe(str(f))


def test_parse_display():
    assert parse_display("19200,5.3") == TPAD_DISPLAY
    assert parse_display("1000") == {"positions": 1000, "dx_um": 5.3}
    for bad in ("0", "x", "10,0", "1,2,3", "10,2000"):
        with pytest.raises(ValueError, match="display"):
            parse_display(bad)


def test_the_cli_prints_a_table_and_json(capsys):
    assert cli.main(["lab", "describe", "quant-paper", "--seed", "5"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("quant-paper (quant)") and "question 27 of 27" in out
    assert cli.main(["lab", "describe", "mapping", "--json", "--display", "19200,5.3"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["protocol"] == "mapping" and len(d["trials"]) == 34 and d["seed"] == 0


@pytest.mark.parametrize("argv, flag", [
    (["lab", "describe", "nope"], "CONFIG: config: no 'nope'"),
    (["lab", "describe"], "CONFIG: lab describe needs a config"),
    (["lab", "describe", "staircase", "--display", "0"], "--display"),
    (["lab", "describe", "staircase", "--seed", "-1"], "--seed"),
    (["lab", "export", "staircase"], "CONFIG: only describe"),
    (["lab", "export", "--json"], "--json: only lab describe"),
])
def test_the_cli_errors_are_one_line(argv, flag, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert flag in err and "Traceback" not in err
