"""Boards as data (boards/*.json, texel.runtime.boards): every shipped board loads and
validates on CPython and under the MicroPython unix port with the same
canonical result; bad files are rejected with the same clear message (file and
key path) on both; the PWM arithmetic puts every board's carrier, and any
carrier from 20 to 60 kHz, within 0.1 % of the set frequency."""
from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest
from hypothesis import given, settings, strategies as st

from support import mpy
from texel.runtime import boards

ROOT = Path(__file__).resolve().parents[2]
BOARDS_DIR = ROOT / "device" / "texel" / "boards.d"
REQUIRED = {"pico", "pico_bridge", "pyboard", "pico_cpy", "virtual"}
SHIPPED = sorted(p.stem for p in BOARDS_DIR.glob("*.json"))


def _raw(name: str) -> dict:
    return json.loads((BOARDS_DIR / f"{name}.json").read_text())


def _err(d, source: str = "boards/x.json") -> str:
    with pytest.raises(ValueError) as ei:
        boards.validate(d, source)
    return str(ei.value)


# --- the shipped boards -------------------------------------------------------

def test_required_boards_are_shipped_and_listed():
    assert REQUIRED <= set(SHIPPED)
    assert boards.names() == SHIPPED                    # default search path finds the repo's
    assert boards.names([str(BOARDS_DIR)]) == SHIPPED
    # the default search path, in the documented order
    sp = boards.search_path()
    assert sp[:2] == ["/boards", "boards"]
    assert Path(sp[2]).resolve() == BOARDS_DIR


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_board_is_canonical(name):
    raw = _raw(name)
    b = boards.load(name)
    # every key is written out in the file: the file is its own canonical form
    assert b == raw
    assert boards.validate(b, f"{name}.json") == b      # idempotent
    assert b["name"] == name
    c = b["carrier"]
    assert c["freq_hz"] == 34000 and c["duty_cap"] == 0.5
    assert b["display"] == {"positions": 19200, "dx_um": 5.3}
    assert b["title"] and len(b["wiring"]) > 100


def test_shipped_board_facts():
    pico, bridge, pyb, cpy, virt = (boards.load(n) for n in
                                    ("pico", "pico_bridge", "pyboard", "pico_cpy", "virtual"))
    assert (pico["port"], pico["cpu_hz"], pico["carrier"]["drive"]) == ("rp2", 125_000_000, "single")
    assert pico["carrier"]["pins"] == [16] and pico["carrier"]["pwm"] == {"slice": 0}
    assert pico["sensor"]["pins"] == [26] and pico["refresh"] == {"hz": 8333, "mode": "timer_irq"}
    assert bridge["carrier"]["drive"] == "bridge" and bridge["carrier"]["pins"] == [16, 17]
    assert pyb["port"] == "stm32" and pyb["cpu_hz"] == 168_000_000
    assert pyb["carrier"]["pwm"]["timer"] in (1, 8) and pyb["carrier"]["drive"] == "bridge"
    assert pyb["sensor"]["pins"] == ["X19"]
    assert cpy["port"] == "circuitpython" and cpy["refresh"]["mode"] == "loop"
    assert cpy["refresh"]["hz"] < pico["refresh"]["hz"]          # reduced-rate profile
    assert virt["port"] == "virtual" and virt["refresh"]["mode"] == "stepped"
    # the arithmetic the wiring notes state
    assert boards.board_top(pico) == 3675                         # 3,676 counts
    assert boards.board_top(bridge) == boards.board_top(virt) == 3675
    # CircuitPython 10's pwmio floors: TOP = 125 MHz // 34 kHz - 1 = 3675 (3,676 clocks)
    assert boards.board_top(cpy) == 3675
    assert boards.board_top(pyb) == 4940                          # 4,941 counts
    assert "4,941 counts" in pyb["wiring"] and "3,676 counts" in pico["wiring"]
    assert "= 3675 itself (3,676 clocks per period, actual carrier 34,004.35 Hz" in cpy["wiring"]
    # the stm32 backend's optional keys, written out
    assert pyb["carrier"]["deadtime_ns"] == 200 and pyb["refresh"]["timer"] == 7
    assert "deadtime_ns" not in pico["carrier"] and "timer" not in pico["refresh"]


@pytest.mark.parametrize("name", SHIPPED)
def test_carrier_within_0_1_percent(name):
    b = boards.load(name)
    top = boards.board_top(b)
    f = boards.actual_hz(b["cpu_hz"], top)
    err = f / b["carrier"]["freq_hz"] - 1
    assert abs(err) <= 0.001, (name, top, f, err)
    if b["port"] == "circuitpython":
        assert top == b["cpu_hz"] // b["carrier"]["freq_hz"] - 1  # pwmio's own rule
    else:
        # nearest count: no other TOP is closer
        for t in (top - 1, top + 1):
            assert abs(b["cpu_hz"] / (t + 1) - b["carrier"]["freq_hz"]) \
                >= abs(f - b["carrier"]["freq_hz"])


def test_exact_carrier_figures():
    assert boards.pwm_top(125_000_000, 34_000) == 3675
    assert boards.actual_hz(125_000_000, 3675) == pytest.approx(34004.3526, abs=1e-4)
    assert boards.pwm_top(168_000_000, 34_000) == 4940
    assert boards.actual_hz(168_000_000, 4940) == pytest.approx(34001.2143, abs=1e-4)
    assert boards.actual_hz(125_000_000, 3676) == pytest.approx(33995.1047, abs=1e-4)


@pytest.mark.parametrize("port,cpu_hz", [("rp2", 125_000_000), ("stm32", 168_000_000),
                                         ("circuitpython", 125_000_000)])
def test_sweep_20_to_60_khz_within_0_1_percent(port, cpu_hz):
    """Every carrier from 20 to 60 kHz, as each port's PWM programs it."""
    board = _raw({"rp2": "pico", "stm32": "pyboard", "circuitpython": "pico_cpy"}[port])
    worst = 0.0
    for f in range(20_000, 60_001, 7):          # every 7 Hz: ~5,700 frequencies
        board["carrier"]["freq_hz"] = f
        top = boards.board_top(board)
        if port != "circuitpython":
            assert top == boards.pwm_top(cpu_hz, f)
        worst = max(worst, abs(boards.actual_hz(cpu_hz, top) / f - 1))
    # half a count (nearest) or one count (floored) at the shortest period
    counts = cpu_hz / 60_000
    assert worst <= (1.0 if port == "circuitpython" else 0.5) / (counts - 1)
    assert worst < 0.001


@settings(max_examples=400, deadline=None)
@given(name=st.sampled_from(["pico", "pico_cpy", "pyboard"]),
       cpu_hz=st.integers(boards.CPU_HZ_MIN, boards.CPU_HZ_MAX),
       freq=st.integers(boards.FREQ_MIN_HZ, boards.FREQ_MAX_HZ))
def test_validator_accepts_only_carriers_within_0_1_percent(name, cpu_hz, freq):
    """Whatever clock and carrier a board file states, a board that
    validates runs within 0.1 % of its carrier (nearest or floored TOP)."""
    d = _raw(name)
    d["cpu_hz"] = cpu_hz
    d["carrier"]["freq_hz"] = freq
    d["refresh"]["hz"] = 50
    d["carrier"].pop("deadtime_ns", None)        # its tick limit depends on the clock
    try:
        b = boards.validate(d, f"{name}.json")
    except ValueError as e:
        assert f"{name}.json: carrier.freq_hz: " in str(e) and "gives PWM TOP" in str(e)
        top = cpu_hz // freq - 1 if name == "pico_cpy" else (cpu_hz + freq // 2) // freq - 1
        least = 1000 if name == "pico_cpy" else 500
        assert top + 1 < least or top > boards.TOP_MAX
        return
    top = boards.board_top(b)
    assert boards.COUNTS_MIN - 1 <= top <= boards.TOP_MAX == 16382
    assert abs(boards.actual_hz(cpu_hz, top) / freq - 1) <= 0.001


def test_pwm_top_errors():
    for args in [(0, 34000), (125_000_000, 0), (125_000_000, -5), (125_000_000, 34000.0),
                 (125e6, 34000), (True, 34000)]:
        with pytest.raises(ValueError):
            boards.pwm_top(*args)
    with pytest.raises(ValueError, match="125000 PWM counts"):
        boards.pwm_top(125_000_000, 1000)          # needs a prescaler: refused
    assert boards.pwm_top(125_000_000, 1_908) == 65513          # 65,513.6 -> 65,514 counts
    with pytest.raises(ValueError, match="65548 PWM counts"):
        boards.pwm_top(125_000_000, 1_907)                          # one Hz lower: too many
    assert boards.pwm_top(125_000_000, 62_500_000) == 1            # 2 counts: the minimum
    with pytest.raises(ValueError, match="1 PWM counts"):
        boards.pwm_top(125_000_000, 100_000_000)


def test_virtual_backend_agrees_on_top():
    """The virtual backend computes the same TOP as boards.board_top."""
    hw_virtual = pytest.importorskip("texel.hw.virtual")
    b = boards.load("virtual")
    assert hw_virtual.VirtualHw(b, record=4).top == boards.board_top(b) == 3675


# --- defaults and canonical form -----------------------------------------------

MINIMAL = {
    "name": "mini", "port": "rp2", "cpu_hz": 125_000_000,
    "carrier": {"drive": "single", "pins": [5]},
    "sensor": {"kind": "adc_ratio", "pins": [27, 28]},
}


def test_defaults_filled_in():
    src = copy.deepcopy(MINIMAL)
    b = boards.validate(src, "boards/mini.json")
    assert src == MINIMAL                                # input untouched
    assert b["title"] == "mini" and b["wiring"] == ""
    assert b["carrier"] == {"freq_hz": 34000, "duty_cap": 0.5, "drive": "single", "pins": [5],
                            "pwm": {"slice": 2}, "idle_amplitude": 0}   # GPIO 5: slice 2 (B)
    assert b["sensor"] == {"kind": "adc_ratio", "pins": [27, 28], "raw_at_start": 2000,
                           "raw_at_end": 63000, "lift_below": 1000, "filter_shift": 2,
                           "latency_us": 150, "velocity_shift": 4, "lift_debounce": 3}
    assert b["refresh"] == {"hz": 8333, "mode": "timer_irq"}
    assert b["display"] == {"positions": 19200, "dx_um": 5.3}
    for port, mode, pins, spins, pwm in [("circuitpython", "loop", ["GP0"], ["A0"], {}),
                                         ("virtual", "stepped", [0], [1], {}),
                                         ("stm32", "timer_irq", ["Y6"], ["X19"],
                                          {"timer": 1, "channel": 4})]:
        d = {"name": "m", "port": port, "cpu_hz": 84_000_000,
             "carrier": {"drive": "single", "pins": pins, "pwm": pwm},
             "sensor": {"kind": "adc_linear", "pins": spins}}
        b = boards.validate(d, "m.json")
        # optional keys stay out; a millisecond-paced loop defaults to its most
        hz = 1000 if port == "circuitpython" else 8333
        assert b["refresh"] == {"hz": hz, "mode": mode}
        assert b["carrier"]["pwm"] == pwm and "deadtime_ns" not in b["carrier"]


def test_a_millisecond_paced_loop_is_asked_no_more_than_it_can_pace():
    d = _raw("pico_cpy")
    d["refresh"]["hz"] = 1001
    with pytest.raises(ValueError, match=r"refresh.hz: 1001 Hz: a paced loop on port "
                                         r"'circuitpython' refreshes at most 1000 times"):
        boards.validate(d, "pico_cpy.json")
    d = _raw("pico")                    # a loop paced in microseconds: no such bound
    d["refresh"] = {"hz": 5000, "mode": "loop"}
    assert boards.validate(d, "pico.json")["refresh"]["hz"] == 5000


def test_accepted_variants():
    # a bridge may put leg A on channel B (hw_rp2 supports either order)
    d = _raw("pico_bridge")
    d["carrier"]["pins"] = [17, 16]
    assert boards.validate(d, "pico_bridge.json")["carrier"]["pins"] == [17, 16]
    # the stm32 optional keys at their limits; a single-drive stm32 board on TIM1 CH4
    d = _raw("pyboard")
    d["carrier"]["deadtime_ns"] = 6000                  # 1008 ticks at 168 MHz
    d["refresh"]["timer"] = 14
    b = boards.validate(d, "pyboard.json")
    assert b["carrier"]["deadtime_ns"] == 6000 and b["refresh"]["timer"] == 14
    del d["carrier"]["deadtime_ns"], d["refresh"]["timer"]
    b = boards.validate(d, "pyboard.json")
    assert "deadtime_ns" not in b["carrier"] and "timer" not in b["refresh"]


def test_first_directory_wins_and_names_merge(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    for d, freq in ((a, 30000), (b, 40000)):
        doc = _raw("pico")
        doc["carrier"]["freq_hz"] = freq
        (d / "pico.json").write_text(json.dumps(doc))
    v = _raw("virtual")
    (b / "virtual.json").write_text(json.dumps(v))
    (b / "notes.txt").write_text("not a board")
    (b / "Bad Name.json").write_text("{}")               # not a valid board name: not listed
    assert boards.load("pico", search=[str(a), str(b)])["carrier"]["freq_hz"] == 30000
    assert boards.load("pico", search=[str(b), str(a)])["carrier"]["freq_hz"] == 40000
    assert boards.load("virtual", search=[str(a), str(b)]) == v
    assert boards.names([str(a), str(b), str(tmp_path / "missing")]) == ["pico", "virtual"]
    assert boards.names(str(a)) == ["pico"]              # one directory as a string


def test_not_found_and_bad_names(tmp_path):
    with pytest.raises(ValueError) as ei:
        boards.load("nope", search=[str(tmp_path), str(BOARDS_DIR)])
    msg = str(ei.value)
    assert "board 'nope': no nope.json in " in msg and str(tmp_path) in msg
    assert "pico, pico_bridge" in msg                    # names the boards there are
    for bad in ["../boards/pico", "pico.json", "", "Pico", "a" * 33, None, 3]:
        with pytest.raises(ValueError, match="board name"):
            boards.load(bad, search=[str(BOARDS_DIR)])


# --- bad files ------------------------------------------------------------------

def _mut(base: str, fn):
    d = _raw(base)
    fn(d)
    return d


def _set(path: str, value):
    def fn(d):
        keys = path.split(".")
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value
    return fn


def _del(path: str):
    def fn(d):
        keys = path.split(".")
        for k in keys[:-1]:
            d = d[k]
        del d[keys[-1]]
    return fn


# (base board, mutation, expected "<key path>: <message>" after the file name)
BAD = [
    ("pico", _set("colour", "red"),
     "colour: unknown key (known: name, port, title, cpu_hz, carrier, sensor, refresh, display, wiring, button, led)"),
    # two unknown keys: the alphabetically first is named, whatever the dict order
    ("pico", lambda d: d.update({"zeta": 1, "alpha": 2}),
     "alpha: unknown key (known: name, port, title, cpu_hz, carrier, sensor, refresh, display, wiring, button, led)"),
    ("pico", _set("carrier.frq_hz", 34000),
     "carrier.frq_hz: unknown key (known: freq_hz, duty_cap, drive, pins, pwm, idle_amplitude, "
     "deadtime_ns)"),
    ("pico", _del("port"), "port: missing (required)"),
    ("pico", _set("port", "esp32"), "port: 'esp32' is not one of rp2, stm32, circuitpython, virtual"),
    ("pico", _set("name", "pyboard"), "name: 'pyboard' does not match the file name (bad.json)"),
    ("pico", _set("name", "Pico!"), "name: 'Pico!': use 1..32 of a-z, 0-9, _ and -"),
    ("pico", _set("cpu_hz", 10), "cpu_hz: 10 Hz is out of range [1000000, 1000000000]"),
    ("pico", _set("cpu_hz", "125 MHz"), "cpu_hz: expected an integer, got a string '125 MHz'"),
    ("pico", _set("carrier", [16]), "carrier: expected an object, got a list"),
    ("pico", _set("carrier.freq_hz", 500), "carrier.freq_hz: 500 Hz is out of range [1000, 200000]"),
    ("pico", _set("carrier.freq_hz", 250000),
     "carrier.freq_hz: 250000 Hz is out of range [1000, 200000]"),
    ("pico", _set("carrier.freq_hz", "34000"),
     "carrier.freq_hz: expected an integer, got a string '34000'"),
    ("pico", _set("carrier.freq_hz", 34000.5),
     "carrier.freq_hz: expected an integer, got a number 34000.5"),
    ("pico", _set("carrier.freq_hz", True), "carrier.freq_hz: expected an integer, got a boolean"),
    ("pico", _set("carrier.freq_hz", None), "carrier.freq_hz: expected an integer, got null"),
    ("pico", _set("carrier.freq_hz", 7000),
     "carrier.freq_hz: 7000 Hz on the 125000000 Hz clock (cpu_hz) gives PWM TOP 17856; need "
     "499 .. 16382 (>= 500 counts for resolution and frequency accuracy; compare words within "
     "small ints)"),
    ("pico", _set("cpu_hz", 1_000_000),
     "carrier.freq_hz: 34000 Hz on the 1000000 Hz clock (cpu_hz) gives PWM TOP 28; need "
     "499 .. 16382 (>= 500 counts for resolution and frequency accuracy; compare words within "
     "small ints)"),
    ("pico", _set("carrier.duty_cap", 0), "carrier.duty_cap: 0 is out of range (0, 0.5]"),
    ("pico", _set("carrier.duty_cap", 0.6), "carrier.duty_cap: 0.6 is out of range (0, 0.5]"),
    ("pico", _set("carrier.duty_cap", -0.1), "carrier.duty_cap: -0.1 is out of range (0, 0.5]"),
    ("pico", _set("carrier.duty_cap", "half"),
     "carrier.duty_cap: expected a finite number, got a string 'half'"),
    ("pico", _set("carrier.drive", "triple"), "carrier.drive: 'triple' is not one of single, bridge"),
    ("pico", _set("carrier.pins", [16, 17]), "carrier.pins: drive 'single' needs 1 pin, got 2"),
    ("pico", _set("carrier.pins", 16), "carrier.pins: expected a list of pins, got a number 16"),
    ("pico", _set("carrier.pins", [30]), "carrier.pins[0]: 30 is out of range [0, 29]"),
    ("pico", _set("carrier.pins", ["GP16"]),
     "carrier.pins[0]: expected a GPIO number, got a string 'GP16'"),
    ("pico", _set("carrier.pwm.slice", 1), "carrier.pwm.slice: 1, but GPIO 16 is on PWM slice 0"),
    ("pico", _set("carrier.pwm.timer", 8),
     "carrier.pwm.timer: unknown key (known: slice)"),
    ("pico", _set("carrier.idle_amplitude", 70000),
     "carrier.idle_amplitude: 70000 is out of range [0, 65535]"),
    ("pico_bridge", _set("carrier.pins", [16]), "carrier.pins: drive 'bridge' needs 2 pins, got 1"),
    ("pico_bridge", _set("carrier.pins", [17, 18]),
     "carrier.pins: [17, 18]: a bridge takes the two channels of one PWM slice (GPIO 2k and "
     "2k+1, e.g. [16, 17]); leg B is inverted"),
    ("pico_bridge", _set("carrier.pins", [16, 15]),
     "carrier.pins: [16, 15]: a bridge takes the two channels of one PWM slice (GPIO 2k and "
     "2k+1, e.g. [16, 17]); leg B is inverted"),
    ("pico_bridge", _set("carrier.pins", [16, 16]),
     "carrier.pins: [16, 16]: a bridge takes the two channels of one PWM slice (GPIO 2k and "
     "2k+1, e.g. [16, 17]); leg B is inverted"),
    ("pico_bridge", _set("carrier.deadtime_ns", 200),
     "carrier.deadtime_ns: only stm32 timers (TIM1, TIM8) have a dead-time generator; on 'rp2' "
     "the gate drivers provide it"),
    ("pyboard", _set("carrier.pins", ["Y1", 8]),
     "carrier.pins[1]: expected a pin name such as \"Y1\", got a number 8"),
    ("pyboard", _set("carrier.pwm.timer", 2),
     "carrier.pwm.timer: 2: the carrier needs an advanced timer, 1 or 8 (complementary "
     "outputs, dead time, safe off state)"),
    ("pyboard", lambda d: d["carrier"].update({"drive": "single", "pins": ["X1"],
                                                "pwm": {"timer": 2, "channel": 1}}),
     "carrier.deadtime_ns: applies to drive 'bridge' (complementary outputs) only"),
    ("pyboard", lambda d: d["carrier"].update({"drive": "single", "pins": ["X1"],
                                                "pwm": {"timer": 2, "channel": 1},
                                                "deadtime_ns": 0}) or d["carrier"].pop("deadtime_ns"),
     "carrier.pwm.timer: 2: the carrier needs an advanced timer, 1 or 8 (complementary "
     "outputs, dead time, safe off state)"),
    ("pyboard", _set("carrier.deadtime_ns", 7000),
     "carrier.deadtime_ns: 7000 ns is 1176 ticks of the 168000000 Hz timer clock; pyb allows "
     "0 .. 1008"),
    ("pyboard", _set("carrier.deadtime_ns", -5),
     "carrier.deadtime_ns: -5 ns: a dead time cannot be negative"),
    ("pyboard", _set("carrier.deadtime_ns", 2.5),
     "carrier.deadtime_ns: expected an integer, got a number 2.5"),
    ("pyboard", _set("refresh.timer", 8),
     "refresh.timer: 8: need a pyb timer 1 .. 14 other than the carrier timers 1 and 8 and TIM2 (the refresh's clock)"),
    ("pyboard", _set("refresh.timer", 15),
     "refresh.timer: 15: need a pyb timer 1 .. 14 other than the carrier timers 1 and 8 and TIM2 (the refresh's clock)"),
    ("pico", _set("refresh.timer", 7),
     "refresh.timer: only stm32 boards choose the refresh timer (pyb.Timer id)"),
    ("pyboard", _set("carrier.pwm.channel", 4), "carrier.pwm.channel: 4 is out of range [1, 3]"),
    ("pyboard", _del("carrier.pwm.timer"), "carrier.pwm.timer: missing (required)"),
    ("pyboard", _set("sensor.pins", ["Y1"]), "sensor.pins[0]: pin 'Y1' is already used"),
    ("pico_cpy", _set("carrier.drive", "bridge"),
     "carrier.drive: 'bridge' needs an inverted (complementary) PWM output, which "
     "CircuitPython's pwmio cannot make; use 'single'"),
    ("pico_cpy", _set("carrier.freq_hz", 130000),
     "carrier.freq_hz: 130000 Hz on the 125000000 Hz clock (cpu_hz) gives PWM TOP 960; need "
     "999 .. 16382 (>= 1000 counts for resolution and frequency accuracy; compare words within "
     "small ints)"),
    ("pico_cpy", _set("refresh.mode", "timer_irq"),
     "refresh.mode: 'timer_irq' is not available on port 'circuitpython' (use loop)"),
    ("pico", _set("refresh.mode", "stepped"),
     "refresh.mode: 'stepped' is not available on port 'rp2' (use timer_irq, core1_viper, loop)"),
    ("pico", _set("refresh.mode", "dma"),
     "refresh.mode: 'dma' is not one of timer_irq, core1_viper, loop, stepped"),
    ("pico", _set("refresh.hz", 40000),
     "refresh.hz: 40000 Hz is faster than the carrier (34000 Hz)"),
    ("pico", _set("refresh.hz", 10), "refresh.hz: 10 Hz is out of range [50, 50000]"),
    ("pico", _set("sensor.kind", "optical"),
     "sensor.kind: 'optical' is not one of adc_linear, adc_ratio"),
    ("pico", _set("sensor.kind", "adc_ratio"), "sensor.pins: kind 'adc_ratio' needs 2 pins, got 1"),
    ("pico", _set("sensor.pins", [16]), "sensor.pins[0]: 16 is out of range [26, 29]"),
    ("virtual", _set("sensor.pins", [16]), "sensor.pins[0]: pin 16 is already used"),
    ("pico", _set("sensor.raw_at_start", 70000),
     "sensor.raw_at_start: 70000 is out of range [0, 65535]"),
    ("pico", _set("sensor.raw_at_end", 2100),
     "sensor.raw_at_end: 2100 is within 256 of raw_at_start (2000): the calibration span is "
     "too small"),
    ("pico", _set("sensor.lift_below", 3000),
     "sensor.lift_below: 3000 is above the calibrated range (2000 .. 63000): a finger at the "
     "end would read as lifted"),
    ("pico", _set("sensor.filter_shift", 9), "sensor.filter_shift: 9 is out of range [0, 8]"),
    ("pico", _set("sensor.latency_us", -1), "sensor.latency_us: -1 us is out of range [0, 20000]"),
    ("pico", _set("sensor.gain", 2),
     "sensor.gain: unknown key (known: kind, pins, raw_at_start, raw_at_end, lift_below, "
     "filter_shift, latency_us, velocity_shift, lift_debounce)"),
    ("pico", _set("display.positions", 0), "display.positions: 0 is out of range [1, 1048576]"),
    ("pico", _set("display.positions", 1048577),
     "display.positions: 1048577 is out of range [1, 1048576]"),
    ("pico", _set("display.positions", 19200.0),
     "display.positions: expected an integer, got a number 19200.0"),
    ("pico", _set("display.dx_um", 0), "display.dx_um: 0 is out of range (0, 1000.0]"),
    ("pico", _set("wiring", 7), "wiring: expected a string, got a number 7"),
]
BAD_IDS = [f"{i:02d}-{exp.split(':')[0]}" for i, (_, _, exp) in enumerate(BAD)]


@pytest.mark.parametrize("base,mutate,expected", BAD, ids=BAD_IDS)
def test_bad_board_rejected(tmp_path, base, mutate, expected):
    d = _mut(base, mutate)
    if isinstance(d.get("name"), str) and d["name"] == base:
        d["name"] = "bad"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(d))
    with pytest.raises(ValueError) as ei:
        boards.load("bad", search=[str(tmp_path)])
    assert str(ei.value) == f"{path}: {expected}"


def test_bad_top_level_and_json(tmp_path):
    for i, text in enumerate(['[1, 2]', '"pico"', '{"name": "bad",', '', '{"a": 1} x']):
        (tmp_path / "bad.json").write_text(text)
        with pytest.raises(ValueError) as ei:
            boards.load("bad", search=[str(tmp_path)])
        msg = str(ei.value)
        assert msg.startswith(f"{tmp_path / 'bad.json'}: "), msg
        if i < 2:
            assert msg.endswith("(top level): expected an object, got "
                                + ("a list" if i == 0 else "a string"))
        else:
            assert "not valid JSON" in msg


def test_non_finite_numbers_rejected():
    for v in (float("nan"), float("inf"), -float("inf")):
        d = _raw("pico")
        d["carrier"]["duty_cap"] = v
        assert "carrier.duty_cap: expected a finite number" in _err(d, "pico.json")
        d = _raw("pico")
        d["display"]["dx_um"] = v
        assert "display.dx_um: expected a finite number" in _err(d, "pico.json")


def test_validate_names_source_and_does_not_mutate():
    d = _raw("pico")
    d["carrier"]["freq_hz"] = 5
    before = copy.deepcopy(d)
    assert _err(d, "my/own.json").startswith("my/own.json: name: 'pico' does not match")
    assert _err(d, "somewhere").startswith("somewhere: carrier.freq_hz: 5 Hz is out of range")
    assert d == before


# --- the same under the MicroPython unix port ---------------------------------------

MP_LOAD_ALL = """
import json
from texel.runtime import boards
out = {}
for n in boards.names():
    b = boards.load(n)
    out[n] = {"board": b, "top": boards.board_top(b)}
out["_search"] = boards.search_path()
print(json.dumps(out))
"""


def test_shipped_boards_under_micropython():
    got = mpy.run_json(MP_LOAD_ALL)
    search = got.pop("_search")
    assert search[:2] == ["/boards", "boards"]
    assert Path(mpy.DEVICE / search[2]).resolve() == BOARDS_DIR   # relative to the cwd
    assert sorted(got) == SHIPPED
    for n in SHIPPED:
        b = boards.load(n)
        assert got[n]["board"] == b, n
        assert got[n]["top"] == boards.board_top(b)


def test_carrier_sweep_under_micropython():
    code = """
import json
from texel.runtime import boards
worst = {}
for cpu in (125000000, 168000000):
    w = 0.0
    for f in range(20000, 60001, 13):
        top = boards.pwm_top(cpu, f)
        e = abs(boards.actual_hz(cpu, top) / f - 1)
        if e > w:
            w = e
    worst[str(cpu)] = w
worst["pico"] = boards.pwm_top(125000000, 34000)
worst["pyboard"] = boards.pwm_top(168000000, 34000)
print(json.dumps(worst))
"""
    got = mpy.run_json(code)
    assert got["pico"] == 3675 and got["pyboard"] == 4940
    assert 0 < got["125000000"] < 0.001 and 0 < got["168000000"] < 0.001


def test_bad_boards_same_messages_under_micropython(tmp_path):
    """Every bad file of BAD, loaded by MicroPython, gives CPython's message
    exactly (fixed key order: MicroPython dicts are unordered)."""
    expected = {}
    for i, (base, mutate, _) in enumerate(BAD):
        name = f"bad{i:02d}"
        d = _mut(base, mutate)
        if isinstance(d.get("name"), str) and d["name"] == base:
            d["name"] = name
        (tmp_path / f"{name}.json").write_text(json.dumps(d))
        with pytest.raises(ValueError) as ei:
            boards.load(name, search=[str(tmp_path)])
        expected[name] = str(ei.value)
    code = """
import json
from texel.runtime import boards
out = {}
for n in boards.names(%r):
    try:
        boards.load(n, search=[%r])
        out[n] = None
    except ValueError as e:
        out[n] = str(e)
print(json.dumps(out))
""" % (str(tmp_path), str(tmp_path))
    got = mpy.run_json(code)
    assert sorted(got) == sorted(expected)
    for n in expected:
        assert got[n] == expected[n], n


def test_micropython_defaults_and_paths():
    code = """
import json
from texel.runtime import boards
b = boards.validate(%r, "boards/mini.json")
print(json.dumps({"b": b, "up": [boards._norm_up(p, 2) for p in
    ("texel", ".", "/texel", "/a/b/c", "../x", "a/b")]}))
""" % (MINIMAL,)
    got = mpy.run_json(code)
    assert got["b"] == boards.validate(MINIMAL, "boards/mini.json")
    assert got["up"] == ["..", "../..", "/", "/a", "../..", "."]
    assert [boards._norm_up(p, 2) for p in ("texel", ".", "/texel", "/a/b/c", "../x", "a/b")] \
        == got["up"]
