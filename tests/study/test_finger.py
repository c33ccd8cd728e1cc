"""study/finger.py: seed 001's swipe measures of the finger records, worked
out by hand on small records - the hard cases: the board clock's 2^30 wrap,
lifts, a record boundary, a resting finger, a trial without samples."""
from __future__ import annotations

import math

import pytest

from texelpad.study import finger as F
from texelpad.study import protocols
from texelpad.study.legacy import effective_header


def _rec(t_us, pos, q=0, dx_um=5.3, lost=0):
    return F.record(q, q, 0, [(t, p, 0) for t, p in zip(t_us, pos)], lost, 100, dx_um)


def test_the_clock_wrap_is_undone():
    t = [F.WRAP - 20000, F.WRAP - 10000, 0, 10000]
    assert F.unwrap(t) == [0.0, 0.01, 0.02, 0.03]


def test_velocities_skip_lifts_and_record_boundaries():
    # 10 positions (53 um) per 10 ms = 5.3 mm/s: resting; 1000 per 10 ms = 530 mm/s
    a = _rec([0, 10000, 20000, 30000, 40000], [100, 110, 1110, -1, 500])
    b = _rec([50000, 60000], [400, 300])       # another read: its first has no velocity
    v, n = F.velocities([a, b])
    assert n == 7
    assert v[0] == pytest.approx(5.3) and v[1] == pytest.approx(530.0)
    assert math.isnan(v[2]) and math.isnan(v[3])
    assert v[4] == pytest.approx(-53.0)
    m = F.measures([a, b])
    # swiping: 530 right, 53 left (5.3 rests); 7 samples, 6 touching (one lifted)
    assert (m["right"], m["left"], m["samples"], m["touching"]) == (1, 1, 7, 6)
    assert m["directional_proportion"] == 0.0
    assert m["speed_mm_s"] == pytest.approx((530.0 + 53.0) / 2)
    assert m["speed_sd_mm_s"] == pytest.approx(math.sqrt(2) * (530.0 - 53.0) / 2)
    assert F.measures([a], contact_only=True)["directional_proportion"] == pytest.approx(1 / 4)
    assert F.measures([a])["directional_proportion"] == pytest.approx(1 / 5)


def test_a_trial_without_samples_or_swipes_says_none():
    m = F.measures([])
    assert m["directional_proportion"] is None and m["speed_mm_s"] is None
    m = F.measures([_rec([0, 10000], [-1, -1], lost=3)])
    assert m["samples"] == 2 and m["speed_mm_s"] is None and m["lost"] == 3
    assert m["directional_proportion"] == 0.0
    s = F.subject([F.measures([])])
    assert s["directional_proportion"] is None and s["speed_sd_mm_s"] is None


def test_a_subjects_proportion_is_the_mean_of_the_trials_magnitudes():
    right = _rec([0, 10000, 20000], [0, 1000, 2000])        # 2 of 3 right: 2/3
    left = _rec([0, 10000, 20000], [2000, 1000, 0])         # -2/3
    s = F.subject([F.measures([right]), F.measures([left])])
    assert s["directional_proportion"] == pytest.approx(2 / 3)
    assert s["signed_directional_proportion"] == pytest.approx(0.0)
    assert s["speed_mm_s"] == pytest.approx(530.0)


def test_the_staircase_records_the_finger_by_default_and_older_sessions_did_not():
    st = protocols.start("staircase", {}, 1)
    assert st.config.finger_hz == F.FINGER_HZ and protocols.get("staircase").finger_hz(st) == 100
    assert protocols.get("pursuit").finger_hz(protocols.start("pursuit", {}, 1)) == 0
    assert protocols.get("staircase").finger_hz(protocols.start("staircase",
                                                                {"finger_hz": 0}, 1)) == 0
    for bad in (True, -1, 1001, 2.5, "100"):
        with pytest.raises(ValueError, match="finger_hz: expected"):
            protocols.start("staircase", {"finger_hz": bad}, 1)
    h = effective_header({"kind": "session", "format": "texelpad-session/3",
                          "protocol": "staircase", "config": {"condition": "wide"}})
    assert h["config"]["finger_hz"] == 0 and h["legacy"]
