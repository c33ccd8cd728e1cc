"""The fused viper refresh (texel/refresh_viper.py) computes exactly what the
Python refresh computes from the same sensor, scene and duty-law objects:
same position, amplitude and duty at every refresh (integers: no tolerance),
same telemetry; its rp2 IRQ entry reads the ADC and writes the compare
register through the addresses it is given; and nothing allocates."""

import pytest

from support import mpy

COMMON = r"""
import json
from array import array
from texel.runtime import boards, scene as S
from texel.runtime.duty import DutyLaw
from texel.runtime.sensor import make_sensor
from texel.runtime.refresh import Refresh
from texel.runtime.refresh_viper import FastRefresh, irq_rp2

board = boards.load("virtual")
disp = board["display"]
cfg = dict(board["sensor"])
cfg.update(%(cfg)s)


def raw_script(n, seed):
    # a finger that touches, swipes at varying speed with noise, drops out
    # for single samples, lifts, touches down elsewhere, and runs off both ends
    out = []
    x = seed & 0x7FFFFFFF
    r0, r1 = cfg["raw_at_start"], cfg["raw_at_end"]
    pos = 3000
    vel = 7
    for k in range(n):
        x = (x * 48271) %% 0x7FFFFFFF
        phase = (k // 1500) %% 4
        if phase == 3:
            out.append(x %% 900)                   # lifted
            pos = (x >> 3) %% 19200
            continue
        if x %% 97 == 0:
            out.append(0)                         # a single dropout
            continue
        if k %% 400 == 0:
            vel = (x >> 5) %% 61 - 30
        pos += vel
        if pos < -300 or pos > 19500:
            vel = -vel
        p = 0 if pos < 0 else (19199 if pos > 19199 else pos)
        raw = r0 + ((r1 - r0) * p) // 19199 + (x %% 41) - 20
        out.append(0 if raw < 0 else (65535 if raw > 65535 else raw))
    return out


def uploaded():
    # scene.K_CHUNK: a map uploaded over part of the display (texel.app.upload_*),
    # played from its 4 KB chunks; 7,001 values, 3 full chunks and a short one
    from texel.runtime.upload import Upload
    s0 = S.to_position(20.0, disp["dx_um"])
    e0 = S.to_position(57.11, disp["dx_um"])
    up = Upload(e0 - s0)
    raw = bytearray()
    x = 12345
    for k in range(e0 - s0):
        x = (x * 48271) %% 0x7FFFFFFF
        raw.append(x & 0xFF)
        raw.append((x >> 8) & 0xFF)
    for o in range(0, e0 - s0, 1000):
        up.write(o, bytes(raw[2 * o:2 * min(e0 - s0, o + 1000)]))
    sc = S.build(S.validate({"regions": [
        {"start_mm": 20.0, "end_mm": 57.11, "texture": {"kind": "samples", "u16": up}},
        {"start_mm": 60, "end_mm": 70, "texture": {"kind": "constant", "level": 0.3}}]}, disp), disp)
    assert S.K_CHUNK in [k for (_, _, k, _) in sc.spans()]
    return sc


scenes = [None,
          S.build(S.validate(%(scene_a)s, disp), disp),
          S.build(S.validate(%(scene_b)s, disp), disp, idle_default=1234),
          uploaded()]


class Feed:
    def __init__(self, seq):
        self.seq = seq
        self.i = 0

    def read(self):
        v = self.seq[self.i]
        self.i += 1
        return v


def make(kind, seq):
    feed = Feed(seq)
    sensor = make_sensor(cfg, [feed.read], disp["positions"], 8333)
    law = DutyLaw(3675, 0.5)
    duties = []
    clock = [0]
    ticks = lambda: clock[0]
    diff = lambda a, b: a - b
    if kind == "py":
        r = Refresh(sensor, law, duties.append, ticks, diff, 120, 77)
    else:
        r = FastRefresh(sensor, law, duties.append, feed.read, ticks, diff, 120, 77)
    return r, duties, clock
"""

SCENE_A = ('{"regions": [{"start_mm": 0, "end_mm": 50.88, "texture": {"kind": "reference", "name": "4sin"}},'
           ' {"start_mm": 50.88, "end_mm": 101.76, "texture": {"kind": "texel", "pitch_db": 6.3,'
           ' "irregularity_db": -12.9, "seed": 7}}]}')
SCENE_B = ('{"regions": [{"start_mm": 3, "end_mm": 20, "texture": {"kind": "constant", "level": 0.7}},'
           ' {"start_mm": 25, "end_mm": 40, "texture": {"kind": "samples", "values": [0, 0.5, 1, 0.25]}},'
           ' {"start_mm": 40, "end_mm": 41, "texture": {"kind": "reference", "name": "pink"}},'
           ' {"start_mm": 45, "end_mm": 58, "texture": {"kind": "samples", "fit": "stretch",'
           ' "u16": [0, 65535, 9, 40000]}},'
           ' {"start_mm": 60, "end_mm": 99, "texture": {"kind": "texel", "pitch_db": 15,'
           ' "irregularity_db": 0, "seed": 3, "texel_samples": 7}}], "idle_amplitude": 999}')

EQUIV = COMMON + r"""
seq = raw_script(%(n)d, %(seed)d)
idle_duty = DutyLaw(3675, 0.5).duty(77)      # what a lifted finger plays (idle 77)
res = []
for si in range(len(scenes)):
    rp, dp, cp = make("py", seq)
    rv, dv, cv = make("viper", seq)
    rp.swap(scenes[si])
    rv.swap(scenes[si])
    rp.tel_every = rv.tel_every = 3
    mism = 0
    first = None
    for k in range(len(seq)):
        cp[0] = cv[0] = k * 120
        rp.step()
        rv.step()
        a = (rp.pos, rp.amp, rp.duty)
        b = (rv.pos, rv.amp, rv.duty)
        if a != b or dp[-1] != dv[-1]:
            mism += 1
            if first is None:
                first = [k, a, b]
        # swap scenes mid-run on both
        if k == len(seq) // 2:
            rp.swap(scenes[(si + 1) %% len(scenes)])
            rv.swap(scenes[(si + 1) %% len(scenes)])
    tp = rp.telemetry_since(0)
    tv = rv.telemetry_since(0)
    lifted = sum(1 for d in dp if d == idle_duty)
    res.append({"mism": mism, "first": first, "count": [rp.count, rv.count], "lifted": lifted,
                "tel_equal": tp == tv, "tel_n": len(tp[0]),
                "positions": len(set(x[0] for x in tp[0]))})
print(json.dumps(res))
"""


@pytest.mark.parametrize("cfg", ["{}", '{"raw_at_start": 60000, "raw_at_end": 3000}',
                                 '{"filter_shift": 0, "latency_us": 0}',
                                 '{"filter_shift": 5, "velocity_shift": 2, "lift_debounce": 1}'],
                         ids=["board", "reversed", "unfiltered", "slow-filter"])
@pytest.mark.slow
def test_viper_equals_python_refresh(cfg):
    code = EQUIV % {"cfg": cfg, "scene_a": SCENE_A, "scene_b": SCENE_B, "n": 6000, "seed": 11}
    res = mpy.run_json(code, timeout=300)
    assert len(res) == 4
    for r in res:
        assert r["mism"] == 0, r["first"]
        assert r["count"] == [6000, 6000]
        assert r["tel_equal"] is True and r["tel_n"] == 256
        assert r["positions"] > 10          # the script really moves the finger
        assert r["lifted"] > 0              # ... and lifts it: the idle level plays


IRQ = COMMON + r"""
import micropython
from texel.runtime import refresh_viper as RV
seq = raw_script(3000, 5)
rp, dp, cp = make("py", seq)
rv, dv, cv = make("viper", seq)
rp.swap(scenes[1])
rv.swap(scenes[1])
clock = array("I", [1000])               # TIMERAWL
adc = array("I", [0x100, 0])             # CS (READY set), RESULT
cc = array("I", [0])                     # the slice's CC word
import uctypes
rv.use_rp2_registers(uctypes.addressof(cc), (1 << 16) | 1, 0,
                     timer_addr=uctypes.addressof(clock), adc_addr=uctypes.addressof(adc))
cs_word = rv._S[RV.S_ADC_CS]
# An array is not an ADC: it cannot raise READY when the conversion ends, so
# the word written to CS carries READY (bit 8, read-only on the RP2040) here.
rv._S[RV.S_ADC_CS] = cs_word | 0x100


def run():
    bad = 0
    for k in range(len(seq)):
        raw = seq[k]
        adc[1] = raw >> 4                         # the RP2040's 12-bit result
        irq_rp2(None)
        if cc[0] != ((dq[k] << 16) | dq[k]):
            bad += 1
    return bad


# the python reference on the same 12-bit readings, scaled as rp2's read_u16
seq12 = [((x >> 4) << 4) | ((x >> 4) >> 8) for x in seq]
rp2, dp2, cp2 = make("py", seq12)
rp2.swap(scenes[1])
for k in range(len(seq12)):
    rp2.step()
dq = dp2


def locked():
    micropython.heap_lock()
    try:
        b = run()
        r = "ok"
    except MemoryError:
        b = -1
        r = "MemoryError"
    micropython.heap_unlock()
    return r, b


r, bad = locked()
print(json.dumps({"alloc": r, "bad": bad, "adc_cs": adc[0], "cs_word": cs_word, "count": rv.count,
                  "worst": rv.worst_us, "overruns": rv.overruns}))
"""


def test_irq_rp2_reads_adc_and_writes_cc_without_allocating():
    code = IRQ % {"cfg": "{}", "scene_a": SCENE_A, "scene_b": SCENE_B}
    r = mpy.run_json(code, timeout=300)
    assert r["alloc"] == "ok"
    assert r["bad"] == 0                  # every CC word = duty in both halves (bridge MUL)
    assert r["cs_word"] == 1 | 4          # EN | START_ONCE, AINSEL = channel 0 (GP26)
    assert r["adc_cs"] == 1 | 4 | 0x100   # what the IRQ wrote (with the fake's READY)
    assert r["count"] == 3000
    assert r["worst"] == 0 and r["overruns"] == 0   # the fake clock does not move


HEAP = COMMON + r"""
import micropython
seq = raw_script(7000, 9)
rv, dv, cv = make("viper", seq)
rv.swap(scenes[2])
rv.tel_every = 2
dv.extend([0] * 6000)                      # preallocate the duty log...
del dv[:]


def locked():
    micropython.heap_lock()
    try:
        for k in range(4000):
            rv.step()
        r = "ok"
    except MemoryError:
        r = "MemoryError"
    micropython.heap_unlock()
    return r


def chunked():
    # the uploaded map (scene.K_CHUNK) through the viper refresh and Scene.amp
    rv.swap(scenes[3])
    sc = scenes[3]
    micropython.heap_lock()
    try:
        for k in range(2000):
            rv.step()
        for p in range(0, 19200, 7):
            sc.amp(p)
        r = "ok"
    except MemoryError:
        r = "MemoryError"
    micropython.heap_unlock()
    return r


def control():
    micropython.heap_lock()
    try:
        x = [1]
        r = "allocated"
    except MemoryError:
        r = "MemoryError"
    micropython.heap_unlock()
    return r


print(json.dumps({"step": locked(), "chunked": chunked(), "control": control(), "n": rv.count}))
"""


def test_fast_step_allocates_nothing():
    code = HEAP % {"cfg": "{}", "scene_a": SCENE_A, "scene_b": SCENE_B}
    r = mpy.run_json(code, timeout=120)
    assert r["control"] == "MemoryError"
    assert r["step"] == "ok" and r["chunked"] == "ok" and r["n"] == 6000
