"""The free exploration and the quantization test (seed 000) as state machines,
the questions the lab asks (blind), answers checked before anything moves, and
the shipped study configs."""
from __future__ import annotations

import json

import pytest

from texel.gen.params import PITCH_DB_MAX
from texelpad.study import configs, protocols, questions
from texelpad.study.free import NINE, Free
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.space import Point

DISPLAY = {"positions": 19200, "dx_um": 5.3}
GIVEN = {"design": "levels", "matches": {r: {"pitch_db": 6.0, "irregularity_db": -12.0}
                                         for r in ("4sin", "pink", "sawtooth")}}


def test_free_exploration_runs_the_nine_in_a_seeded_recorded_order():
    a, b, c = Free(1), Free(1), Free(2)
    assert sorted(a.order) == sorted(NINE) and a.order == b.order and a.order != c.order
    sim = SimulatedParticipant(Point(0.4, 0.5))
    seen = []
    while not a.done:
        seen.append(a.reference)
        protocols.apply("free", a, sim.answer("free", a))
    assert seen == b.order and [m["reference"] for m in a.matches] == b.order
    assert a.matches[0] == {"pitch_db": 1.0, "irregularity_db": -10.0, "confidence": 4,
                            "trial": 0, "reference": b.order[0]}


def test_free_sliders_redraw_on_every_change_and_clamp_at_nyquist():
    st = Free(5)
    t0, t1 = st.texture(3.0, -10.0, 0), st.texture(3.0, -10.0, 1)
    assert t0["seed"] != t1["seed"] and t0 == st.texture(3.0, -10.0, 0)      # replayable
    assert st.texture(20.0, -10.0, 0)["pitch_db"] == PITCH_DB_MAX
    assert t0["texel_samples"] == 50 and t0["v"] == 2          # the lab's app's 50, format 2
    scene, kept = questions.slider_scene(st, {"config": {}}, DISPLAY, 3.00049, -10, 0)
    assert kept == (3.0, -10.0)
    assert scene["regions"][0]["texture"] == {"kind": "reference", "name": st.reference}
    for bad in ((20.5, -10), (3, -31), (float("nan"), 0), ("3", 0), (True, 0)):
        with pytest.raises(ValueError):
            st.check(*bad)


@pytest.mark.parametrize("answer, fragment", [
    ({"pitch_db": 3, "irregularity_db": -10}, "expected {pitch_db"),
    ({"pitch_db": 3, "irregularity_db": -10, "confidence": 6}, "confidence: expected a number 1 .. 5"),
    ({"pitch_db": 3, "irregularity_db": -10, "confidence": True}, "confidence"),
    ({"pitch_db": 30, "irregularity_db": -10, "confidence": 3}, "outside the slider"),
    ("3", "expected {pitch_db"),
])
def test_a_bad_free_answer_is_refused_and_changes_nothing(answer, fragment):
    st = Free(3)
    q = questions.ask("free", st, {"config": {}, "seed": 3}, DISPLAY)
    with pytest.raises(ValueError, match=fragment):
        questions.normalise("free", q, st, answer)
    assert st.trial == 0 and st.matches == []


def test_quantization_test_rates_every_reference_at_every_level_once():
    st = protocols.start("quant", GIVEN, 4)
    assert sorted(st.trials) == sorted((r, q) for r in ("4sin", "pink", "sawtooth")
                                       for q in (0.0, 1.0, 3.0, 5.0))
    seeds = {}
    while not st.done:
        tex = st.texture()
        ref, q = st.current
        assert tex["quant_db"] == q and tex["pitch_db"] == 6.0 and tex["v"] == 2
        assert seeds.setdefault(ref, tex["seed"]) == tex["seed"]   # only q differs
        st.answer(3)
    assert len(st.ratings) == 12
    with pytest.raises(ValueError, match="finished"):
        st.answer(3)


@pytest.mark.parametrize("config, fragment", [
    ({"design": "levels", "matches": {}}, "no match of"),
    ({"design": "levels", "matches": {"4sin": {"pitch_db": 6.0, "irregularity_db": -12.0}}},
     "no match of"),
    ({"design": "levels", "matches": {r: {"pitch_db": 6.0} for r in ("4sin", "pink", "sawtooth")}},
     "needs {pitch_db"),
    (dict(GIVEN, levels_db=[0, 0.0001]), "levels_db"),
    (dict(GIVEN, references=["4sin", "nope"]), "references"),
    ({"design": "levels", "matches": {r: {"pitch_db": 25.0, "irregularity_db": -12.0}
                                      for r in ("4sin", "pink", "sawtooth")}}, "pitch_db of"),
])
def test_a_bad_quantization_config_says_why(config, fragment):
    with pytest.raises((ValueError, TypeError), match=fragment):
        protocols.start("quant", config, 1)


def test_answers_are_compared_as_json_true_is_not_1():
    st = protocols.start("search", {}, 2)
    q = questions.ask("search", st, {"config": {}, "seed": 2}, DISPLAY)
    for bad in ({"choose": True}, {"choose": 1.0}, {"stop": 1}, {"choose": 3}, None):
        with pytest.raises(ValueError, match="expected one of"):
            questions.normalise("search", q, st, bad)
    assert questions.normalise("search", q, st, {"stop": True}) == {"stop": True}
    st2 = protocols.start("staircase", {}, 2)
    q2 = questions.ask("staircase", st2, {"config": {}, "seed": 2}, DISPLAY)
    with pytest.raises(ValueError):
        questions.normalise("staircase", q2, st2, True)
    assert questions.normalise("staircase", q2, st2, q2.odd) is True


def test_the_participants_questions_hold_no_parameter_values():
    header = {"config": {}, "seed": 1}
    for proto, config in (("pursuit", {}), ("search", {}), ("staircase", {}),
                          ("quant", GIVEN), ("free", {})):
        st = protocols.start(proto, config, 1)
        q = questions.ask(proto, st, dict(header, config=config), DISPLAY)
        # the options' labels are fixed words (pursuit: "reference", "A", "B")
        assert set(q.public["options"]) <= {"reference", "A", "B", "1", "2", "3", "rendering"}
        text = json.dumps(dict(q.public, options=None))
        if proto == "free":             # the sliders' ranges only, never a value shown
            text = json.dumps(dict(q.public, sliders=None, start=None))
        for word in ("pitch_db", "irregularity", "texel_samples", "length_mm", '"odd"',
                     "centre", "reference", "quant_db", "seed", "sigma", "mean"):
            assert word not in text, (proto, word)


def test_the_shipped_configs_all_load_and_a_broken_one_is_named(tmp_path):
    shipped = configs.available()
    assert {"free-nine", "pursuit-4sin", "staircase", "search-4sin"} <= set(shipped)
    assert not [n for n, c in shipped.items() if "error" in c]
    (tmp_path / "mine.json").write_text(json.dumps({"protocol": "staircase",
                                                    "config": {"start_mm": "long"}}))
    (tmp_path / "typo.json").write_text('{"protocol": "pursuit", "confg": {}}')
    mine = configs.available(tmp_path)
    assert "error" in mine["mine"] and "unknown key 'confg'" in mine["typo"]["error"]
    with pytest.raises(ValueError, match="config typo: unknown key"):
        configs.load("typo", tmp_path)
    with pytest.raises(ValueError, match="no 'nope'"):
        configs.load("nope")
