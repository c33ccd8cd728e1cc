"""texel.runtime.duty.DutyLaw: amplitude (uint16) -> PWM compare counts.

The law: D(a) = asin(a * sin(pi*cap)) / pi, so the PWM fundamental
sin(pi*D) is a * sin(pi*cap) -- linear in the commanded amplitude. These
tests evaluate duty() for every one of the 65,536 amplitudes and measure:

- the fundamental error |sin(pi*c/(top+1)) - a*sin(pi*cap)| in units of one
  count's worth of fundamental (sin(pi/(top+1)), the most one count can
  change it): must stay below 1 (it is ~0.51 for the boards' TOPs, i.e. the
  integer rounding itself);
- the duty error |c - D(a)*(top+1)| in counts: <= 1 except in the last few
  tenths of a percent of amplitude, where the fundamental is flat at the 50 %
  cap and D(a) has infinite slope;
- the table, bit for bit, on CPython and under the MicroPython unix port
  (both binary64), and duty() allocation-free under heap_lock.
"""
from __future__ import annotations

import math
import random

import numpy as np
import pytest

from support import mpy
from texel.runtime.duty import DutyLaw

# TOP of the boards at 34 kHz: RP2040 125 MHz (3675), STM32F405 TIM1/8 168 MHz
# (4940), RP2350 150 MHz (4411), a TOP of 3676 (an odd one out)
BOARD_TOPS = (3675, 4940, 4411, 3676)


def all_duties(law: DutyLaw) -> np.ndarray:
    return np.array([law.duty(a) for a in range(65536)], dtype=np.int64)


def errors(law: DutyLaw, c: np.ndarray):
    n = law.top + 1
    a = np.arange(65536) / 65535.0
    s = math.sin(math.pi * law.duty_cap)
    fund = np.abs(np.sin(np.pi * c / n) - a * s) / math.sin(math.pi / n)
    exact = np.arcsin(np.minimum(1.0, a * s)) / np.pi * n
    return fund, np.abs(c - exact), a


@pytest.mark.parametrize("top", BOARD_TOPS)
@pytest.mark.parametrize("cap", (0.5, 0.45))
def test_fundamental_linear_within_one_count_on_the_boards(top, cap):
    law = DutyLaw(top, cap)
    c = all_duties(law)
    fund, duty_err, a = errors(law, c)
    # the fundamental is as linear as integer counts allow (rounding alone
    # gives 0.5); the table + interpolation add only a few hundredths
    assert fund.max() < 0.56, fund.max()
    # the duty itself is within 1 count of the exact law below a = 0.99
    assert duty_err[a <= 0.99].max() <= 1.0
    # ends, bound and monotonicity
    assert c[0] == 0 and c[-1] == law.max_counts == int(cap * (top + 1))
    assert c.max() == law.max_counts
    assert np.all(np.diff(c) >= 0)


def test_fundamental_within_one_count_over_tops_and_caps():
    rng = random.Random(20240611)
    cases = [(rng.randint(1, 9999), rng.uniform(0.01, 0.5)) for _ in range(40)]
    cases += [(rng.randint(1, 9999), 0.5) for _ in range(20)]
    worst = 0.0
    for top, cap in cases:
        law = DutyLaw(top, cap)
        c = all_duties(law)
        fund, _, _ = errors(law, c)
        assert c[-1] == law.max_counts and c.max() <= cap * (top + 1)
        assert np.all(np.diff(c) >= 0), (top, cap)
        worst = max(worst, fund.max())
    assert worst < 1.0, worst


def test_table_layout():
    law = DutyLaw(3675)
    assert law.top == 3675 and law.period == 3676 and law.max_counts == 1838
    assert len(law.lut) == 1025 and law.lut.typecode == "H"
    lut = np.array(law.lut)
    assert lut[0] == 0 and lut[1024] == 1838
    assert np.all(np.diff(lut) >= 0)
    # lut[i] is the duty at amp16 = 64*i, and round(D*(top+1)) of that amplitude
    for i in range(1024):
        assert law.duty(64 * i) == lut[i]
    s = math.sin(math.pi * 0.5)
    exact = np.array([math.asin(64 * i / 65535 * s) / math.pi * 3676 for i in range(1024)])
    assert np.all(np.abs(lut[:1024] - exact) <= 0.5 + 2.0 ** -law.q)
    assert law.q == 5          # 1838 * 32 fits uint16 with headroom


def test_known_values():
    law = DutyLaw(3675)
    # small amplitudes: D ~ a/pi, so counts ~ a * 3676 / pi
    assert law.duty(0) == 0
    assert law.duty(65535) == 1838
    assert law.duty(32768) == round(math.asin(32768 / 65535) / math.pi * 3676)   # 613
    assert law.duty(32768) == 613
    assert law.duty(1000) == round(math.asin(1000 / 65535) / math.pi * 3676)


def test_out_of_range_amplitudes_clamp():
    law = DutyLaw(3675)
    assert law.duty(-1) == law.duty(-70000) == 0
    assert law.duty(65536) == law.duty(1 << 20) == law.duty(65535)


@pytest.mark.parametrize("bad", (0, -1, 65536, 3675.0, "3675", None))
def test_rejects_bad_top(bad):
    with pytest.raises(ValueError, match="top"):
        DutyLaw(bad)


@pytest.mark.parametrize("bad", (0, -0.1, 0.51, 1.0))
def test_rejects_bad_cap(bad):
    with pytest.raises(ValueError, match="duty_cap"):
        DutyLaw(3675, bad)


def test_amplitude_of_inverts_the_law():
    law = DutyLaw(3675)
    one_count = 65535 * math.sin(math.pi / 3676)   # amplitude of one count at most
    for a in list(range(0, 65536, 97)) + [65535]:
        back = law.amplitude_of(law.duty(a))
        assert abs(back - a) <= one_count, (a, back)
    assert law.amplitude_of(0) == 0
    assert law.amplitude_of(1838) == 65535
    assert law.amplitude_of(-3) == 0
    # capped law: the (floored) cap count is amplitude 1, less under one count's worth
    law45 = DutyLaw(3675, 0.45)
    assert 65535 - one_count < law45.amplitude_of(law45.max_counts) < 65535


def test_counts_never_exceed_the_cap_for_odd_periods():
    # 0.5 * 4941 = 2470.5: the cap is floored to 2470
    law = DutyLaw(4940)
    assert law.max_counts == 2470
    assert law.duty(65535) == 2470 and max(law.lut) == 2470


# ---------------------------------------------------------------- MicroPython

MP_TABLE = """
import json
from texel.runtime.duty import DutyLaw
out = []
for top, cap in %s:
    law = DutyLaw(top, cap)
    out.append({"lut": list(law.lut), "fine": list(law._fine), "q": law.q,
                "max": law.max_counts,
                "duty": [law.duty(a) for a in range(0, 65536, 61)] + [law.duty(65535)],
                "amp": [law.amplitude_of(c) for c in range(0, law.max_counts + 1, 37)]})
print(json.dumps(out))
"""

CASES = [(3675, 0.5), (4940, 0.5), (3676, 0.45), (1000, 0.3), (255, 0.5)]


def test_table_identical_on_micropython():
    got = mpy.run_json(MP_TABLE % (CASES,))
    for (top, cap), g in zip(CASES, got):
        law = DutyLaw(top, cap)
        assert g["lut"] == list(law.lut), (top, cap)
        assert g["fine"] == list(law._fine), (top, cap)
        assert g["q"] == law.q and g["max"] == law.max_counts
        assert g["duty"] == [law.duty(a) for a in range(0, 65536, 61)] + [law.duty(65535)]
        assert g["amp"] == [law.amplitude_of(c) for c in range(0, law.max_counts + 1, 37)]


MP_HEAP = """
import json, micropython, time
from texel.runtime.duty import DutyLaw
law = DutyLaw(3675)
duty = law.duty

def sweep(law):
    s = 0
    for a in range(0, 65536, 3):
        s += law.duty(a)          # method-call syntax: no bound-method object
    s += law.duty(-5) + law.duty(70000) + law.duty(65535)
    return s

def control():
    return [1, 2, 3]

def timed(duty, n):
    t = time.ticks_us()
    for a in range(n):
        duty(a)
    return time.ticks_diff(time.ticks_us(), t)

def locked(law, res):
    # everything between lock and unlock stays in this function: module-level
    # stores would grow the globals dict (an allocation of the test's own)
    micropython.heap_lock()
    try:
        res[0] = sweep(law)
        res[1] = 1
    except MemoryError:
        res[1] = 0
    try:
        control()
    except MemoryError:
        res[2] = 1
    micropython.heap_unlock()

res = [0, 0, 0]
locked(law, res)
us = timed(duty, 65536)
print(json.dumps({"ok": res[1] == 1, "sum": res[0], "control_raised": res[2] == 1,
                  "us_per_duty": us / 65536}))
"""


def test_duty_allocation_free_under_heap_lock():
    r = mpy.run_json(MP_HEAP)
    assert r["control_raised"], "heap_lock did not lock (the control allocation succeeded)"
    assert r["ok"], "DutyLaw.duty allocated under heap_lock"
    law = DutyLaw(3675)
    assert r["sum"] == sum(law.duty(a) for a in range(0, 65536, 3)) + law.duty(65535) \
        + law.duty(65535)
    assert 0 < r["us_per_duty"] < 20, r["us_per_duty"]
    print("MicroPython unix port: %.3f us per DutyLaw.duty" % r["us_per_duty"])


def test_float32_board_table_within_one_count():
    """The boards build the table in float32 (rp2/stm32 MicroPython). Emulate
    the construction with numpy float32 and compare with the binary64 table:
    at most one fine unit (1/2^q count) apart, so duties agree within 1 count."""
    law = DutyLaw(3675)
    f32 = np.float32
    s = f32(math.sin(f32(math.pi) * f32(0.5)))
    i = np.arange(1024)
    x = (i * 64).astype(f32) / f32(65535.0) * s
    x = np.minimum(x, f32(1.0))
    scale = f32(3676 * (1 << law.q)) / f32(math.pi)
    v = np.floor(np.arcsin(x).astype(f32) * scale + f32(0.5)).astype(np.int64)
    v = np.minimum(v, law.max_counts << law.q)
    fine = np.array(law._fine[:1024], dtype=np.int64)
    assert np.abs(v - fine).max() <= 2
    assert np.abs(((v + law._half) >> law.q) - np.array(law.lut[:1024])).max() <= 1
