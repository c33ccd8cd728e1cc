"""Hardware backends (texel.hw.rp2, hw_stm32, hw_cpy) under the real
MicroPython unix port, with the recording fakes of tests/support/fakes first on the
module path (MICROPYPATH=tests/support/fakes:device).

The fakes model the peripherals the backends drive (the RP2040 PWM slice
registers, STM32 TIM1/TIM8 registers and pins, CircuitPython's rp2 pwmio
rounding), so the tests check what the pins would do over one carrier
period, not only which calls were made:

- carrier frequency and TOP/period as configured;
- the duty law end to end: amplitude -> DutyLaw counts -> set_duty -> the
  compare value the hardware holds, and the high time of leg A;
- safe state (duty 0, legs low) on construction, on off(), on stop();
- pin mapping per board dict (carrier legs, sensor ADC pins);
- bridge legs complementary at every count of the period;
- set_duty and adc_read allocation-free under micropython.heap_lock() (with
  a control allocation that must raise);
- the refresh timer: hard IRQ at 8,333 Hz, callback gets the timer object.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from support import mpy

ROOT = mpy.ROOT
FAKES = mpy.FAKES
BOARDS_DIR = ROOT / "device" / "texel" / "boards.d"


def _board(name, port, cpu_hz, carrier, sensor_pins, refresh_mode="timer_irq"):
    return {
        "name": name, "port": port, "title": name, "cpu_hz": cpu_hz,
        "carrier": dict({"freq_hz": 34000, "duty_cap": 0.5, "idle_amplitude": 0}, **carrier),
        "sensor": {"kind": "adc_ratio" if len(sensor_pins) == 2 else "adc_linear",
                   "pins": sensor_pins, "raw_at_start": 2000, "raw_at_end": 63000,
                   "lift_below": 1000, "filter_shift": 2, "latency_us": 150},
        "refresh": {"hz": 8333, "mode": refresh_mode},
        "display": {"positions": 19200, "dx_um": 5.3},
        "wiring": "test board",
    }


PICO = _board("pico", "rp2", 125000000,
              {"drive": "single", "pins": [16], "pwm": {"slice": 0}}, [26])
PICO_BRIDGE = _board("pico_bridge", "rp2", 125000000,
                     {"drive": "bridge", "pins": [16, 17], "pwm": {"slice": 0}}, [26, 27])
PICO_BRIDGE_BA = _board("pico_bridge_ba", "rp2", 125000000,   # leg A on channel B
                        {"drive": "bridge", "pins": [17, 16], "pwm": {"slice": 0}}, [26])
PYBOARD = _board("pyboard", "stm32", 168000000,
                 {"drive": "single", "pins": ["Y1"], "pwm": {"timer": 8, "channel": 1}}, ["X1"])
PYBOARD_BRIDGE = _board("pyboard_bridge", "stm32", 168000000,
                        {"drive": "bridge", "pins": ["Y1", "X8"],
                         "pwm": {"timer": 8, "channel": 1}}, ["X1", "X2"])
PICO_CPY = _board("pico_cpy", "circuitpython", 125000000,
                  {"drive": "single", "pins": [16], "pwm": {}}, ["A0"], "loop")

MODULE = {"rp2": "hw.rp2", "stm32": "hw.stm32", "circuitpython": "hw.cpy"}

# What the hardware does, per port (runs under MicroPython with the fakes).
PRELUDE = r"""
import json, micropython, machine, pyb, pwmio, analogio, board
from texel.runtime.duty import DutyLaw

def fresh():
    machine.reset(); pyb.reset(); pwmio.reset(); analogio.reset()

def make(b, cpu=None, **kw):
    # cpu: run the fake clocks at this frequency (default: rp2 125 MHz,
    # stm32 TIM1/8 168 MHz, CircuitPython 125 MHz)
    fresh()
    port = b["port"]
    if cpu is not None:
        machine.freq(cpu)
        pwmio.CPU_HZ = cpu
    if port == "rp2":
        from texel.hw.rp2 import Hw
    elif port == "stm32":
        from texel.hw.stm32 import Hw
    else:
        from texel.hw.cpy import Hw
    return Hw(b, **kw)

def waves(hw, port):
    # each leg's level at every count of one carrier period
    if port == "rp2":
        return [machine.wave(p) for p in hw.pins]
    if port == "stm32":
        return [pyb.wave(p, hw.timer_id) for p in hw.pins]
    o = pwmio.OUTS[-1]
    return [[o.level(c) for c in range(o.top + 1)]]

def summary(ws):
    # per leg: [counts high, counts low, counts floating]
    return [[w.count(1), w.count(0), w.count(None)] for w in ws]

def complementary(ws):
    return len(ws) == 2 and all(a is not None and b is not None and a != b
                                for a, b in zip(ws[0], ws[1]))

def compare(hw, port):
    # the compare value the hardware holds for leg A
    if port == "rp2":
        return machine.pwm_cc(hw.pins[0])
    if port == "stm32":
        return pyb.timer(hw.timer_id).channel(hw.channel).pulse_width()
    return pwmio.OUTS[-1].compare

def script_adc(port, pin, values):
    if port == "rp2":
        machine.script_adc(pin, values)
    elif port == "stm32":
        pyb.script_adc(pin, values)
    else:
        analogio.script(getattr(board, pin) if isinstance(pin, str) else
                        getattr(board, "GP%d" % pin), values)
"""


def run_mp(body: str, board: dict | None = None, **kw):
    code = PRELUDE
    if board is not None:
        code += "B = json.loads(%r)\n" % json.dumps(board)
    return mpy.run_json(code + body, extra_path=FAKES, **kw)


def run_mp_raw(body: str, board: dict | None = None) -> str:
    code = PRELUDE
    if board is not None:
        code += "B = json.loads(%r)\n" % json.dumps(board)
    return mpy.run(code + body, extra_path=FAKES, check=False)


# ------------------------------------------------------------- the shared suite

SUITE = r"""
AMPS = [0, 1, 100, 1000, 16384, 32768, 50000, 65472, 65535]
out = {}
hw = make(B)
port = B["port"]
out["top"] = hw.top
out["max_counts"] = hw.max_counts
out["construct"] = summary(waves(hw, port))
out["construct_compare"] = compare(hw, port)
law = DutyLaw(hw.top, B["carrier"]["duty_cap"])
rows = []
for a in AMPS:
    c = law.duty(a)
    hw.set_duty(c)
    ws = waves(hw, port)
    rows.append([a, c, compare(hw, port), summary(ws), complementary(ws)])
out["rows"] = rows
hw.set_duty(law.duty(40000))
hw.off()
out["off"] = summary(waves(hw, port))
out["off_compare"] = compare(hw, port)
# off() is not sticky: the next set_duty drives again
hw.set_duty(law.duty(40000))
out["after_off"] = [law.duty(40000), compare(hw, port), summary(waves(hw, port))]
# clamping: never above the cap, never below 0
hw.set_duty(hw.max_counts + 500)
out["clamp_hi"] = compare(hw, port)
hw.set_duty(-7)
out["clamp_lo"] = compare(hw, port)
print(json.dumps(out))
"""


def check_suite(r, board, top):
    n = top + 1
    bridge = board["carrier"]["drive"] == "bridge"
    legs = 2 if bridge else 1
    cap = int(board["carrier"]["duty_cap"] * n)
    assert r["top"] == top
    assert r["max_counts"] == cap
    low = [[0, n, 0]] * legs
    assert r["construct"] == low, "not safe after construction"
    assert r["construct_compare"] == 0
    from texel.runtime.duty import DutyLaw
    law = DutyLaw(top, board["carrier"]["duty_cap"])
    for a, c, cmp_, summ, compl in r["rows"]:
        assert c == law.duty(a)
        assert cmp_ == c, f"amplitude {a}: law says {c} counts, hardware compare {cmp_}"
        assert summ[0] == [c, n - c, 0], f"leg A high time for amplitude {a}"
        if bridge:
            assert summ[1] == [n - c, c, 0], f"leg B for amplitude {a}"
            assert compl, f"legs not complementary at amplitude {a}"
    assert r["rows"][-1][1] == cap            # amplitude 65535 lands on the cap
    assert r["off"] == low, "off() did not leave both legs low"
    assert r["off_compare"] == 0
    c40 = law.duty(40000)
    assert r["after_off"][:2] == [c40, c40]
    assert r["after_off"][2][0] == [c40, n - c40, 0]
    assert r["clamp_hi"] == cap and r["clamp_lo"] == 0


@pytest.mark.parametrize("board, top, kw", [
    (PICO, 3675, "direct=True"),
    (PICO, 3675, "direct=False"),
    (PICO_BRIDGE, 3675, "direct=True"),
    (PICO_BRIDGE, 3675, "direct=False"),
    (PICO_BRIDGE_BA, 3675, "direct=True"),
    (PICO_BRIDGE_BA, 3675, "direct=False"),
    (PYBOARD, 4940, ""),
    (PYBOARD_BRIDGE, 4940, ""),
    (PICO_CPY, 3675, ""),
], ids=["pico-direct", "pico-duty_u16", "pico_bridge-direct", "pico_bridge-duty_u16",
        "pico_bridge_ba-direct", "pico_bridge_ba-duty_u16", "pyboard", "pyboard_bridge",
        "pico_cpy"])
def test_backend_suite(board, top, kw):
    r = run_mp(SUITE.replace("hw = make(B)", "hw = make(B%s)" % (", " + kw if kw else "")),
               board)
    check_suite(r, board, top)


# ------------------------------------------------------------- rp2 specifics

def test_rp2_carrier_config_and_pins():
    r = run_mp(r"""
hw = make(B, direct=True)
out = {"pwms": [[p.gpio, p.freq_hz, p.invert, p.slice, p.channel] for p in machine.PWMS],
       "top_reg": machine.pwm_top(0), "div": machine.REGS[machine.pwm_reg(0, machine.PWM_DIV)],
       "freq": machine.PWMS[0].freq(), "adcs": [a.gpio for a in machine.ADCS],
       "mux": sorted(machine.MUX.items())}
print(json.dumps(out))
""", PICO_BRIDGE)
    assert r["pwms"] == [[16, 34000, False, 0, 0], [17, 34000, True, 0, 1]]   # leg B inverted
    assert r["top_reg"] == 3675 and r["div"] == 16                          # divider 1
    assert r["freq"] == 34004                  # the real carrier: 125 MHz / 3676 = 34,004.4 Hz
    assert r["adcs"] == [26, 27]
    assert r["mux"] == [[16, "PWM"], [17, "PWM"], [26, "ADC"], [27, "ADC"]]


def test_rp2_direct_store_is_one_32bit_cc_write():
    # slice 3 (GPIO 6/7): address 0x4005000C + 0x14*3, both halves in one store
    b = json.loads(json.dumps(PICO_BRIDGE))
    b["carrier"]["pins"] = [6, 7]
    b["carrier"]["pwm"] = {"slice": 3}
    r = run_mp(r"""
hw = make(B, direct=True)
machine.mem32.clear()
for c in (0, 1, 613, 1838):
    hw.set_duty(c)
hw.off()
print(json.dumps({"w": machine.mem32.writes(), "reads": machine.mem32.reads}))
""", b)
    cc = 0x4005000C + 0x14 * 3
    assert r["w"] == [[cc, 0], [cc, 0x10001], [cc, 613 * 0x10001], [cc, 1838 * 0x10001],
                      [cc, 3676 << 16]]      # off: A = 0, B (inverted) = TOP+1 -> both low
    assert r["reads"] == 0                    # the hot path only stores


def test_rp2_single_on_channel_b_and_single_writes():
    b = json.loads(json.dumps(PICO))
    b["carrier"]["pins"] = [17]
    b["carrier"]["pwm"] = {"slice": 0}
    r = run_mp(r"""
hw = make(B, direct=True)
machine.mem32.clear()
hw.set_duty(100)
print(json.dumps({"w": machine.mem32.writes(), "cc": machine.pwm_cc(17),
                  "wave": summary(waves(hw, "rp2"))}))
""", b)
    assert r["w"] == [[0x4005000C, 100 << 16]]
    assert r["cc"] == 100 and r["wave"] == [[100, 3576, 0]]


def test_rp2_duty_u16_fallback_hits_every_count_exactly():
    # the fallback's u16 value must round back (rp2: (u*(TOP+1)+32767)//65535)
    # to exactly the requested count, for every count up to the cap
    r = run_mp(r"""
hw = make(B, direct=False)
bad = []
for c in range(hw.max_counts + 1):
    hw.set_duty(c)
    if machine.pwm_cc(16) != c or machine.pwm_cc(17) != c:
        bad.append(c)
print(json.dumps({"bad": bad, "n": hw.max_counts, "stores": machine.mem32.count}))
""", PICO_BRIDGE)
    assert r["n"] == 1838 and r["bad"] == [] and r["stores"] == 0


@pytest.mark.parametrize("cpu, top", [(125000000, 3675), (133000000, 3911), (150000000, 4411),
                                      (200000000, 5881)])
def test_rp2_top_follows_cpu_hz(cpu, top):
    b = json.loads(json.dumps(PICO))
    b["cpu_hz"] = cpu
    r = run_mp(r"""
hw = make(B, cpu=B["cpu_hz"], direct=True)
print(json.dumps([hw.top, machine.pwm_top(0)]))
""", b)
    assert r == [top, top]
    assert top == (cpu + 17000) // 34000 - 1


@pytest.mark.parametrize("change, msg", [
    ({"carrier": {"drive": "bridge", "pins": [16, 18]}}, "two channels of one"),
    ({"carrier": {"drive": "bridge", "pins": [16]}}, "needs 2 pin"),
    ({"carrier": {"drive": "single", "pins": [16, 17]}}, "needs 1 pin"),
    ({"carrier": {"drive": "push-pull"}}, "carrier.drive"),
    ({"carrier": {"pins": [18], "pwm": {"slice": 0}}}, "slice"),
    ({"carrier": {"freq_hz": 5000}}, "freq_hz"),
    ({"cpu_hz": 133000000}, "machine.freq"),
    ({"port": "stm32"}, "port"),
])
def test_rp2_rejects_bad_boards(change, msg):
    b = json.loads(json.dumps(PICO))
    for k, v in change.items():
        if isinstance(v, dict):
            b[k].update(v)
        else:
            b[k] = v
    out = run_mp_raw(r"""
fresh()
from texel.hw.rp2 import Hw
try:
    Hw(B, direct=True)
    print("built")
except ValueError as e:
    print("ValueError:", e)
""", b)
    assert "ValueError:" in out and msg in out, out


def test_rp2_refresh_timer_hard_irq():
    r = run_mp(r"""
hw = make(B, direct=True)
got = []
def cb(t):
    got.append(t)
hw.start(cb, 8333)
t = machine.TIMERS[-1]
a = dict(t.args)
a["callback"] = a["callback"] is cb
t.fire(3)
out = {"args": a, "period_us": t.period_us, "calls": len(got),
       "same": all(g is t for g in got), "running": t.running}
hw.set_duty(900)
hw.stop()
out["after_stop"] = [t.running, summary(waves(hw, "rp2"))]
t.fire(2)
out["calls_after_stop"] = len(got)
# start twice: the first timer is stopped, one runs
hw.start(cb, 8333)
hw.start(cb, 8333)
out["running"] = [x.running for x in machine.TIMERS]
print(json.dumps(out))
""", PICO_BRIDGE)
    assert r["args"] == {"mode": 1, "callback": True, "period": -1, "tick_hz": 1000,
                         "freq": 8333, "hard": True}
    assert r["period_us"] == 120               # int(1e6 / 8333): 8,333.3 Hz
    assert r["calls"] == 3 and r["same"] and r["running"]
    assert r["after_stop"] == [False, [[0, 3676, 0], [0, 3676, 0]]]
    assert r["calls_after_stop"] == 3
    assert r["running"] == [False, False, True]


# ------------------------------------------------------------- stm32 specifics

def test_stm32_carrier_timer_pins_and_deadtime():
    r = run_mp(r"""
hw = make(B)
t = pyb.timer(8)
base = machine.TIM8_BASE
out = {"inits": t.inits, "freq": t.freq(), "period": t.period(), "psc": t.prescaler(),
       "dtg": machine.REGS[base + 0x44] & 0xFF, "dead": hw.deadtime_ticks,
       "pins": sorted([k, v["mode"], v["af"]] for k, v in pyb.PIN_STATE.items()),
       "adcs": [a.pin for a in pyb.ADCS], "ch": [t.channel(1).mode, hw.channel],
       "cr2_ois": (machine.REGS[base + 4] >> 8) & 3, "bdtr": machine.REGS[base + 0x44]}
hw.set_duty(100)
out["bdtr_run"] = machine.REGS[base + 0x44]
print(json.dumps(out))
""", PYBOARD_BRIDGE)
    assert r["inits"] == [{"freq": None, "prescaler": 0, "period": 4940, "mode": 0,
                           "callback": False, "deadtime": 34, "brk": 0}]
    assert r["period"] == 4940 and r["psc"] == 0
    assert r["freq"] == 34001                  # 168 MHz / 4941
    assert r["dead"] == 34 and r["dtg"] == 34  # 200 ns at 168 MHz
    # Y1 = PC6 = TIM8_CH1, X8 = PA7 = TIM8_CH1N, both AF3; X1/X2 = PA0/PA1 analog
    assert r["pins"] == [["A0", 3, -1], ["A1", 3, -1], ["A7", 2, 3], ["C6", 2, 3]]
    assert r["adcs"] == ["A0", "A1"]
    assert r["ch"] == [0, 1]                   # Timer.PWM
    assert r["cr2_ois"] == 0                   # idle levels low (pyb had set them high)
    assert r["bdtr"] & 0x8000 == 0 and r["bdtr"] & 0x0C00 == 0x0C00   # MOE off, OSSI/OSSR on
    assert r["bdtr_run"] == r["bdtr"] | 0x8000


def test_stm32_pins_are_low_outputs_before_the_timer_drives_them():
    r = run_mp(r"""
hw = make(B)
print(json.dumps(pyb.EVENTS))
""", PYBOARD_BRIDGE)
    ev = [e for e in r if e[0] in ("Pin.init", "Timer.init", "Timer.channel")]
    # OUT_PP value 0 first, then the timer, then the alternate function
    assert ev[0] == ["Pin.init", "C6", 1, -1, 0] and ev[1] == ["Pin.init", "A7", 1, -1, 0]
    assert ev[2][0] == "Timer.init" and ev[3][0] == "Timer.channel"
    assert ev[4] == ["Pin.init", "C6", 2, 3, None] and ev[5] == ["Pin.init", "A7", 2, 3, None]


@pytest.mark.parametrize("timer, channel, pins, ccr", [
    (1, 1, ["A8", "B13"], 0x40010034),
    (8, 2, ["Y2", "Y11"], 0x40010438),          # PC7 / PB0
    (1, 3, ["A10", "Y8"], 0x4001003C),          # PA10 / PB15
])
def test_stm32_timer_and_channel_addresses(timer, channel, pins, ccr):
    b = json.loads(json.dumps(PYBOARD_BRIDGE))
    b["carrier"]["pwm"] = {"timer": timer, "channel": channel}
    b["carrier"]["pins"] = pins
    r = run_mp(r"""
hw = make(B)
machine.mem32.clear()
hw.set_duty(777)
hw.off()
ws = None
hw.set_duty(321)
ws = waves(hw, "stm32")
print(json.dumps({"w": machine.mem32.writes(), "compl": complementary(ws),
                  "s": summary(ws)}))
""", b)
    bdtr = (0x40010000 if timer == 1 else 0x40010400) + 0x44
    assert [w[0] for w in r["w"]][:4] == [ccr, bdtr, bdtr, ccr]
    assert r["w"][0][1] == 777 and r["w"][3][1] == 0
    assert r["compl"] and r["s"] == [[321, 4941 - 321, 0], [4941 - 321, 321, 0]]


def test_stm32_adc_scaling_and_refresh_timer():
    r = run_mp(r"""
hw = make(B)
script_adc("stm32", "X1", [0, 1, 2048, 4095])
script_adc("stm32", "X2", [100])
vals = [hw.adc_read(0) for _ in range(4)] + [hw.adc_read(1)]
got = []
def cb(t):
    got.append(t)
hw.start(cb, 8333)
t = pyb.timer(7)
t.fire(2)
out = {"vals": vals, "inits": t.inits, "freq": t.freq(), "period": t.period(),
       "calls": len(got), "same": all(g is t for g in got)}
hw.set_duty(1000)
hw.stop()
out["stopped"] = [t.running, summary(waves(hw, "stm32"))]
print(json.dumps(out))
""", PYBOARD_BRIDGE)
    # read_u16 scaling of a 12-bit reading: raw << 4 | raw >> 8
    assert r["vals"] == [0, 16, 32776, 65535, 1600]
    assert r["inits"] == [{"freq": 8333, "prescaler": None, "period": None, "mode": 0,
                           "callback": True, "deadtime": 0, "brk": 0}]
    assert r["period"] == 10079 and r["freq"] == 8333      # 84 MHz / 10,080 = 8,333.3 Hz
    assert r["calls"] == 2 and r["same"]
    assert r["stopped"] == [False, [[0, 4941, 0], [0, 4941, 0]]]


@pytest.mark.parametrize("change, msg", [
    ({"carrier": {"pwm": {"timer": 2, "channel": 1}}}, "carrier.pwm.timer"),
    ({"carrier": {"pwm": {"timer": 8, "channel": 4}}}, "carrier.pwm.channel"),
    ({"carrier": {"pins": ["Y1"]}}, "needs 2 pin"),
    ({"refresh": {"hz": 8333, "timer": 8}}, "refresh.timer"),
    ({"cpu_hz": 180000000}, "source_freq"),
    ({"carrier": {"deadtime_ns": 7000}}, "deadtime_ns"),
    ({"port": "rp2"}, "port"),
])
def test_stm32_rejects_bad_boards(change, msg):
    b = json.loads(json.dumps(PYBOARD_BRIDGE))
    for k, v in change.items():
        if isinstance(v, dict):
            b[k].update(v)
        else:
            b[k] = v
    out = run_mp_raw(r"""
fresh()
from texel.hw.stm32 import Hw
try:
    Hw(B)
    print("built")
except ValueError as e:
    print("ValueError:", e)
""", b)
    assert "ValueError:" in out and msg in out, out


# ------------------------------------------------------------- CircuitPython

def test_cpy_pwmout_pins_and_exact_counts():
    r = run_mp(r"""
hw = make(B)
o = pwmio.OUTS[0]
bad = []
for c in range(hw.max_counts + 1):
    hw.set_duty(c)
    if o.compare != c:
        bad.append(c)
script_adc("circuitpython", "A0", [7, 65535])
out = {"pin": o.pin.name, "freq": o.frequency, "var": o.variable_frequency, "top": o.top,
       "bad": bad, "adc_pins": [a.pin.name for a in analogio.INS],
       "adc": [hw.adc_read(0), hw.adc_read(0)], "writes": o.writes}
try:
    hw.start(lambda t: None, 8333)
    out["start"] = "ran"
except NotImplementedError as e:
    out["start"] = str(e)
hw.set_duty(500)
hw.stop()
out["stopped"] = [o.duty_cycle, summary(waves(hw, "circuitpython"))]
# a start after a stop in the same VM (texel.app.serve's Ctrl-C): the pins are taken over
hw2 = make(B)
hw2.set_duty(7)
out["again"] = [hw2._pwm is o, hw2._adc[0] is hw._adc[0], o.compare]
print(json.dumps(out))
""", PICO_CPY)
    # pwmio's own TOP and frequency (10.2.1: cpu // freq - 1 = 3675, 125 MHz / 3676)
    assert r["pin"] == "GP16" and r["freq"] == 34004 and r["var"] is False
    assert r["top"] == 3675 and r["bad"] == []
    assert r["writes"] == 1839 + 1          # one per count, and the constructor's duty 0
    assert r["adc_pins"] == ["GP26"] and r["adc"] == [7, 65535]
    assert "paced loop" in r["start"]
    assert r["stopped"] == [0, [[0, 3676, 0]]]     # driven low, never released to float
    assert r["again"] == [True, True, 7]


def test_cpy_rejects_bridge():
    b = json.loads(json.dumps(PICO_CPY))
    b["carrier"].update({"drive": "bridge", "pins": [16, 17]})
    out = run_mp_raw("""
try:
    make(B)
    print("built")
except ValueError as e:
    print("ValueError:", e)
""", b)
    assert "ValueError:" in out and "single" in out, out


# ------------------------------------------------------------- hot path

HEAP = r"""
def hot(hw, n):
    s = 0
    for i in range(n):
        hw.set_duty(i & 4095)             # includes clamped values
        s += hw.adc_read(i & 1) if len(hw._adc) > 1 else hw.adc_read(0)
    hw.set_duty(-3)
    return s

def control():
    return bytearray(16)

def locked(hw, res):
    micropython.heap_lock()
    try:
        res[0] = hot(hw, 2000)
        res[1] = 1
    except MemoryError:
        res[1] = 0
    try:
        control()
    except MemoryError:
        res[2] = 1
    micropython.heap_unlock()

def timed(hw, n):
    set_duty = hw.set_duty
    import time
    t = time.ticks_us()
    for i in range(n):
        set_duty(i & 1023)
    return time.ticks_diff(time.ticks_us(), t) / n

hw = make(B%s)
for i, p in enumerate(B["sensor"]["pins"]):
    script_adc(B["port"], p, [1000 + i, 2000 + i, 3000 + i])
res = [0, 0, 0]
locked(hw, res)
print(json.dumps({"ok": res[1] == 1, "sum": res[0], "control_raised": res[2] == 1,
                  "us": timed(hw, 20000)}))
"""


@pytest.mark.parametrize("board, kw", [
    (PICO, ", direct=True"), (PICO_BRIDGE, ", direct=True"), (PICO_BRIDGE, ", direct=False"),
    (PYBOARD, ""), (PYBOARD_BRIDGE, ""), (PICO_CPY, ""),
], ids=["pico-direct", "pico_bridge-direct", "pico_bridge-duty_u16", "pyboard",
        "pyboard_bridge", "pico_cpy"])
def test_set_duty_and_adc_read_allocation_free(board, kw):
    r = run_mp(HEAP % kw, board)
    assert r["control_raised"], "heap_lock did not lock (the control allocation succeeded)"
    assert r["ok"], "set_duty or adc_read allocated under heap_lock"
    assert r["sum"] > 0
    print("%s%s: %.2f us per set_duty (unix port, through the fake)" % (board["name"], kw, r["us"]))


# ------------------------------------------------------------- imports, boards, mpy-cross

HW_FILES = ["hw/rp2.py", "hw/stm32.py", "hw/cpy.py"]


def test_backends_fail_cleanly_without_their_platform():
    # CPython: ImportError (ModuleNotFoundError) naming the platform module,
    # and importing texel pulls in no backend
    code = (
        "import sys, importlib, texel\n"
        "assert not [m for m in sys.modules if m.startswith('texel.hw.')]\n"
        "for name, mod in (('hw.rp2', 'machine'), ('hw.stm32', 'pyb'), ('hw.cpy', 'pwmio')):\n"
        "    try:\n"
        "        importlib.import_module('texel.' + name)\n"
        "    except ImportError as e:\n"
        "        assert mod in str(e), e\n"
        "    else:\n"
        "        raise SystemExit(name + ' imported')\n"
        "print('ok')\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "device"))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0 and p.stdout.strip() == "ok", p.stdout + p.stderr
    # MicroPython without the fakes: pyb / pwmio are missing -> ImportError;
    # (the unix port has its own small `machine`, without PWM/ADC/Timer)
    out = mpy.run("""
import sys, texel
print(sorted(m for m in sys.modules if m.startswith('texel.hw.')))
for name in ('texel.hw.stm32', 'texel.hw.cpy'):
    try:
        __import__(name)
        print(name, 'imported')
    except ImportError as e:
        print(name, 'ImportError')
""")
    assert out.split() == ["[]", "texel.hw.stm32", "ImportError", "texel.hw.cpy", "ImportError"]


def _real_boards():
    if not BOARDS_DIR.is_dir():
        return []
    out = []
    for f in sorted(BOARDS_DIR.glob("*.json")):
        try:
            b = json.loads(f.read_text())
        except ValueError:
            continue
        if b.get("port") in MODULE:
            out.append(pytest.param(b, id=f.stem))
    return out


REAL = _real_boards()


@pytest.mark.skipif(not REAL, reason="no boards/*.json for a hardware port yet")
@pytest.mark.parametrize("board", REAL)
def test_real_board_files(board):
    """The shipped board definitions build on their backend and pass the suite."""
    port = board["port"]
    kw = ", cpu=B['cpu_hz']" + (", direct=True" if port == "rp2" else "")
    body = SUITE.replace("hw = make(B)", "hw = make(B%s)" % kw)
    cpu = int(board["cpu_hz"])
    if port == "stm32" and cpu != 168000000:
        # the fake models an F405 (TIM1/8 at 168 MHz); another STM32's advanced timers
        # (the Black Pill's F411: 96 MHz) are the board file's clock
        body = ("import pyb\npyb.SOURCE_FREQ.update({1: %d, 8: %d})\n" % (cpu, cpu)) + body
    r = run_mp(body, board)
    f = int(board["carrier"]["freq_hz"])
    if port == "rp2":
        top = (cpu + f // 2) // f - 1
    elif port == "stm32":
        top = (cpu + f // 2) // f - 1
    else:
        top = cpu // f - 1                       # CircuitPython 10 pwmio (hw/cpy.py)
    check_suite(r, dict(board, carrier=dict(board["carrier"],
                                            duty_cap=board["carrier"].get("duty_cap", 0.5))), top)


@pytest.mark.parametrize("name", ["runtime/duty.py"] + HW_FILES)
@pytest.mark.parametrize("march", ["armv6m", "armv7emsp", None])
def test_mpy_cross(tmp_path, name, march):
    src = mpy.DEVICE / "texel" / name
    p = mpy.mpy_cross(src, tmp_path / (name[:-3].replace("/", "_") + ".mpy"), march)
    assert p.returncode == 0, p.stdout + p.stderr
