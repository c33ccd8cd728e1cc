"""The device runtime end to end, under the real MicroPython unix port: the
virtual board (stepped time, a scripted finger feeding the board's own
sensor code through a virtual ADC, every duty recorded) and the rp2 board on
recording fakes of `machine`.

Tolerances, and why:
- Exact: every refresh plays law.duty(scene.amp(p_sensed)) - the map at the
  position the sensor reports, through the sin(pi D) law, with no other error
  (checked per refresh from telemetry taken at the full refresh rate).
- POS_TOL = 3 positions (16 um) between the sensed and the true finger: the
  sensor tracks a constant-speed swipe to < 1 position after settling
  (tests/runtime/test_sensor.py: 0.56 at 100 mm/s); the virtual ADC's integer
  calibration adds < 1 position; the margin covers a speed change.
- SETTLE = 40 refreshes (4.8 ms) after touch-down and after a stop are not
  checked against the true finger: the filter re-seeds and the velocity
  estimate decays (an abrupt stop at 100 mm/s overshoots ~6 positions and is
  back within 3 after ~25 refreshes).
- Lift: carrier at idle within LIFT_DEBOUNCE = 3 refreshes.
"""

import json

import pytest

from support import mpy

FAKES = mpy.FAKES
POS_TOL = 3
SETTLE = 40
LIFT_DEBOUNCE = 3

SWIPE = r"""
import json
import texel.app as app
import texel.wire as wire
st0 = app.start("virtual", fast=%(fast)s)
rt = app._rt
hw = rt.hw
law = rt.law
# touch at 5 mm, swipe to 95 mm at 100 mm/s, hold 50 ms, lift at 960 ms
wire.finger([(0, 5.0), (900, 95.0), (950, 95.0), (960, None)])
hw.clear_record()
app.stream(rate_hz=8333)              # telemetry at every refresh
sc = rt.refresh.scene
exact_bad = 0
exact_n = 0
tel_lost = 0
t = 0
while t < 1100:
    wire.advance(20)                   # 166 refreshes < the 256-slot ring
    t += 20
    samples, lost = app.telemetry()
    tel_lost += lost
    for (ts, pos, amp) in samples:
        want = sc.idle if pos < 0 else sc.amp(pos)
        exact_n += 1
        if amp != want:
            exact_bad += 1
# duties against the true finger
track_bad = 0
track_n = 0
worst_pos = 0
lift_late = 0
over_cap = 0
cap = (hw.top + 1) // 2
idle_duty = law.duty(sc.idle)
for i in range(hw.nrec):
    ts = hw.rec_t[i]
    d = hw.rec_d[i]
    if d > cap:
        over_cap += 1
    p = hw.finger.at(ts)
    if p < 0:
        if ts >= 960000 + %(deb)d * 120 and d != idle_duty:
            lift_late += 1
        continue
    if i < %(settle)d or 900000 <= ts < 900000 + %(settle)d * 120:
        continue
    track_n += 1
    ok = False
    for q in range(max(0, p - %(tol)d), min(19199, p + %(tol)d) + 1):
        if law.duty(sc.amp(q)) == d:
            ok = True
            break
    if not ok:
        track_bad += 1
st = app.status()
app.stop()
last = hw.rec_d[hw.nrec - 1]
print(json.dumps({"n": hw.nrec, "exact_n": exact_n, "exact_bad": exact_bad, "tel_lost": tel_lost,
                  "track_n": track_n, "track_bad": track_bad, "lift_late": lift_late,
                  "over_cap": over_cap, "last_duty_after_stop": last, "status": st, "start": st0}))
"""


@pytest.fixture(scope="module", params=[True, False], ids=["viper", "python"])
def swipe(request):
    code = SWIPE % {"tol": POS_TOL, "settle": SETTLE, "deb": LIFT_DEBOUNCE,
                    "fast": request.param}
    r = mpy.run_json(code, timeout=300)
    r["fast"] = request.param
    return r


def test_swipe_every_refresh_recorded(swipe):
    # 1.1 s at 8,333 Hz (virtual periods of 1e6/8333 us) + the safe-off
    # write of app.stop()
    assert swipe["n"] == 9166 + 1
    st = swipe["status"]
    assert st["refreshes"] == 9166 and st["faults"] == 0
    assert st["board"] == "virtual" and st["pwm_top"] == 3675 and st["refresh_hz"] == 8333
    assert st["refresh"] == ("viper" if swipe["fast"] else "python")


def test_swipe_plays_map_at_sensed_position_exactly(swipe):
    assert swipe["tel_lost"] == 0
    assert swipe["exact_n"] == 9166
    assert swipe["exact_bad"] == 0


def test_swipe_tracks_true_finger(swipe):
    assert swipe["track_n"] > 7000
    assert swipe["track_bad"] == 0


def test_lift_goes_to_idle_and_stop_is_safe(swipe):
    assert swipe["lift_late"] == 0
    assert swipe["last_duty_after_stop"] == 0


def test_duty_never_exceeds_cap(swipe):
    assert swipe["over_cap"] == 0


def test_status_reports_scene_and_versions(swipe):
    st = swipe["start"]
    assert st["protocol"] == 3 and st["running"] is True
    regs = st["scene"]["regions"]
    assert [r["kind"] for r in regs] == ["reference", "texel"]
    # the reference half as a 9,600-sample uint16 map, the texel half as its
    # plan (192 texels x 8 bytes), and the region table
    assert st["scene"]["bytes"] == 2 * 9600 + 8 * 192 + 48 == 20784
    assert [r["mode"] for r in st["scene"]["regions"]] == ["map", "plan"]
    assert st["last_push"]["scene_bytes"] == 20784
    assert st["firmware"].startswith("micropython")


SWAP = r"""
import json
import texel.app as app
import texel.wire as wire
app.start("virtual")
rt = app._rt
hw = rt.hw
law = rt.law
wire.finger([(0, 20.0), (2000, 80.0)])          # 30 mm/s across both halves
wire.advance(100)
old = rt.refresh.scene
before = app.status()["scene"]
errors = []
for bad in ({"regions": [{"start_mm": 0, "end_mm": 50, "texture": {"kind": "texel",
                          "pitch_db": float("nan"), "irregularity_db": -10}}]},
            {"regions": [{"start_mm": 0, "end_mm": 60, "texture": {"kind": "constant", "level": 0.5}},
                         {"start_mm": 50, "end_mm": 90, "texture": {"kind": "constant", "level": 0.2}}]},
            {"regions": [], "junk": "__import__('os').system('x')"},
            "not a scene"):
    try:
        app.push(bad)
        errors.append(None)
    except ValueError as e:
        errors.append(str(e))
same = rt.refresh.scene is old and app.status()["scene"] == before
hw.clear_record()
wire.advance(100)
still_old = 0
for i in range(hw.nrec):
    p = hw.finger.at(hw.rec_t[i])
    if any(law.duty(old.amp(q)) == hw.rec_d[i] for q in range(max(0, p - 3), min(19199, p + 3) + 1)):
        still_old += 1
n_old = hw.nrec
new = {"regions": [{"start_mm": 0, "end_mm": 101.76, "texture": {"kind": "constant", "level": 0.25}}]}
st = app.push(new)
hw.clear_record()
wire.advance(100)
new_duty = law.duty(rt.refresh.scene.amp(0))
all_new = all(hw.rec_d[i] == new_duty for i in range(hw.nrec))
print(json.dumps({"errors": errors, "same": same, "still_old": still_old, "n_old": n_old,
                  "all_new": all_new, "n_new": hw.nrec, "last_push": st["last_push"],
                  "pushes": st["pushes"]}))
app.stop()
"""


def test_rejected_scene_keeps_old_playing_and_swap_is_clean():
    r = mpy.run_json(SWAP, timeout=120)
    e = r["errors"]
    assert e[0].startswith("regions[0].texture.pitch_db:") and "not finite" in e[0]
    assert "overlap" in e[1]
    assert e[2] is not None and e[3] is not None
    assert r["same"] is True
    assert r["n_old"] == 833 and r["still_old"] == r["n_old"]
    assert r["all_new"] is True and r["n_new"] == 833
    assert r["pushes"] == 2
    assert r["last_push"]["scene_bytes"] < 100     # a constant region holds no samples


def test_step_uses_one_scene_even_if_swapped_mid_refresh():
    """The refresh reads self.scene once: a swap landing while a refresh runs
    (an IRQ can't be interrupted by the REPL on a board, but the swap could
    land between two reads in a naive loop) never mixes two scenes."""
    code = r"""
import json
from texel.runtime.refresh import Refresh
class Law:
    def duty(self, a): return a
class Sensor:
    def read(self): return 5
class Sc:
    def __init__(self, v, other=None):
        self.v = v; self.idle = 0; self.other = other; self.r = None
    def amp(self, pos):
        if self.other is not None:
            self.r.swap(self.other)          # swap lands mid-refresh
        return self.v
out = []
r = Refresh(Sensor(), Law(), out.append, lambda: 0, lambda a, b: a - b, 120)
b = Sc(222)
a = Sc(111, b)
a.r = r
r.swap(a)
r.step()
r.step()
print(json.dumps(out))
"""
    assert mpy.run_json(code) == [111, 222]


HEAP = r"""
import json, micropython
import texel.app as app
import texel.wire as wire
app.start("virtual", fast=%(fast)s)
rt = app._rt
hw = rt.hw
wire.finger([(0, 10.0), (1000, 90.0), (1100, None), (1200, 30.0)])
app.stream(rate_hz=125)
wire.advance(1)                        # first refresh outside the lock


def locked(us):
    # inside a function: names are locals (a new module-level global could
    # grow the globals dict and allocate by itself)
    n = 0
    r = "ok"
    micropython.heap_lock()
    try:
        n = hw.advance(us)            # swipe, lift, touch-down, telemetry
    except MemoryError:
        r = "MemoryError"
    micropython.heap_unlock()
    return r, n


def control():
    r = "allocated"
    micropython.heap_lock()
    try:
        x = [1, 2, 3]
    except MemoryError:
        r = "MemoryError"
    micropython.heap_unlock()
    return r


res = {}
res["refresh"], res["n"] = locked(1500000)
res["control"] = control()
res["faults"] = rt.refresh.faults
samples, lost = app.telemetry()
res["telemetry"] = len(samples) + lost
app.stop()
print(json.dumps(res))
"""


@pytest.mark.parametrize("fast", [True, False], ids=["viper", "python"])
def test_refresh_allocates_nothing(fast):
    r = mpy.run_json(HEAP % {"fast": fast}, timeout=120)
    assert r["control"] == "MemoryError"          # the lock is real
    assert r["refresh"] == "ok" and r["n"] == 12499
    assert r["faults"] == 0
    # telemetry written inside the lock at 125 Hz (every 66th refresh)
    assert r["telemetry"] == 12499 // 66


def test_start_with_bad_scene_changes_nothing():
    code = r"""
import json
import texel.app as app
import texel.wire as wire
try:
    app.start("virtual", {"regions": [{"start_mm": 0, "end_mm": 10, "texture": {"kind": "nope"}}]})
    r = "started"
except ValueError as e:
    r = str(e)
print(json.dumps({"err": r, "running": app.status()["running"]}))
"""
    r = mpy.run_json(code)
    assert r["err"].startswith("regions[0].texture.kind:")
    assert r["running"] is False


def test_unknown_board_is_a_clear_error():
    code = r"""
import json
import texel.app as app
import texel.wire as wire
try:
    app.start("no_such_board")
    r = "started"
except ValueError as e:
    r = str(e)
print(json.dumps(r))
"""
    r = mpy.run_json(code)
    assert "no_such_board" in r and "pico" in r


PICO = r"""
import json, machine
import texel.app as app
import texel.wire as wire
machine.script_adc(26, [32000])                 # finger resting mid-strip
st = app.start("pico")
tim = machine.TIMERS[-1]
res = {"returned": True, "timer": {"freq": tim.args["freq"], "hard": tim.args["hard"],
                                   "mode": tim.args["mode"]},
       "top": machine.pwm_top(0), "cc_before": machine.pwm_cc(16)}
tim.fire(200)                                   # 200 refreshes from the IRQ
rt = app._rt
res["refreshes"] = rt.refresh.count
res["pos"] = rt.refresh.pos
res["cc"] = machine.pwm_cc(16)
res["want"] = rt.law.duty(rt.refresh.scene.amp(rt.refresh.pos))
machine.script_adc(26, [0])                     # finger lifted
tim.fire(10)
res["cc_lifted"] = machine.pwm_cc(16)
app.stop()
res["timer_running"] = tim.running
res["cc_stopped"] = machine.pwm_cc(16)
print(json.dumps(res))
"""


def test_pico_start_runs_in_hard_timer_irq_on_fakes():
    r = mpy.run_json(PICO, extra_path=FAKES, timeout=120)
    assert r["returned"] is True
    assert r["timer"] == {"freq": 8333, "hard": True, "mode": 1}
    assert r["top"] == 3675 and r["cc_before"] == 0          # safe until the first refresh
    assert r["refreshes"] == 200 and r["pos"] > 0
    assert r["cc"] == r["want"] and r["cc"] > 0
    assert r["cc_lifted"] == 0                                # idle amplitude 0
    assert r["timer_running"] is False and r["cc_stopped"] == 0


CPY = r"""
import json
import texel.app as app
import texel.wire as wire
st = app.start("pico_cpy")
loop = app.run_loop(seconds=0.2)
st2 = app.status()
app.stop()
import pwmio
print(json.dumps({"port": st["port"], "top": st["pwm_top"], "hz": st["refresh_hz"], "loop": loop,
                  "refreshes": st2["refreshes"], "status_loop": st2["loop"]}))
"""


def test_circuitpython_paced_loop_reports_its_rate():
    """No timer IRQ on CircuitPython: run_loop() paces the refresh on the
    board's ticks and reports the rate it achieved (here on the recording
    pwmio/analogio fakes; the rate is printed, never asserted)."""
    r = mpy.run_json(CPY, extra_path=FAKES, timeout=120)
    assert r["port"] == "circuitpython" and r["top"] == 3675     # pwmio: cpu // freq - 1
    loop = r["loop"]
    assert loop == r["status_loop"]
    assert loop["refreshes"] == r["refreshes"] > 0
    # never more refreshes than the schedule allows (k is due at k*1e6//hz)
    assert loop["refreshes"] <= r["hz"] * loop["seconds"] + 1
    print("CircuitPython-profile loop on the unix port:", loop)


MODES = r"""
import json
import texel.app as app
import texel.wire as wire
from texel.runtime import boards
b = boards.load("pico")
res = {}
for mode in ("core1_viper", "loop"):
    d = dict(b)
    d["refresh"] = dict(b["refresh"], mode=mode)
    d["name"] = "pico_" + mode
    with open("boards/pico_" + mode + ".json", "w") as f:     # ./boards is searched
        json.dump(d, f)
try:
    app.start("pico_core1_viper")
    res["core1"] = "started"
except ValueError as e:
    res["core1"] = str(e)
import machine
n = len(machine.TIMERS)
st = app.start("pico_loop")
res["loop_mode"] = st["refresh_mode"]
res["timers_started"] = len(machine.TIMERS) - n
loop = app.run_loop(seconds=0.05)
res["loop_refreshes"] = loop["refreshes"]
app.stop()
print(json.dumps(res))
"""


def test_refresh_modes(tmp_path):
    """core1_viper is refused by name (not built yet); 'loop' starts no timer
    and run_loop() drives the refresh (rp2 on the recording fakes)."""
    (tmp_path / "boards").mkdir()
    r = mpy.run_json("import os\nos.chdir(%r)\n" % str(tmp_path) + MODES,
                     extra_path=FAKES, timeout=120)
    assert "core1_viper" in r["core1"] and "not implemented" in r["core1"]
    assert r["loop_mode"] == "loop" and r["timers_started"] == 0
    assert r["loop_refreshes"] > 0


INTERRUPTED_START = r"""
import json, machine
import texel.app as app
import texel.wire as wire
import texel.runtime.scene as scene_mod
machine.script_adc(26, [32000])
build = scene_mod.build
def ctrl_c(*a, **k):
    raise KeyboardInterrupt         # Ctrl-C inside the first build (what a host that gave up sends)
scene_mod.build = ctrl_c
res = {}
try:
    app.start("pico")
    res["raised"] = None
except KeyboardInterrupt:
    res["raised"] = "KeyboardInterrupt"
tim = machine.TIMERS[-1] if machine.TIMERS else None
res["running"] = app.status()["running"]
res["timer_running"] = bool(tim and tim.running)
res["cc"] = machine.pwm_cc(16)
scene_mod.build = build
app.start("pico")
tim = machine.TIMERS[-1]
tim.fire(50)
res["refreshes"] = app.status()["refreshes"]
app.stop()
print(json.dumps(res))
"""


def test_ctrl_c_inside_start_leaves_nothing_half_started():
    """KeyboardInterrupt inside start()'s first build (a Ctrl-C, or the host's
    interrupt after it gave up waiting) on the MicroPython unix port with the
    recording Pico fakes: it propagates, nothing says "running", no tick is
    armed, the carrier is off - and the next start plays. (Before: the
    runtime was left set but its tick never started - status said running
    with 0 refreshes - and the next start ran out of memory.)"""
    r = mpy.run_json(INTERRUPTED_START, extra_path=FAKES, timeout=120)
    assert r["raised"] == "KeyboardInterrupt"
    assert r["running"] is False and r["timer_running"] is False and r["cc"] == 0
    assert r["refreshes"] == 50


TELEMETRY_PACKED = r"""
import json, struct
from texel.runtime.refresh import Refresh, TELEMETRY_SLOTS
WRAP = 0x3FFFFFFF
r = Refresh(None, None, None, None, None, 120)
def fill(head, n):
    # n samples written, the last one numbered head - 1 (mod 2^30), as step() writes them
    for k in range(n):
        h = (head - n + k) & WRAP
        i = h % TELEMETRY_SLOTS
        r.tel_t[i] = (h * 7919) & WRAP
        r.tel_pos[i] = (h %% 19200) - (1 if h %% 5 == 0 else 0) * ((h %% 19200) + 1)
        r.tel_amp[i] = (h * 31) & 0xFFFF
    r.tel_head = head
out = []
# (head, samples written, tail): inside the ring, across its wrap, lapped, empty, and
# across the counters' 2^30 wrap
for head, n, tail in ((100, 100, 0), (300, 300, 250), (300, 300, 40), (1000, 1000, 0),
                      (1000, 1000, 1000), (5, 300, WRAP - 100), (5, 300, WRAP - 600)):
    fill(head, n)
    want, wt, wl = r.telemetry_since(tail)
    t, p, m, cnt, pt, pl = r.telemetry_packed_since(tail)
    got = [(struct.unpack_from("<i", t, 4 * k)[0], struct.unpack_from("<i", p, 4 * k)[0],
            struct.unpack_from("<H", m, 2 * k)[0]) for k in range(cnt)]
    out.append([head, tail, len(want), wl, got == [tuple(x) for x in want], cnt == len(want),
                pt == wt, pl == wl, len(t) == 4 * cnt and len(p) == 4 * cnt and len(m) == 2 * cnt])
print(json.dumps(out))
"""


@pytest.mark.parametrize("runtime", [None, pytest.param("circuitpython", marks=pytest.mark.instruments)])
def test_packed_telemetry_is_the_samples_telemetry_since_gives(runtime):
    """Refresh.telemetry_packed_since (what the host reads, texel.wire.telemetry_b64: the
    ring copied by slicing, at C speed) gives exactly telemetry_since's samples, new
    tail and lost count: inside the ring, across its wrap, lapped (lost counted), empty,
    and across the counters' 2^30 wrap - on the MicroPython unix port, CircuitPython
    and CPython."""
    from texelpad import toolchain
    exe = None
    if runtime:
        exe = toolchain.interpreter(runtime)
        if exe is None:
            pytest.skip("%s not found (../shared/instruments)" % runtime)
    code = TELEMETRY_PACKED.replace("%%", "%")
    rows = mpy.run_json(code, exe=exe)
    ns: dict = {}
    import contextlib
    import io
    import json
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(code, ns)
    assert json.loads(buf.getvalue()) == rows            # CPython: the same
    for head, tail, n, lost, *same in rows:
        assert all(same), (head, tail, n, lost, same)
    assert [(r[2], r[3]) for r in rows] == [(100, 0), (50, 0), (256, 4), (256, 744), (0, 0),
                                            (106, 0), (256, 350)]


def test_a_push_answers_before_any_collection():
    """Issue 32 item 4: the board's answer to a push comes before any
    gc.collect. app.push leaves the old scene's collection due and reports no
    heap figure (gc.mem_free walks the whole allocation table: 9 ms on an
    RP2040); texel.wire.reply prints the answer as one line and only then
    collects (app.tidy); status() collects and measures as before."""
    code = r"""
import gc, json
import texel.app as app
import texel.wire as wire
app.start("virtual")
seen = []
class Gc:                       # app's gc, recording (the gc module itself is read-only)
    def collect(self):
        seen.append("collect")
        gc.collect()
    def __getattr__(self, name):
        return getattr(gc, name)
app.gc = Gc()
st = app.push(app.full_screen({"kind": "constant", "level": 0.5}))
seen.append("returned")
due = app._rt.collect_due
wire.reply("push", json.dumps(app.full_screen({"kind": "bump", "width_mm": 8})))
seen.append("after reply")
app.gc = gc
st2 = app.status()
print(json.dumps({"seen": seen, "due": due, "free": st["mem_free"],
                  "due_after": app._rt.collect_due, "free2": st2["mem_free"]}))
"""
    out = mpy.run(code).strip().splitlines()
    r = json.loads(out[-1])
    answer = out[-2]
    assert answer.startswith("('ok', {") and "'mem_free': None" in answer
    # push itself collected nothing; the reply's collection came after its line
    assert r["seen"] == ["returned", "collect", "after reply"]
    assert r["due"] is True and r["free"] is None and r["due_after"] is False
    assert isinstance(r["free2"], int) and r["free2"] > 0
